#!/usr/bin/env bash
# The distributed path of issue 14 against the single-process one, on one
# machine:
#
#   bench/p4est_bench.sh MIXOCT [SURFACE] [LEVELS]
#
# SURFACE: default ../shared/data/surfaces/cortex.off; LEVELS: surface
# levels, default "8 9 10". For each level:
#  1. octree: refine + balance of the single-process octree (2 threads,
#     `--stage octree`) against p4est's on 1 and 2 ranks x 1 thread (the
#     slowest rank's refine + balance);
#  2. whole pipeline (octree, mesh, checks; nothing written): 1 process x 1
#     and 2 threads; 1 rank x 1 and 2 threads, 2 ranks x 1 thread: wall
#     seconds (the run's own total), peak memory per rank (max), the halo
#     (patch leaves - own leaves, max), the node records the ranks sent each
#     other (sum) and the largest message, the mesh hash;
#  3. with CHECK=1 (default for levels <= 9), the 2-rank mesh is written as
#     .pvtu and checked by `mixoct check --surface` (conformity across the
#     partition boundary, boundary on the input), and its hash compared with
#     the single-process file's.
# Runs are single (REPEAT=N: median of N for the times). mpirun gets
# --oversubscribe --allow-run-as-root, and --bind-to none with more than one
# thread per rank (Open MPI binds a rank to one core by default, so its
# threads would share it). The last line is one JSON object with
# every row.
set -eu
mixoct=${1:?usage: p4est_bench.sh MIXOCT [SURFACE] [LEVELS]}
here=$(cd "$(dirname "$0")" && pwd)
surf=${2:-$here/../../shared/data/surfaces/cortex.off}
levels=${3:-8 9 10}
repeat=${REPEAT:-1}
mpirun=${MPIRUN:-mpirun}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# python3 reads the last JSON line of a file: get FILE KEY.PATH
get() {
  python3 -c 'import json,sys
j=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
for k in sys.argv[2].split("."): j=j[k]
print(j)' "$1" "$2"
}
median() { tr ' ' '\n' | grep -v '^$' | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

# run OUT RANKS THREADS args...: RANKS 0 = the single-process program
run() {
  local out=$1 ranks=$2 threads=$3
  shift 3
  local times=""
  for _ in $(seq "$repeat"); do
    if [ "$ranks" = 0 ]; then
      OMP_NUM_THREADS=$threads "$mixoct" --threads "$threads" "$@" --json >"$out" 2>"$tmp/err" ||
        { cat "$tmp/err" >&2; return 1; }
    else
      # Open MPI binds each rank to one core by default: threads need room
      local bind=()
      [ "$threads" -gt 1 ] && bind=(--bind-to none)
      OMP_NUM_THREADS=$threads "$mpirun" --oversubscribe --allow-run-as-root "${bind[@]}" -n "$ranks" \
        -x OMP_NUM_THREADS "$mixoct" --threads "$threads" "$@" --p4est --json >"$out" 2>"$tmp/err" ||
        { cat "$tmp/err" >&2; return 1; }
    fi
    times="$times $(get "$out" total_s)"
  done
  echo "$times" | median
}

rows=""
row() { rows="$rows${rows:+, }$1"; }
printf '%-6s %-22s %9s %9s %11s %10s %12s %12s %s\n' level run "wall s" "peak MB" "halo lv" \
  "sent MB" "largest MB" "vs 1x2" hash
for L in $levels; do
  # 1. octree
  run "$tmp/o0.json" 0 2 -i "$surf" -s "$L" --stage octree >/dev/null
  ours=$(python3 -c "import json;j=json.loads(open('$tmp/o0.json').read().strip().splitlines()[-1]);print(j['phases']['refine']+j['phases']['balance'])")
  for r in 1 2; do
    run "$tmp/o$r.json" "$r" 1 -i "$surf" -s "$L" --stage octree >/dev/null
    p4=$(python3 -c "import json;j=json.loads(open('$tmp/o$r.json').read().strip().splitlines()[-1]);print(j['phases']['refine']+j['phases']['balance'])")
    ratio=$(python3 -c "print('%.2f' % ($p4 / $ours))")
    printf '%-6s %-22s %9.3f %9s %11s %10s %12s %12s\n' "$L" "octree p4est ${r}x1" "$p4" - - - - \
      "${ratio}x ours"
    row "{\"level\": $L, \"run\": \"octree\", \"ranks\": $r, \"p4est_refine_balance_s\": $p4, \"ours_refine_balance_s\": $ours}"
  done
  printf '%-6s %-22s %9.3f\n' "$L" "octree ours 1x2" "$ours"
  # 2. whole pipeline
  base=""
  for cfg in "0 1" "0 2" "1 1" "1 2" "2 1"; do
    set -- $cfg
    r=$1 t=$2
    wall=$(run "$tmp/w.json" "$r" "$t" -i "$surf" -s "$L")
    if [ "$r" = 0 ]; then
      name="single 1x$t"
      peak=$(get "$tmp/w.json" peak_rss_mb)
      halo=0 sent=0 big=0 hash=-
      [ "$t" = 2 ] && base=$wall
    else
      name="p4est ${r}x$t"
      peak=$(get "$tmp/w.json" mesh.per_rank.peak_rss_mb | tr -d '[],' | cut -d' ' -f2)
      halo=$(python3 -c "import json;j=json.loads(open('$tmp/w.json').read().strip().splitlines()[-1])['mesh']['per_rank'];print(int(max(j['patch_leaves'])-min(j['leaves'])) if True else 0)")
      sent=$(python3 -c "import json;j=json.loads(open('$tmp/w.json').read().strip().splitlines()[-1]);print('%.2f'%(j['mesh']['exchanged_bytes']/1048576))")
      big=$(python3 -c "import json;j=json.loads(open('$tmp/w.json').read().strip().splitlines()[-1]);print('%.2f'%(j['mesh']['largest_message_bytes']/1048576))")
      hash=$(get "$tmp/w.json" mesh.mesh_hash)
    fi
    vs=$(python3 -c "print('%.2f' % ($wall / ${base:-$wall}))")
    printf '%-6s %-22s %9.3f %9.1f %11s %10s %12s %12s %s\n' "$L" "$name" "$wall" "$peak" "$halo" \
      "$sent" "$big" "${vs}x" "$hash"
    row "{\"level\": $L, \"run\": \"pipeline\", \"ranks\": $r, \"threads\": $t, \"wall_s\": $wall, \"peak_rss_mb\": $peak, \"halo_leaves_max\": $halo, \"sent_mb\": $sent, \"largest_message_mb\": $big, \"hash\": \"$hash\"}"
  done
  # 3. the files checked
  if [ "${CHECK:-$([ "$L" -le 9 ] && echo 1 || echo 0)}" = 1 ]; then
    OMP_NUM_THREADS=2 "$mixoct" -i "$surf" -s "$L" -o "$tmp/s.vtu" --quiet
    hs=$("$mixoct" check "$tmp/s.vtu" --json | python3 -c 'import json,sys;print(json.load(sys.stdin)["mesh_hash"])')
    OMP_NUM_THREADS=1 "$mpirun" --oversubscribe --allow-run-as-root -n 2 "$mixoct" -i "$surf" \
      -s "$L" --p4est -o "$tmp/p.pvtu" --quiet
    "$mixoct" check "$tmp/p.pvtu" --surface "$surf" --json >"$tmp/c.json" || true
    printf '%-6s %-22s defects %s, hash %s (single-process file %s)\n' "$L" "check 2-rank .pvtu" \
      "$(get "$tmp/c.json" defects)" "$(get "$tmp/c.json" mesh_hash)" "$hs"
    row "{\"level\": $L, \"run\": \"check\", \"defects\": $(get "$tmp/c.json" defects), \"hash\": \"$(get "$tmp/c.json" mesh_hash)\", \"single_hash\": \"$hs\"}"
    rm -f "$tmp"/*.vtu "$tmp"/*.pvtu
  fi
done
echo "{\"bench\": \"p4est\", \"surface\": \"$surf\", \"repeat\": $repeat, \"rows\": [$rows]}"
