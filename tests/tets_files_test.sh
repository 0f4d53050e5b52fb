#!/bin/bash
# --tets end to end (issue 30, item 2): the written files of a tetrahedral
# mesh, judged by `mixoct check` (an independent reader and checker).
#  - two inputs, a sphere and a copy scaled 0.85 inside it (a thin layer:
#    leaves meet both), at -s 4 and 5, mixed and --tets, as .msh, .mesh
#    and .vtu: no defect; only tetrahedra; per boundary tag (.msh, .mesh), the tetrahedral mesh's
#    triangles = the mixed mesh's triangles + 2 x its quadrangles (each
#    quadrilateral cut in two, its triangles tagged as it was); the same
#    volume (the quadrilaterals' cut changes it by the warp of the boundary
#    quadrilaterals only: 1e-3 relative);
#  - .msh, .vtu, .getfem and the restart file the same bytes for 1 and 2
#    threads;
#  - a restart file written with --tets, refined by a list of tetrahedra
#    (-c, -l): exit 0, only tetrahedra; without --tets it is refused
#    (exit 2) saying so.
#
#   bash tests/tets_files_test.sh path/to/mixoct
set -u
MIXOCT=${1:?usage: tets_files_test.sh path/to/mixoct}
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
T=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_tets.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
pass=0 fail=0
ok() { pass=$((pass + 1)); echo "ok   $1"; }
bad() { fail=$((fail + 1)); echo "FAIL $1"; }

"$PY" "$HERE/make_surfaces.py" "$T" >/dev/null || { echo "FAIL make_surfaces.py"; exit 1; }
"$PY" - "$T/sphere.off" "$T/inner.off" <<'EOF' || { echo "FAIL inner sphere"; exit 1; }
import sys
lines = open(sys.argv[1]).read().split("\n")
nv, nf, _ = map(int, lines[1].split())
v = [list(map(float, l.split())) for l in lines[2:2 + nv]]
c = [sum(p[a] for p in v) / nv for a in range(3)]
with open(sys.argv[2], "w") as f:
    f.write("OFF\n%d %d 0\n" % (nv, nf))
    for p in v:
        f.write("%.17g %.17g %.17g\n" % tuple(c[a] + 0.85 * (p[a] - c[a]) for a in range(3)))
    f.write("\n".join(lines[2 + nv:2 + nv + nf]) + "\n")
EOF

# per-tag counts and the volume of a checked file: "elements tets defects volume tag:tri:quad ..."
summary() {
  "$MIXOCT" check "$1" --json 2>/dev/null | tail -1 | "$PY" -c '
import json, sys
j = json.loads(sys.stdin.read())
print(j["elements"], j["by_type"]["tet"], j["defects"], repr(j["volume"]),
      " ".join("%d:%d:%d" % (t["tag"], t["triangles"], t["quads"]) for t in j["boundary_tags"]))'
}

for s in 4 5; do
  for ext in msh mesh vtu; do
    "$MIXOCT" -i "$T/sphere.off" -i "$T/inner.off" -s $s -o "$T/m$s.$ext" --quiet || bad "-s $s mixed: exit $?"
    "$MIXOCT" -i "$T/sphere.off" -i "$T/inner.off" -s $s --tets -o "$T/t$s.$ext" --quiet || bad "-s $s --tets: exit $?"
    read -r me mt md mv mtags <<<"$(summary "$T/m$s.$ext")"
    read -r te tt td tv ttags <<<"$(summary "$T/t$s.$ext")"
    [ "$td" = 0 ] && [ "$te" = "$tt" ] && [ "$te" -gt "$me" ] &&
      ok "-s $s .$ext: $me mixed elements -> $te tetrahedra, no defect" ||
      bad "-s $s .$ext: tets $te elements, $tt tetrahedra, $td defects (mixed $me)"
    want=$(for x in $mtags; do IFS=: read -r tag tri quad <<<"$x"; echo -n "$tag:$((tri + 2 * quad)):0 "; done)
    if [ $ext != vtu ]; then # .vtu: tags per node only (surface_tag)
      [ -n "$mtags" ] && [ "$want" = "$ttags " ] && ok "-s $s .$ext: boundary tags $mtags -> $ttags" ||
        bad "-s $s .$ext: boundary tags $ttags, expected $want (mixed $mtags)"
    fi
    "$PY" -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(abs(a - b) > 1e-3 * abs(a))" "$mv" "$tv" &&
      ok "-s $s .$ext: volume $mv -> $tv" || bad "-s $s .$ext: volume $mv -> $tv"
  done
done

for n in 1 2; do
  "$MIXOCT" -i "$T/sphere.off" -i "$T/inner.off" -s 5 --tets --threads $n -o "$T/j$n.msh" \
    -o "$T/j$n.vtu" -o "$T/j$n.getfem" --restart "$T/j$n.octb" --quiet || bad "--threads $n: exit $?"
done
same=1
for ext in msh vtu getfem octb; do cmp -s "$T/j1.$ext" "$T/j2.$ext" || { same=0; bad ".$ext differs for 1 and 2 threads"; }; done
[ $same = 1 ] && ok ".msh .vtu .getfem .octb: the same bytes for 1 and 2 threads"

printf '0\n7\n' >"$T/list.txt"
"$MIXOCT" -i "$T/sphere.off" -i "$T/inner.off" -c "$T/j1.octb" -l "$T/list.txt" --tets \
  -o "$T/r.vtu" --quiet && read -r re rt rd rv rtags <<<"$(summary "$T/r.vtu")" &&
  [ "$re" = "$rt" ] && [ "$rd" = 0 ] && ok "refined from the restart file by tetrahedra: $re tetrahedra" ||
  bad "refined from the restart file by tetrahedra"
"$MIXOCT" -i "$T/sphere.off" -i "$T/inner.off" -c "$T/j1.octb" -l "$T/list.txt" \
  -o "$T/r2.vtu" --quiet 2>"$T/err"
rc=$?
[ $rc = 2 ] && grep -q -- "--tets" "$T/err" && ok "without --tets: exit 2, saying so" ||
  bad "without --tets: exit $rc: $(cat "$T/err")"

echo "$pass passed, $fail failed"
[ $fail = 0 ]
