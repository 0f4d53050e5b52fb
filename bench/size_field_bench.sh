#!/usr/bin/env bash
# Size fields on the cortex (issue 27's target): a field from the surface's
# curvature and thickness against -s 8, the boundary accuracy of each
# (mixoct check --surface: the volume error and the distances between the
# mesh boundary and the input surface, both ways, max and mean) and its
# elements, time and memory.
#
#   PATH=/usr/bin:$PATH bench/size_field_bench.sh MIXOCT [CONFIG ...]
#
# Each CONFIG is one run's flags in quotes (default: the list below). One
# line per run; the element ratio against -s 8 (the target: at most 1/3 with
# the same accuracy).
set -u
M=${1:?usage: size_field_bench.sh MIXOCT [CONFIG ...]}
shift
HERE=$(cd "$(dirname "$0")" && pwd)
D=$(cd "${MIXOCT_DATA:-$HERE/../../shared/data}" && pwd)
C=$D/surfaces/cortex.off
[ -f "$C" ] || { echo "no $C"; exit 77; }
T=$(mktemp -d) || exit 1
trap 'rm -rf "$T"' EXIT
if [ $# -eq 0 ]; then
  set -- "-s 8" "-s 7" "-s 5 --curvature 10 --thickness 2" "-s 6 --curvature 5 --thickness 2" \
    "-s 5 --curvature 3 --size-min 0.66 --thickness 2" "-s 5 --curvature 1.5 --size-min 0.66 --thickness 2"
fi
printf '%-52s %9s %9s %7s %6s %10s %s\n' flags elements ratio wall_s mem_mb vol_err "boundary <-> surface distances over the diagonal (check --surface: mesh->surface, surface->mesh)"
ref=
for cfg in "$@"; do
  # shellcheck disable=SC2086
  /usr/bin/time -f '%e %M' -o "$T/time" "$M" -i "$C" $cfg -o "$T/m.vtu" --json >"$T/run.json" 2>"$T/err" ||
    { echo "$cfg: exit $? $(head -1 "$T/err")"; continue; }
  "$M" check "$T/m.vtu" --surface "$C" --json >"$T/check.json" 2>/dev/null
  python3 - "$T/run.json" "$T/check.json" "$T/time" "$cfg" "${ref:-0}" <<'PY' >"$T/line"
import json, sys
run = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
chk = json.loads(open(sys.argv[2]).read().strip().splitlines()[-1])
wall, mem = open(sys.argv[3]).read().split()[-2:]
ref = float(sys.argv[5]) or run["elements"]
names = (("hausdorff_mesh_to_surface_max", "m2s_max"), ("hausdorff_mesh_to_surface_mean", "m2s_mean"),
         ("hausdorff_surface_to_mesh_max", "s2m_max"), ("hausdorff_surface_to_mesh_mean", "s2m_mean"))
d = " ".join("%s=%.3g" % (short, chk[k]) for k, short in names if k in chk)
print("%-52s %9d %9.3f %7.2f %6.0f %10.2e %s" % (sys.argv[4], run["elements"],
      run["elements"] / ref, float(wall), int(mem) / 1024, chk.get("volume_error", float("nan")), d))
PY
  cat "$T/line"
  [ -n "$ref" ] || ref=$(python3 -c "import json,sys; print(json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])['elements'])" "$T/run.json")
done
