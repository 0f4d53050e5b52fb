#!/usr/bin/env bash
# The memory estimate against the measured peak, level by level:
#
#   bench/memory_sweep.sh MIXOCT [SURFACE] [LEVELS]
#
# For each surface level L of LEVELS (default "4 5 6 7 8 9 10"), one run
#   MIXOCT -i SURFACE -s L -o TMP.vtu --json
# (SURFACE default: the cortex of ../shared/data) and one line: level,
# leaves, elements, the estimate made before meshing (memory_estimate_mb),
# the one re-made on the octree's leaves (memory_estimate_prior_mb is the
# first; see README "Memory"), the peak resident memory, and estimate/peak.
# The issue-12 promise: estimate/peak within [0.85, 1.15] at every level.
# Last line: one JSON object with the rows.
set -eu
mixoct=${1:?usage: memory_sweep.sh MIXOCT [SURFACE] [LEVELS]}
here=$(cd "$(dirname "$0")" && pwd)
surface=${2:-$here/../../shared/data/surfaces/cortex.off}
levels=${3:-4 5 6 7 8 9 10}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-6s %10s %11s %12s %12s %10s %9s\n' level leaves elements est_prior_mb est_mb peak_mb est/peak
rows=""
for L in $levels; do
  "$mixoct" -i "$surface" -s "$L" -o "$tmp/m.vtu" --json --quiet >"$tmp/out.txt"
  row=$(tail -1 "$tmp/out.txt" | python3 -c '
import json, sys
d = json.load(sys.stdin)
est = d.get("memory_estimate_mb", 0.0)
prior = d.get("memory_estimate_prior_mb", est)
peak = d["peak_rss_mb"]
print(json.dumps({"level": int(sys.argv[1]), "leaves": d["leaves"], "elements": d["elements"],
                  "estimate_prior_mb": prior, "estimate_mb": est, "peak_mb": peak,
                  "ratio": round(est / peak, 3) if peak else None}))' "$L")
  python3 -c '
import json, sys
r = json.loads(sys.argv[1])
print("%-6d %10d %11d %12.0f %12.0f %10.0f %9.3f" % (r["level"], r["leaves"], r["elements"],
      r["estimate_prior_mb"], r["estimate_mb"], r["peak_mb"], r["ratio"]))' "$row"
  rows="$rows${rows:+,}$row"
  rm -f "$tmp/m.vtu"
done
echo "{\"surface\": \"$(basename "$surface")\", \"rows\": [$rows]}"
