#!/usr/bin/env bash
# What the input and file checks cost (issue 23): a baseline mixoct (an
# older build) against the current one, in the same run, alternating, REPEAT
# times each, medians and the ratio current / baseline of
#   - the cortex at LEVEL written as .vtu: total seconds and the read phase
#     (phases.read, from --json), and whether the two .vtu are the same bytes;
#   - the reading of a surface of quadrilaterals (a 200 x 100 torus of quads,
#     40,000 triangles after the split: every face goes through the polygon
#     splitter), as phases.read of a --stage octree run at -s 3;
#   - the output identity check: a run with 16 outputs in one directory
#     (dry: --stage octree at -s 2), total seconds.
#
#   bench/input_bench.sh BASELINE_MIXOCT MIXOCT [LEVEL] [REPEAT]
#
# LEVEL defaults to 8, REPEAT to 5. Needs ../shared/data (or MIXOCT_DATA) and
# python3. Files go to a temporary directory, removed at the end.
set -u
export LC_ALL=C
OLD=${1:?usage: input_bench.sh BASELINE_MIXOCT MIXOCT [LEVEL] [REPEAT]}
NEW=${2:?usage: input_bench.sh BASELINE_MIXOCT MIXOCT [LEVEL] [REPEAT]}
LEVEL=${3:-8}
REPEAT=${4:-5}
here=$(cd "$(dirname "$0")" && pwd)
DATA=${MIXOCT_DATA:-$here/../../shared/data}
SURF=$DATA/surfaces/cortex.off
[ -f "$SURF" ] || { echo "input_bench: $SURF not found (set MIXOCT_DATA)"; exit 2; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

python3 - "$T/quads.off" <<'PY'
import math, sys
nu, nv, R, r = 200, 100, 1.0, 0.35
with open(sys.argv[1], "w") as f:
    f.write("OFF\n%d %d 0\n" % (nu * nv, nu * nv))
    for i in range(nu):
        for j in range(nv):
            u, v = 2 * math.pi * i / nu, 2 * math.pi * j / nv
            f.write("%.9f %.9f %.9f\n" % ((R + r * math.cos(v)) * math.cos(u),
                                          (R + r * math.cos(v)) * math.sin(u), r * math.sin(v)))
    for i in range(nu):
        for j in range(nv):
            a, b = i * nv + j, ((i + 1) % nu) * nv + j
            c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
            f.write("4 %d %d %d %d\n" % (a, b, c, d))
PY

field() { # json file, key path
  python3 -c 'import json,sys
j=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
for k in sys.argv[2].split("."): j=j[k]
print(j)' "$1" "$2"
}
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
now() { date +%s.%N; }

: >"$T/old_total"; : >"$T/new_total"; : >"$T/old_read"; : >"$T/new_read"
: >"$T/old_quads"; : >"$T/new_quads"; : >"$T/old_outs"; : >"$T/new_outs"
outs=()
for k in $(seq 1 16); do outs+=(-o "$T/o$k.vtu"); done
for r in $(seq 1 "$REPEAT"); do
  for who in old new; do
    bin=$OLD; [ "$who" = new ] && bin=$NEW
    "$bin" -i "$SURF" -s "$LEVEL" -o "$T/$who.vtu" --json --quiet >"$T/j" 2>/dev/null
    field "$T/j" total_s >>"$T/${who}_total"
    field "$T/j" phases.read >>"$T/${who}_read"
    "$bin" -i "$T/quads.off" -s 3 --stage octree --json --quiet >"$T/j" 2>/dev/null
    field "$T/j" phases.read >>"$T/${who}_quads"
    t0=$(now)
    "$bin" -i "$SURF" -s 2 --stage octree "${outs[@]}" --quiet >/dev/null 2>&1
    echo "$(now) - $t0" | bc >>"$T/${who}_outs"
  done
done
line() { # label, file stem
  local o n
  o=$(median <"$T/old_$2"); n=$(median <"$T/new_$2")
  printf '%-44s %10.4f %10.4f %8.2f\n' "$1" "$o" "$n" "$(echo "$n / $o" | bc -l)"
}
echo "input_bench: medians of $REPEAT alternated runs; $(nproc) cores"
printf '%-44s %10s %10s %8s\n' "" baseline current ratio
line "cortex -s $LEVEL -o .vtu: total (s)" total
line "cortex -s $LEVEL: read phase (s)" read
line "200x100 quad torus: read phase (s)" quads
line "16 outputs, -s 2 octree: total (s)" outs
if cmp -s "$T/old.vtu" "$T/new.vtu"; then echo "cortex -s $LEVEL .vtu: the same bytes"
else echo "cortex -s $LEVEL .vtu: the bytes differ"; fi
