#!/usr/bin/env bash
# The OpenSCAD corpus (tools/openscad_corpus.sh: rendered CAD models plus
# the odd STL files of openscad-testing-data) meshed at every level of
# LEVELS, each result checked with `mixoct check --surface`:
#
#   bench/corpus_bench.sh MIXOCT [OUTDIR]
#
# OUTDIR holds the corpus (OUTDIR/*.stl, OUTDIR/broken/*.stl); when it has
# no .stl file, tools/openscad_corpus.sh renders it there first (default
# OUTDIR: a temporary directory, removed at the end). Per run:
#   mixoct -i X.stl -s L -o RUN.vtu --quiet     (under timeout TIMEOUT)
#   mixoct check RUN.vtu --surface X.stl --json --quiet   (after exit 0)
# and one of
#   valid    exit 0 and check reports no defect and no invalid element
#   refused  exit 2 (the input refused, with a message)
#   invalid  exit 5 (elements with J_ENS <= 0 left; nothing written)
#   broken   exit 0 but check rejects the mesh or no file was written:
#            the case that must never happen (counted apart too: the
#            broken runs whose only defects are check's --surface
#            tolerances, volume_off and boundary_off_surface)
#   crashed  killed by a signal (139: segfault, 134: abort)
#   timeout  more than TIMEOUT seconds
#   toolarge exit 3 with a message: the run's memory estimate is over
#            what the machine has (refused before meshing)
#   other    any other exit (1 internal failure, 3 without a message,
#            4 output),
#            or exit 2 / 5 without a message on stderr
# One line per run (file, level, exit, class, nodes, elements, J_ENS min,
# volume error, boundary distance, mesh and check seconds, and the first
# stderr line or the non-zero defect counts), then the totals, the list of
# broken / crashed / timeout / other runs, and last one JSON object with the
# totals.
#
# Environment: LEVELS (default "3 4 5 6 7"), TIMEOUT (seconds per mixoct
# run, default 120), THREADS (mixoct --threads, default: mixoct's default),
# MIXOCT_ARGS (more arguments for the mixoct runs, e.g. "--repair-input"),
# CHECK_ARGS (more arguments for `mixoct check`, e.g. "--volume-tol 0.5"),
# MAX (models rendered when the corpus is made, default 40), KEEP=1 keeps
# the .vtu of the broken runs in OUTDIR/bench_broken/.
# Exit status: 0 when nothing is broken, crashed or timed out, 1 otherwise,
# 2 usage.
MIXOCT=${1:?usage: bench/corpus_bench.sh MIXOCT [OUTDIR]}
export LC_ALL=C
[ -x "$MIXOCT" ] || { echo "corpus_bench: $MIXOCT is not a program" >&2; exit 2; }
MIXOCT=$(realpath "$MIXOCT")
LEVELS=${LEVELS:-"3 4 5 6 7"}
TIMEOUT=${TIMEOUT:-120}
CHECK_ARGS=${CHECK_ARGS:-}
MIXOCT_ARGS=${MIXOCT_ARGS:-}
here=$(cd "$(dirname "$0")" && pwd)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
corpus=${2:-$W/corpus}
threads=()
[ -n "${THREADS:-}" ] && threads=(--threads "$THREADS")

if ! ls "$corpus"/*.stl "$corpus"/broken/*.stl >/dev/null 2>&1; then
  echo "# rendering the corpus into $corpus"
  "$here/../tools/openscad_corpus.sh" "$corpus" "${MAX:-40}" | sed 's/^/# /'
  [ "${PIPESTATUS[0]}" -eq 0 ] || { echo "corpus_bench: no corpus" >&2; exit 2; }
fi
files=$( (cd "$corpus" && ls *.stl broken/*.stl 2>/dev/null) | sort)
nmodels=$( (cd "$corpus" && ls *.stl 2>/dev/null) | wc -l)
nbroken=$( (cd "$corpus" && ls broken/*.stl 2>/dev/null) | wc -l)
[ -n "$files" ] || { echo "corpus_bench: no .stl in $corpus" >&2; exit 2; }
echo "# corpus $corpus: $nmodels rendered model(s), $nbroken STL file(s) in broken/"
echo "# mixoct $MIXOCT ($("$MIXOCT" --version 2>&1 | head -1)), levels $LEVELS, timeout $TIMEOUT s${THREADS:+, $THREADS thread(s)}${MIXOCT_ARGS:+, mixoct $MIXOCT_ARGS}${CHECK_ARGS:+, check $CHECK_ARGS}"

# The non-zero defect counts of a `mixoct check --json` object, as
# "key:count ..." (every integer field but the sizes and non-defect counts).
defect_counts() {
  printf '%s\n' "$1" | sed 's/"tolerances".*//; s/"by_type":{[^}]*}//' |
    tr ',{' '\n\n' | grep -E '^"[a-z_]+":[0-9]+$' |
    grep -vE '^"(nodes|elements|faces_interior|faces_boundary|nonmanifold_edges|surface_open_edges|defects|volume|surface_volume|volume_error|boundary_max_dist|hausdorff_[a-z_]+|jens_min|jens_mean)":' |
    grep -v ':0$' | tr -d '"' | tr '\n' ' '
}
fidelity_only=0
now() { date +%s.%N; }
dt() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }
declare -A total=([valid]=0 [refused]=0 [invalid]=0 [toolarge]=0 [broken]=0 [crashed]=0 [timeout]=0 [other]=0)
declare -A lvl_time
problems=()
mesh_s=0
start=$(now)

printf '%-46s %3s %4s %-8s %9s %9s %8s %9s %8s %8s %7s  %s\n' \
  file level exit class nodes elements jens_min vol_err dist mesh_s check_s note
for f in $files; do
  for k in $LEVELS; do
    out=$W/run.vtu
    rm -f "$out"
    t0=$(now)
    timeout -k 10 "$TIMEOUT" "$MIXOCT" -i "$corpus/$f" -s "$k" -o "$out" --quiet \
      "${threads[@]}" $MIXOCT_ARGS >"$W/out" 2>"$W/err"
    rc=$?
    t1=$(now)
    t2=$t1
    msg=$(grep -m1 . "$W/err" | cut -c1-120)
    nodes=- elems=- jmin=- verr=- dist=-
    case $rc in
    0)
      if [ ! -s "$out" ]; then
        class=broken; msg="exit 0 but no output file${msg:+; $msg}"
      else
        "$MIXOCT" check "$out" --surface "$corpus/$f" $CHECK_ARGS --json --quiet >"$W/check" 2>"$W/check.err"
        crc=$?
        t2=$(now)
        j=$(tail -1 "$W/check")
        num() { printf '%s\n' "$j" | sed -n "s/.*[{,]\"$1\":\([-0-9.e+a-z]*\)[,}].*/\1/p"; }
        defects=$(num defects) invalid=$(num invalid)
        nodes=$(num nodes) elems=$(num elements)
        jmin=$(num jens_min) verr=$(num volume_error) dist=$(num boundary_max_dist)
        [ -n "$jmin" ] && [ "$jmin" != null ] && jmin=$(printf '%.4f' "$jmin")
        [ -n "$verr" ] && [ "$verr" != null ] && verr=$(printf '%+.1e' "$verr")
        [ -n "$dist" ] && [ "$dist" != null ] && dist=$(printf '%.0e' "$dist")
        if [ "$crc" -eq 0 ] && [ "$defects" = 0 ] && [ "$invalid" = 0 ]; then
          class=valid
        else
          class=broken
          if [ -z "$defects" ]; then
            msg="check exit $crc, no JSON: $(head -1 "$W/check.err")"
          else
            msg=$(defect_counts "$j")
            # only the --surface tolerances (volume error, boundary
            # distance): the mesh is valid but not faithful enough
            if [ -n "$msg" ] && [ -z "$(printf '%s\n' $msg | grep -vE '^(volume_off|boundary_off_surface):')" ]; then
              fidelity_only=$((fidelity_only + 1)); msg="[volume/distance only] $msg"
            fi
            msg="check exit $crc, defects $defects: $msg"
          fi
          if [ "${KEEP:-}" = 1 ]; then
            mkdir -p "$corpus/bench_broken"
            cp "$out" "$corpus/bench_broken/$(basename "$f" .stl)_$k.vtu"
          fi
        fi
      fi
      ;;
    2) class=refused ;;
    5) class=invalid ;;
    3) class=toolarge ;;
    124 | 137) class=timeout; msg="more than $TIMEOUT s" ;;
    *) if [ "$rc" -gt 128 ]; then class=crashed; else class=other; fi ;;
    esac
    if { [ "$class" = refused ] || [ "$class" = invalid ] || [ "$class" = toolarge ]; } &&
      [ -z "$msg" ]; then
      class=other; msg="exit $rc without a message"
    fi
    if [ "$class" = invalid ] && [ -e "$out" ]; then
      class=other; msg="exit 5 but the file was written; $msg"
    fi
    total[$class]=$((total[$class] + 1))
    ms=$(dt "$t0" "$t1")
    mesh_s=$(awk -v a="$mesh_s" -v b="$ms" 'BEGIN { print a + b }')
    lvl_time[$k]=$(awk -v a="${lvl_time[$k]:-0}" -v b="$ms" 'BEGIN { print a + b }')
    line=$(printf '%-46s %3s %4s %-8s %9s %9s %8s %9s %8s %8s %7s  %s' \
      "$f" "$k" "$rc" "$class" "${nodes:--}" "${elems:--}" "${jmin:--}" "${verr:--}" "${dist:--}" \
      "$ms" "$(dt "$t1" "$t2")" "$msg")
    echo "$line"
    case $class in broken | crashed | timeout | other) problems+=("$line") ;; esac
    rm -f "$out"
  done
done
secs=$(dt "$start" "$(now)")
runs=0
for c in "${!total[@]}"; do runs=$((runs + total[$c])); done

echo
echo "# totals: $runs runs ($nmodels models + $nbroken STL files, levels $LEVELS)"
for c in valid refused invalid toolarge broken crashed timeout other; do
  printf '#   %-8s %5d\n' "$c" "${total[$c]}"
  [ "$c" = broken ] && [ "${total[broken]}" -gt 0 ] &&
    printf '#     of which %d only over the volume / distance tolerances of check --surface\n' "$fidelity_only"
done
for k in $LEVELS; do printf '#   mixoct time at -s %s: %.1f s\n' "$k" "${lvl_time[$k]:-0}"; done
echo "#   time: mixoct $(printf '%.1f' "$mesh_s") s, total $secs s"
if [ ${#problems[@]} -gt 0 ]; then
  echo "# broken / crashed / timeout / other:"
  printf '#   %s\n' "${problems[@]}"
fi
printf '{"runs":%d,"models":%d,"stl_files":%d,"levels":[%s],"valid":%d,"refused":%d,"invalid":%d,"toolarge":%d,"broken":%d,"broken_volume_distance_only":%d,"crashed":%d,"timeout":%d,"other":%d,"mixoct_seconds":%.1f,"seconds":%s}\n' \
  "$runs" "$nmodels" "$nbroken" "$(echo $LEVELS | tr ' ' ',')" \
  "${total[valid]}" "${total[refused]}" "${total[invalid]}" "${total[toolarge]}" "${total[broken]}" "$fidelity_only" \
  "${total[crashed]}" "${total[timeout]}" "${total[other]}" "$mesh_s" "$secs"
[ $((total[broken] + total[crashed] + total[timeout])) -eq 0 ]
