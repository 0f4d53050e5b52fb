#!/usr/bin/env bash
# What the files a solver can use directly cost (issue 11): the cortex at a
# level, written as binary .vtu and binary .msh, by a baseline mixoct (an
# older build, e.g. without tagged boundaries and grouped blocks) and by the
# current one, in the same run, alternating, REPEAT times each; the write
# phase seconds from --json (phases.write), their medians and the ratio
# current / baseline; then each format's write speed (file bytes /
# phases.write, MB/s) against a plain sequential write of as many bytes to
# the same directory (dd, 8 MiB blocks, to a new file and fsync'ed, as the
# writers' files are: what the disk and page cache give), as the ratio
# writer / plain; then meshio reading the current .vtu (blocks, seconds).
# phases.write also holds the preparation of the view (boundary faces,
# bodies, written order), so the ratio is a lower bound for the writer.
# Then, per build, .msh over .vtu (write medians), and one run writing
# both and the boundary (-o .vtu -o .msh --boundary .vtu): a build that
# makes the view once per mesh (issue 31) makes it once for the three
# files, an older one three times.
#
#   bench/write_bench.sh BASELINE_MIXOCT MIXOCT [LEVEL] [REPEAT] [THREADS]
#
# LEVEL defaults to 9, REPEAT to 3, THREADS (--threads) to 2. Needs ../shared/data (or MIXOCT_DATA)
# and, for the meshio line, /usr/bin/python3 with meshio (python3-meshio).
# Files go to a temporary directory, removed at the end.
set -u
export LC_ALL=C
OLD=${1:?usage: write_bench.sh BASELINE_MIXOCT MIXOCT [LEVEL] [REPEAT]}
NEW=${2:?usage: write_bench.sh BASELINE_MIXOCT MIXOCT [LEVEL] [REPEAT]}
LEVEL=${3:-9}
REPEAT=${4:-3}
THREADS=${5:-2}
here=$(cd "$(dirname "$0")" && pwd)
DATA=${MIXOCT_DATA:-$here/../../shared/data}
SURF=$DATA/surfaces/cortex.off
[ -f "$SURF" ] || { echo "write_bench: $SURF not found (set MIXOCT_DATA)"; exit 2; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

# one run: prints "total write" seconds from the JSON line. The file of
# the run before is removed first: replacing it would free its blocks
# inside the write phase (ext4: some 40 ms for 260 MB), a cost of the
# bench's reuse of one name, not of writing.
run() { # binary, output file
  rm -f "$2"
  "$1" -i "$SURF" -s "$LEVEL" --threads "$THREADS" -o "$2" --json 2>/dev/null | tail -1 |
    python3 -c 'import json,sys; d=json.loads(sys.stdin.read()); print(d["total_s"], d["phases"]["write"], d["elements"])'
}
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
# a plain write of BYTES (rounded up to 8 MiB blocks) to a new file in $T,
# fsync'ed: prints "seconds bytes"
plain() {
  local n=$(( ($1 + 8388607) / 8388608 ))
  rm -f "$T/plain"
  local t0 t1
  t0=$(date +%s.%N)
  dd if=/dev/zero of="$T/plain" bs=8M count="$n" conv=fsync status=none
  t1=$(date +%s.%N)
  rm -f "$T/plain"
  echo "$(awk -v a="$t0" -v b="$t1" 'BEGIN{print b - a}') $(( n * 8388608 ))"
}

echo "# cortex -s $LEVEL, $THREADS threads, $REPEAT runs each, alternating; seconds (median)"
for fmt in vtu msh; do
  : >"$T/old_$fmt"; : >"$T/new_$fmt"; : >"$T/plain_$fmt"
  for _ in $(seq 1 "$REPEAT"); do
    run "$OLD" "$T/old.$fmt" >>"$T/old_$fmt"
    run "$NEW" "$T/new.$fmt" >>"$T/new_$fmt"
    plain "$(stat -c %s "$T/new.$fmt")" >>"$T/plain_$fmt"
  done
  ow=$(awk '{print $2}' "$T/old_$fmt" | median); nw=$(awk '{print $2}' "$T/new_$fmt" | median)
  eval "ow_$fmt=$ow nw_$fmt=$nw"
  ot=$(awk '{print $1}' "$T/old_$fmt" | median); nt=$(awk '{print $1}' "$T/new_$fmt" | median)
  osz=$(stat -c %s "$T/old.$fmt"); nsz=$(stat -c %s "$T/new.$fmt")
  printf '%-4s write: baseline %.3f s, current %.3f s (x%.2f); run: %.3f s -> %.3f s (x%.2f); file %.1f MB -> %.1f MB\n' \
    "$fmt" "$ow" "$nw" "$(awk -v a="$nw" -v b="$ow" 'BEGIN{print a/b}')" "$ot" "$nt" \
    "$(awk -v a="$nt" -v b="$ot" 'BEGIN{print a/b}')" "$(awk -v s="$osz" 'BEGIN{print s/1e6}')" \
    "$(awk -v s="$nsz" 'BEGIN{print s/1e6}')"
  # speeds: file bytes / write seconds of each run, medians
  osp=$(awk -v s="$osz" '{print ($2 > 0 ? s / $2 / 1e6 : 0)}' "$T/old_$fmt" | median)
  nsp=$(awk -v s="$nsz" '{print ($2 > 0 ? s / $2 / 1e6 : 0)}' "$T/new_$fmt" | median)
  psp=$(awk '{print ($1 > 0 ? $2 / $1 / 1e6 : 0)}' "$T/plain_$fmt" | median)
  ps=$(awk '{print $1}' "$T/plain_$fmt" | median)
  printf '%-4s speed: baseline %.0f MB/s, current %.0f MB/s; plain write %.0f MB/s (%.3f s); writer/plain: baseline %.2f, current %.2f\n' \
    "$fmt" "$osp" "$nsp" "$psp" "$ps" "$(awk -v a="$osp" -v b="$psp" 'BEGIN{print (b > 0 ? a / b : 0)}')" \
    "$(awk -v a="$nsp" -v b="$psp" 'BEGIN{print (b > 0 ? a / b : 0)}')"
done
printf 'msh/vtu write: baseline %.2f, current %.2f\n' \
  "$(awk -v a="$ow_msh" -v b="$ow_vtu" 'BEGIN{print a/b}')" "$(awk -v a="$nw_msh" -v b="$nw_vtu" 'BEGIN{print a/b}')"
# the three files of one run
both() { # binary, prefix
  rm -f "$2.vtu" "$2.msh" "$2_b.vtu"
  "$1" -i "$SURF" -s "$LEVEL" --threads "$THREADS" -o "$2.vtu" -o "$2.msh" --boundary "$2_b.vtu" \
    --json 2>/dev/null | tail -1 |
    python3 -c 'import json,sys; d=json.loads(sys.stdin.read()); print(d["total_s"], d["phases"]["write"])'
}
: >"$T/old_both"; : >"$T/new_both"
for _ in $(seq 1 "$REPEAT"); do
  both "$OLD" "$T/ob" >>"$T/old_both"
  both "$NEW" "$T/nb" >>"$T/new_both"
done
ow=$(awk '{print $2}' "$T/old_both" | median); nw=$(awk '{print $2}' "$T/new_both" | median)
printf 'vtu+msh+boundary write: baseline %.3f s, current %.3f s (x%.2f)\n' "$ow" "$nw" \
  "$(awk -v a="$nw" -v b="$ow" 'BEGIN{print a/b}')"
for f in .vtu .msh _b.vtu; do cmp -s "$T/ob$f" "$T/nb$f" || echo "note: ob$f and nb$f differ"; done
if /usr/bin/python3 -c 'import meshio' 2>/dev/null; then
  for who in old new; do
    /usr/bin/python3 - "$T/$who.vtu" "$who" <<'PY'
import sys, time, meshio
t = time.perf_counter(); m = meshio.read(sys.argv[1]); dt = time.perf_counter() - t
print("meshio %-8s .vtu: %d cells in %d blocks, read in %.2f s" % (
    "baseline" if sys.argv[2] == "old" else "current", sum(len(c.data) for c in m.cells), len(m.cells), dt))
PY
  done
else
  echo "meshio: not installed (python3-meshio)"
fi
