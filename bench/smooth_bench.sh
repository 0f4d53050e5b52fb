#!/usr/bin/env bash
# The smoothing's cost and gain on the cortex (issue 29, item 4): for each
# surface level and each number of rounds, the mesh's least J_ENS, the
# median wall time of REPEAT runs (dry runs, no output), the smoothing's own
# seconds and nodes moved (from --json), and whether `mixoct check
# --surface` passes on the written mesh. Ratios against --smooth 0; nothing
# is asserted.
#   bench/smooth_bench.sh [build/mixoct] [surface.off]
#   LEVELS="6 7 8 9" ROUNDS="0 1 3" REPEAT=3 THREADS=2 (the defaults)
set -u
MIXOCT=${1:-build/mixoct}
SURF=${2:-$(dirname "$0")/../../shared/data/surfaces/cortex.off}
LEVELS=${LEVELS:-6 7 8 9}
ROUNDS=${ROUNDS:-0 1 3}
REPEAT=${REPEAT:-3}
THREADS=${THREADS:-2}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
[ -r "$SURF" ] || { echo "no surface $SURF" >&2; exit 2; }

field() { # field FILE EXPR: a value of the last JSON line
  python3 -c "import json,sys; d=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1]); print($2)" "$1"
}

printf '%-3s %-6s %10s %9s %9s %9s %8s %8s %9s %s\n' \
  "-s" "smooth" "J_ENS min" "gain" "wall s" "ratio" "smooth s" "moved" "invalid" "check --surface"
for s in $LEVELS; do
  base_t="" base_q=""
  for r in $ROUNDS; do
    times=()
    for ((k = 0; k < REPEAT; k++)); do
      /usr/bin/time -f %e -o "$T/time" "$MIXOCT" -i "$SURF" -s "$s" --smooth "$r" \
        --threads "$THREADS" --json >"$T/run.json" 2>/dev/null
      times+=("$(cat "$T/time")")
    done
    med=$(printf '%s\n' "${times[@]}" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
    q=$(field "$T/run.json" "d['jens_min']")
    inv=$(field "$T/run.json" "d['invalid']")
    st=$(field "$T/run.json" "d['boundary']['smoothing']['seconds']")
    mv=$(field "$T/run.json" "d['boundary']['smoothing']['moved']")
    "$MIXOCT" -i "$SURF" -s "$s" --smooth "$r" --threads "$THREADS" -o "$T/m.vtu" --quiet \
      >/dev/null 2>&1
    if "$MIXOCT" check "$T/m.vtu" --surface "$SURF" --quiet >"$T/check" 2>&1; then chk=OK
    else chk="FAIL ($(tail -1 "$T/check"))"; fi
    [ -z "$base_t" ] && base_t=$med base_q=$q
    printf '%-3s %-6s %10.6f %+9.6f %9.2f %9.2f %8.2f %8s %9s %s\n' "$s" "$r" "$q" \
      "$(python3 -c "print($q - $base_q)")" "$med" "$(python3 -c "print($med / $base_t)")" \
      "$st" "$mv" "$inv" "$chk"
  done
done
