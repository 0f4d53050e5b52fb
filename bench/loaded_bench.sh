#!/usr/bin/env bash
# A bench script for loaded machines (issue 24, item 2): 1 thread against 2
# threads while another job holds one of the cores, as on a shared node, a
# login node or a CI runner, and the same runs on the machine as it is.
#
#   bench/loaded_bench.sh [options] [MIXOCT]
#
# MIXOCT defaults to build/mixoct of this tree; mesher2d and mesher_roi are
# the links beside it. The runs (the data from ../shared/data, or MIXOCT_DATA;
# every output to a temporary directory, removed at the end):
#   a_s12   mesher2d -p polylines/a.poly -s 12 -u TMP/s12 -v
#           (the letter A, surface level 12; ASCII VTK and the restart file)
#   remesh  mesher_roi -o surfaces/cortex.off -c remesh/c5.oct
#           -l remesh/list.txt -u TMP/r -v  (Table 1 re-mesh of the 2021 paper)
#   c_s7    mixoct -i surfaces/cortex.off -s 7 -o TMP/x.vtu
#   c_s9    the same at -s 9 (15-20 s a run on 2 cores; --quick skips it)
# each with --threads 1 and --threads 2, alternately, RUNS times each. For
# each run and repetition the "loaded" condition starts a busy process
# (`sh -c 'while :; do :; done'`, not pinned: one core's worth of load, as
# another job would take) and stops it after; the "quiet" condition runs
# with no busy process (the machine as it is: other users' load stays).
# Wall seconds by `date +%s%N` around the command. A run that exits with
# anything but 0 stops the script (exit 1) with the command and the end of
# its output; no time is reported for it.
#
# OMP_WAIT_POLICY is not set: the programs choose the passive policy
# themselves when neither it nor GOMP_SPINCOUNT is set (README, Threads). An
# OMP_WAIT_POLICY or GOMP_SPINCOUNT in the caller's environment is removed
# for the default runs, so they measure the programs' own choice. --active
# adds runs with OMP_WAIT_POLICY=active (libgomp's spinning), alternated
# with the default ones, to show what spinning costs.
#
# Printed: per run and condition the median, min and max wall seconds with 1
# and 2 threads, 2 threads / 1 thread, and where REFERENCE.md's "Side by side
# on 2026-12-04" table has the published program on the same run (a_s12:
# 1.87 s, remesh: 0.79 s, measured on a machine at load 2-4, so compare the
# loaded rows) the published time and ours / published; then loaded / quiet
# and active / default. Its cortex RL7 and RL9 figures are for ASCII VTK and
# the restart file, not this .vtu run: no ratio there. Last, one JSON line
# per run (lines starting with '{').
#
# Options (and the environment variables that do the same):
#   -n, --runs N    runs per thread count and condition (RUNS, default 5)
#   --quick         skip c_s9 (QUICK=1)
#   --no-quiet      only the loaded condition (NO_QUIET=1)
#   --active        also OMP_WAIT_POLICY=active (ACTIVE=1)
#   --only LIST     comma-separated runs among a_s12,remesh,c_s7,c_s9
#   -h, --help      this text
# Needs python3 (the summary). With 3 runs, both conditions and -s 9 it
# took 5 minutes on 2 cores (5 runs: about 8); --active adds as much again
# or more (spinning threads at -s 9 under load: minutes a run). Ctrl-C
# stops the busy process and removes the temporary directory.
set -u
export LC_ALL=C
here=$(cd "$(dirname "$0")" && pwd)

usage() { sed -n '2,/^set -u$/p' "$0" | sed -e '$d' -e 's/^# \{0,1\}//'; }

runs=${RUNS:-5}
quick=${QUICK:-0}
no_quiet=${NO_QUIET:-0}
active=${ACTIVE:-0}
only=""
mixoct=""
while [ $# -gt 0 ]; do
  case "$1" in
    -n | --runs) runs=${2:?loaded_bench: $1 needs a number}; shift ;;
    --runs=*) runs=${1#--runs=} ;;
    --quick) quick=1 ;;
    --no-quiet) no_quiet=1 ;;
    --active) active=1 ;;
    --only) only=${2:?loaded_bench: --only needs a list}; shift ;;
    --only=*) only=${1#--only=} ;;
    -h | --help) usage; exit 0 ;;
    -*) echo "loaded_bench: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) [ -z "$mixoct" ] || { echo "loaded_bench: one MIXOCT only" >&2; exit 2; }
       mixoct=$1 ;;
  esac
  shift
done
case "$runs" in
  '' | *[!0-9]* | 0) echo "loaded_bench: runs must be a positive integer, not '$runs'" >&2; exit 2 ;;
esac
mixoct=${mixoct:-$here/../build/mixoct}
bindir=$(cd "$(dirname "$mixoct")" 2>/dev/null && pwd) ||
  { echo "loaded_bench: no directory for $mixoct" >&2; exit 2; }
for p in mixoct mesher2d mesher_roi; do
  [ -x "$bindir/$p" ] || { echo "loaded_bench: $bindir/$p not found (build first)" >&2; exit 2; }
done
DATA=${MIXOCT_DATA:-$here/../../shared/data}
for f in polylines/a.poly surfaces/cortex.off remesh/c5.oct remesh/list.txt; do
  [ -f "$DATA/$f" ] || { echo "loaded_bench: $DATA/$f not found (set MIXOCT_DATA)" >&2; exit 2; }
done
command -v python3 >/dev/null || { echo "loaded_bench: python3 is needed" >&2; exit 2; }

# the runs: label, published seconds ("" for none), the command as shown;
# set_argv NAME fills argv with the command itself
names=(a_s12 remesh c_s7 c_s9)
declare -A label pub shown
label[a_s12]="letter A, surface RL12"; pub[a_s12]=1.87
shown[a_s12]="mesher2d -p a.poly -s 12 -u <tmp>/s12 -v"
label[remesh]="re-mesh c5.oct+list.txt"; pub[remesh]=0.79
shown[remesh]="mesher_roi -o cortex.off -c c5.oct -l list.txt -u <tmp>/r -v"
label[c_s7]="cortex -s 7, .vtu"; pub[c_s7]=""
shown[c_s7]="mixoct -i cortex.off -s 7 -o <tmp>/x.vtu"
label[c_s9]="cortex -s 9, .vtu"; pub[c_s9]=""
shown[c_s9]="mixoct -i cortex.off -s 9 -o <tmp>/x.vtu"
set_argv() {
  case "$1" in
    a_s12) argv=("$bindir/mesher2d" -p "$DATA/polylines/a.poly" -s 12 -u "$T/s12" -v) ;;
    remesh) argv=("$bindir/mesher_roi" -o "$DATA/surfaces/cortex.off" -c "$DATA/remesh/c5.oct"
              -l "$DATA/remesh/list.txt" -u "$T/r" -v) ;;
    c_s7) argv=("$bindir/mixoct" -i "$DATA/surfaces/cortex.off" -s 7 -o "$T/x.vtu") ;;
    c_s9) argv=("$bindir/mixoct" -i "$DATA/surfaces/cortex.off" -s 9 -o "$T/x.vtu") ;;
  esac
}
if [ -n "$only" ]; then
  for n in ${only//,/ }; do
    [ -n "${label[$n]+x}" ] || { echo "loaded_bench: no run '$n' (a_s12,remesh,c_s7,c_s9)" >&2; exit 2; }
  done
fi
selected=()
for n in "${names[@]}"; do
  if [ -n "$only" ]; then
    case ",$only," in *",$n,"*) ;; *) continue ;; esac
  fi
  [ "$n" = c_s9 ] && [ "$quick" = 1 ] && continue
  selected+=("$n")
done
[ ${#selected[@]} -gt 0 ] || { echo "loaded_bench: no run left to do" >&2; exit 2; }
conds=(loaded); [ "$no_quiet" = 1 ] || conds+=(quiet)
policies=(default); [ "$active" = 1 ] && policies+=(active)

T=$(mktemp -d)
busy=""
stop_busy() {
  if [ -n "$busy" ]; then
    kill "$busy" 2>/dev/null
    wait "$busy" 2>/dev/null
    busy=""
  fi
}
trap 'stop_busy; rm -rf "$T"' EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
start_busy() {
  sh -c 'while :; do :; done' &
  busy=$!
  sleep 0.2 # let the scheduler give it its core before the run starts
}

# one timed run: name, condition, policy, threads; appends a row to $T/times
: >"$T/times"
run() {
  local name=$1 cond=$2 policy=$3 threads=$4 t0 t1 rc=0
  local -a argv
  set_argv "$name"
  if [ "$cond" = loaded ] && ! kill -0 "$busy" 2>/dev/null; then
    echo "loaded_bench: the busy process is gone; stopping" >&2
    exit 1
  fi
  t0=$(date +%s%N)
  if [ "$policy" = active ]; then
    env -u GOMP_SPINCOUNT OMP_WAIT_POLICY=active "${argv[@]}" --threads "$threads" \
      >"$T/log" 2>&1 || rc=$?
  else
    env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "${argv[@]}" --threads "$threads" \
      >"$T/log" 2>&1 || rc=$?
  fi
  t1=$(date +%s%N)
  if [ "$rc" -ne 0 ]; then
    echo "loaded_bench: FAILED (exit $rc; $cond, wait $policy, --threads $threads):" >&2
    echo "  ${argv[*]} --threads $threads" >&2
    tail -5 "$T/log" | sed 's/^/  | /' >&2
    exit 1
  fi
  printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$cond" "$policy" "$threads" "$((t1 - t0))" >>"$T/times"
  rm -f "$T"/s12.* "$T"/r.* "$T"/x.vtu
}

# the policy each mode gets, as the program reports it (--json wait_policy)
policy_of() {
  local -a e=(env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT)
  [ "$1" = active ] && e=(env -u GOMP_SPINCOUNT OMP_WAIT_POLICY=active)
  "${e[@]}" "$bindir/mixoct" --demo -s 1 --threads 1 --json 2>/dev/null | tail -1 |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["wait_policy"])' 2>/dev/null ||
    echo "unknown"
}
report=""
for policy in "${policies[@]}"; do
  got=$(policy_of "$policy")
  if [ "$policy" = active ] && [ "$got" != active ]; then
    echo "loaded_bench: OMP_WAIT_POLICY=active not taken (the program reports '$got')" >&2
    exit 1
  fi
  report="$report${report:+, }$policy = $got"
done

echo "# loaded_bench: ${selected[*]}; $runs runs each with 1 and 2 threads, alternated;" \
  "conditions: ${conds[*]}; wait policy: ${policies[*]}"
echo "# $(nproc) cores; load average at start: $(cut -d' ' -f1-3 /proc/loadavg); $(date -Iseconds)"
echo "# $bindir/mixoct; data $DATA"
echo "# wait policy as reported by mixoct --json: $report"
if [ -n "${OMP_WAIT_POLICY:-}${GOMP_SPINCOUNT:-}" ]; then
  echo "# OMP_WAIT_POLICY/GOMP_SPINCOUNT of the environment removed for the default runs"
fi
for r in $(seq 1 "$runs"); do
  for name in "${selected[@]}"; do
    printf '# repetition %d/%d: %s\n' "$r" "$runs" "$name" >&2
    for cond in "${conds[@]}"; do
      [ "$cond" = loaded ] && start_busy
      for policy in "${policies[@]}"; do
        for threads in 1 2; do
          run "$name" "$cond" "$policy" "$threads"
        done
      done
      stop_busy
    done
  done
done
echo "# load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"

specs=()
for n in "${selected[@]}"; do
  specs+=("$n|${label[$n]}|${pub[$n]}|${shown[$n]}")
done
python3 - "$T/times" "$runs" "${specs[@]}" <<'EOF'
import json, statistics, sys
path, runs, specs = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
rows = [l.rstrip("\n").split("\t") for l in open(path) if l.strip()]
times = {}
for name, cond, policy, threads, ns in rows:
    times.setdefault((name, cond, policy, int(threads)), []).append(int(ns) / 1e9)
conds = [c for c in ("loaded", "quiet") if any(k[1] == c for k in times)]
policies = [p for p in ("default", "active") if any(k[2] == p for k in times)]

def stats(v):
    return {"median": round(statistics.median(v), 4), "min": round(min(v), 4),
            "max": round(max(v), 4), "n": len(v)}

def r4(x):
    return round(x, 4)

def cell(s):
    return "%7.3f [%6.3f-%6.3f]" % (s["median"], s["min"], s["max"])

hdr = "%-24s %-6s %-7s %-23s %-23s %6s %6s %6s %6s" % (
    "run", "load", "wait", "1 thread  [min-max]", "2 threads [min-max]",
    "2t/1t", "pub s", "1t/pub", "2t/pub")
print()
print("wall seconds, %d runs per cell, 1 and 2 threads alternated" % runs)
print(hdr)
print("-" * len(hdr))
lines = []
for spec in specs:
    name, label, pub, cmd = spec.split("|", 3)
    pub = float(pub) if pub else None
    out = {"bench": "loaded_bench", "run": name, "cmd": cmd, "runs": runs,
           "published_s": pub}
    for cond in conds:
        for policy in policies:
            if (name, cond, policy, 1) not in times:
                continue
            s1, s2 = stats(times[(name, cond, policy, 1)]), stats(times[(name, cond, policy, 2)])
            c = {"t1": s1, "t2": s2, "t2_over_t1": r4(s2["median"] / s1["median"])}
            line = "%-24s %-6s %-7s %-23s %-23s %6.2f" % (
                label, cond, policy, cell(s1), cell(s2), c["t2_over_t1"])
            if pub:
                c["t1_over_published"] = r4(s1["median"] / pub)
                c["t2_over_published"] = r4(s2["median"] / pub)
                line += " %6.2f %6.2f %6.2f" % (pub, c["t1_over_published"],
                                                c["t2_over_published"])
            else:
                line += " %6s %6s %6s" % ("-", "-", "-")
            print(line)
            out.setdefault(cond, {})[policy] = c
            label = ""
    def ratio(a, b):
        return {"t1": r4(a["t1"]["median"] / b["t1"]["median"]),
                "t2": r4(a["t2"]["median"] / b["t2"]["median"])}
    for policy in policies:
        if "quiet" in out and policy in out.get("loaded", {}) and policy in out["quiet"]:
            r = ratio(out["loaded"][policy], out["quiet"][policy])
            out.setdefault("loaded_over_quiet", {})[policy] = r
            print("%-24s loaded / quiet (wait %s): 1 thread %.2f, 2 threads %.2f"
                  % ("", policy, r["t1"], r["t2"]))
    if "active" in policies:
        for cond in conds:
            if cond in out and "active" in out[cond]:
                r = ratio(out[cond]["active"], out[cond]["default"])
                out.setdefault("active_over_default", {})[cond] = r
                print("%-24s active / default (%s): 1 thread %.2f, 2 threads %.2f"
                      % ("", cond, r["t1"], r["t2"]))
    lines.append(json.dumps(out))
print()
print("pub s: REFERENCE.md, side by side on 2026-12-04, the published program on a loaded"
      " machine (load 2-4): compare the loaded rows.")
print("2t/1t > 1: two threads slower than one. Ratios are of medians.")
for l in lines:
    print(l)
EOF
