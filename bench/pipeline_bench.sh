#!/usr/bin/env bash
# The targets of issue 12 in one run: the cortex at a level (default 9),
# meshed and written as binary VTU, REPEAT times (default 5) with 2 threads
# and REPEAT times with 1 thread, alternating. Per configuration: the median
# wall, user and sys seconds (/usr/bin/time), sys / user, the peak RSS, the
# median of every phase and boundary step with its spread (max / min over
# the runs), and the speed-up of 2 threads over 1 on the wall time. A
# BASELINE binary (optional) runs alternately with the 2-thread runs, for a
# ratio measured in the same conditions. Last line: one JSON object.
#
#   bench/pipeline_bench.sh MIXOCT [LEVEL] [REPEAT] [BASELINE]
#
# Needs ../shared/data (or MIXOCT_DATA), /usr/bin/time and python3. The
# output file goes to a temporary directory on the same disk as /tmp,
# removed at the end.
set -u
export LC_ALL=C
BIN=${1:?usage: pipeline_bench.sh MIXOCT [LEVEL] [REPEAT] [BASELINE]}
LEVEL=${2:-9}
REPEAT=${3:-5}
BASE=${4:-}
here=$(cd "$(dirname "$0")" && pwd)
DATA=${MIXOCT_DATA:-$here/../../shared/data}
SURF=$DATA/surfaces/cortex.off
[ -f "$SURF" ] || { echo "pipeline_bench: $SURF not found (set MIXOCT_DATA)"; exit 2; }
[ -x /usr/bin/time ] || { echo "pipeline_bench: /usr/bin/time is needed (apt-get install time)"; exit 2; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

# one run: appends one JSON line (the mixoct summary plus wall/user/sys)
run() { # name binary threads
  /usr/bin/time -f '%e %U %S' -o "$T/time" "$2" -i "$SURF" -s "$LEVEL" --threads "$3" \
    -o "$T/out.vtu" --json 2>/dev/null | tail -1 >"$T/json"
  read -r wall user sys <"$T/time"
  python3 - "$1" "$wall" "$user" "$sys" "$T/json" >>"$T/runs" <<'EOF'
import json, sys
name, wall, user, sys_, path = sys.argv[1:6]
try:
    d = json.load(open(path))
except Exception:
    d = {}
d.update({"config": name, "wall": float(wall), "user": float(user), "sys": float(sys_)})
print(json.dumps(d))
EOF
}

: >"$T/runs"
for _ in $(seq 1 "$REPEAT"); do
  run t2 "$BIN" 2
  [ -n "$BASE" ] && run base "$BASE" 2
  run t1 "$BIN" 1
done

python3 - "$T/runs" "$LEVEL" "$REPEAT" <<'EOF'
import json, statistics, sys
runs = [json.loads(l) for l in open(sys.argv[1])]
level, repeat = int(sys.argv[2]), int(sys.argv[3])
out = {"bench": "pipeline", "input": "cortex", "level": level, "repeat": repeat}
def phases(r):
    p = {k: v for k, v in (r.get("phases") or {}).items() if k not in ("read", "restart")}
    for k, v in ((r.get("boundary") or {}).get("seconds") or {}).items():
        p["boundary." + k] = v
    return p
print(f"# cortex -s {level}, binary VTU written, {repeat} runs per configuration, medians")
for cfg in ("t2", "base", "t1"):
    rs = [r for r in runs if r["config"] == cfg]
    if not rs:
        continue
    ok = all(r.get("exit_code") == 0 for r in rs)
    med = lambda k: statistics.median(r[k] for r in rs)
    c = {"runs": len(rs), "all_valid": ok, "wall_s": med("wall"), "user_s": med("user"),
         "sys_s": med("sys"), "peak_rss_mb": max(r.get("peak_rss_mb", 0) for r in rs),
         "nodes": rs[0].get("nodes"), "elements": rs[0].get("elements")}
    c["sys_over_user"] = c["sys_s"] / c["user_s"] if c["user_s"] else None
    names = sorted({k for r in rs for k in phases(r)})
    ph = {}
    for k in names:
        v = [phases(r).get(k, 0.0) for r in rs]
        lo = min(v)
        ph[k] = {"median": statistics.median(v), "spread": (max(v) / lo) if lo > 0 else None}
    c["phases"] = ph
    out[cfg] = c
    print(f"{cfg:5s} wall {c['wall_s']:7.2f} s  user {c['user_s']:7.2f}  sys {c['sys_s']:6.2f}"
          f"  sys/user {c['sys_over_user']:.3f}  peak {c['peak_rss_mb']:7.1f} MB"
          f"  nodes {c['nodes']} elements {c['elements']} valid {ok}")
    for k in names:
        s = ph[k]["spread"]
        print(f"        {k:22s} {ph[k]['median']:7.3f} s  spread {s:.2f}" if s else
              f"        {k:22s} {ph[k]['median']:7.3f} s")
if "t1" in out and "t2" in out:
    out["speedup_2_over_1"] = out["t1"]["wall_s"] / out["t2"]["wall_s"]
    print(f"2 threads over 1: {out['speedup_2_over_1']:.2f}x (wall)")
if "base" in out and "t2" in out:
    out["baseline_over_current"] = out["base"]["wall_s"] / out["t2"]["wall_s"]
    print(f"baseline / current: {out['baseline_over_current']:.2f}x (wall, 2 threads)")
print(json.dumps(out))
EOF
