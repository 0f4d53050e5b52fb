#!/usr/bin/env bash
# The restart file's writing (issue 24): an older build against this one,
# alternated in one run, on the cortex (`mixoct -s LEVEL --restart x.oct`,
# with a binary .vtu beside it as a user would) and on the letter A in 2D
# (`mesher2d -a LEVEL2D -u x`: ASCII VTK and the quadtree restart file).
# Prints each run's restart phase (from --json for mixoct, from the summary's
# time line for mesher2d), the medians, the old/new ratio, and whether the
# two builds wrote the same bytes (cmp of the restart files).
#
#   bench/restart_bench.sh OLD_MIXOCT NEW_MIXOCT [LEVEL=9] [RUNS=3] [LEVEL2D=12]
#
# mesher2d is taken beside each mixoct. The data: ../shared/data next to the
# project, or MIXOCT_DATA.
set -u
OLD=${1:?usage: restart_bench.sh OLD_MIXOCT NEW_MIXOCT [LEVEL] [RUNS] [LEVEL2D]}
NEW=${2:?usage: restart_bench.sh OLD_MIXOCT NEW_MIXOCT [LEVEL] [RUNS] [LEVEL2D]}
LEVEL=${3:-9}
RUNS=${4:-3}
LEVEL2D=${5:-12}
HERE=$(cd "$(dirname "$0")" && pwd)
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
CORTEX=$DATA/surfaces/cortex.off
POLY=$DATA/polylines/a.poly
for f in "$OLD" "$NEW" "$CORTEX" "$POLY"; do
  [ -e "$f" ] || { echo "restart_bench: $f is missing" >&2; exit 1; }
done
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }

# 3D: the restart phase and the total, from --json
run3d() { # binary, tag
  local out
  out=$("$1" -i "$CORTEX" -s "$LEVEL" -o "$T/$2.vtu" --restart "$T/$2.oct" --json 2>"$T/err") || {
    echo "restart_bench: $1 failed: $(tail -3 "$T/err")" >&2; exit 1; }
  echo "$out" | tail -1 | python3 -c 'import json,sys; d=json.load(sys.stdin); print("%.3f %.3f %.0f" % (d["phases"]["restart"], d["total_s"], d["peak_rss_mb"]))'
}
# 2D: the restart figure of the summary's time line
run2d() { # mesher2d, tag
  "$1" -p "$POLY" -a "$LEVEL2D" -u "$T/$2" -v >"$T/$2.txt" 2>&1 || {
    echo "restart_bench: $1 failed: $(tail -3 "$T/$2.txt")" >&2; exit 1; }
  sed -n 's/.* restart \([0-9.]*\).*/\1/p' "$T/$2.txt" | head -1
}

echo "# restart_bench: cortex -s $LEVEL and letter A -a $LEVEL2D, $RUNS runs each, old and new alternated"
echo "# old $OLD"
echo "# new $NEW"
echo "# $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg)"
: >"$T/o3"; : >"$T/n3"; : >"$T/o2"; : >"$T/n2"
for i in $(seq "$RUNS"); do
  read -r r t m < <(run3d "$OLD" old); echo "$r $t $m" >>"$T/o3"
  echo "3d run $i old: restart $r s, total $t s, peak $m MB"
  read -r r t m < <(run3d "$NEW" new); echo "$r $t $m" >>"$T/n3"
  echo "3d run $i new: restart $r s, total $t s, peak $m MB"
  r=$(run2d "$(dirname "$OLD")/mesher2d" old2); echo "$r" >>"$T/o2"; echo "2d run $i old: restart $r s"
  r=$(run2d "$(dirname "$NEW")/mesher2d" new2); echo "$r" >>"$T/n2"; echo "2d run $i new: restart $r s"
done
cmp -s "$T/old.oct" "$T/new.oct" && same3="identical" || same3="DIFFERENT"
cmp -s "$T/old2.oct" "$T/new2.oct" && same2="identical" || same2="DIFFERENT"
o3=$(cut -d' ' -f1 "$T/o3" | median); n3=$(cut -d' ' -f1 "$T/n3" | median)
ot=$(cut -d' ' -f2 "$T/o3" | median); nt=$(cut -d' ' -f2 "$T/n3" | median)
om=$(cut -d' ' -f3 "$T/o3" | median); nm=$(cut -d' ' -f3 "$T/n3" | median)
o2=$(median <"$T/o2"); n2=$(median <"$T/n2")
size3=$(stat -c %s "$T/new.oct"); size2=$(stat -c %s "$T/new2.oct")
echo
printf '%-34s %10s %10s %8s\n' "median of $RUNS" old new old/new
printf '%-34s %10.3f %10.3f %8.2f\n' "cortex -s $LEVEL restart phase (s)" "$o3" "$n3" "$(echo "$o3 / $n3" | bc -l)"
printf '%-34s %10.3f %10.3f %8.2f\n' "cortex -s $LEVEL whole run (s)" "$ot" "$nt" "$(echo "$ot / $nt" | bc -l)"
printf '%-34s %10.0f %10.0f %8.2f\n' "cortex -s $LEVEL peak memory (MB)" "$om" "$nm" "$(echo "$om / $nm" | bc -l)"
printf '%-34s %10.3f %10.3f %8.2f\n' "letter A -a $LEVEL2D restart phase (s)" "$o2" "$n2" "$(echo "$o2 / $n2" | bc -l)"
echo "restart files: 3D $same3 ($((size3 / 1000000)) MB), 2D $same2 ($((size2 / 1000000)) MB)"
echo "{\"bench\": \"restart\", \"level\": $LEVEL, \"runs\": $RUNS, \"old_s\": $o3, \"new_s\": $n3, \"old_total_s\": $ot, \"new_total_s\": $nt, \"old_2d_s\": $o2, \"new_2d_s\": $n2, \"identical_3d\": $([ "$same3" = identical ] && echo true || echo false), \"identical_2d\": $([ "$same2" = identical ] && echo true || echo false)}"
[ "$same3" = identical ] && [ "$same2" = identical ]
