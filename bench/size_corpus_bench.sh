#!/usr/bin/env bash
# Issue 27's target on the OpenSCAD corpus: at the coarsest level of
# bench/corpus_bench.sh (-s 3, the lowest of its LEVELS), does a thickness
# size field keep every closed input's volume within 2%?
#
#   bench/size_corpus_bench.sh MIXOCT [OUTDIR]
#
# OUTDIR holds the corpus (OUTDIR/*.stl); when it has none,
# tools/openscad_corpus.sh renders MAX models there first (default OUTDIR:
# a temporary directory, removed at the end). Only the rendered models are
# meshed, not OUTDIR/broken/, and of them only the closed ones: those a
# dry run (mixoct -i X.stl -s 0 --stage octree) does not refuse as having
# no well-defined inside (open, non-manifold or self-crossing surfaces:
# listed, with mixoct's reason, and skipped). Each closed model twice:
#   (a) mixoct -i X.stl -s L -o RUN.vtu --json              (today)
#   (b) mixoct -i X.stl -s L --thickness N -o RUN.vtu --json
# each under timeout TIMEOUT, and after exit 0
#   mixoct check RUN.vtu --surface X.stl --json --quiet
# The class of a run is corpus_bench.sh's: valid (exit 0, check finds no
# defect with its own volume tolerance, 5% at least), refused (exit 2),
# invalid (exit 5), toolarge (exit 3), broken (exit 0 but check rejects
# the mesh, or no file), crashed (signal), timeout, other. The volume error
# is check's, (mesh - surface) / surface, printed in %; "ok2" counts the
# valid runs within 2% of the volume, the issue's target.
#
# One line per model: name, triangles, then for (a) and (b): exit, class,
# elements, volume error %, J_ENS min, the deepest level of the octree,
# mixoct's seconds (check's not counted); for (b) also the thickness
# sources. Then the totals for (a) and (b), the runs that time out, the
# (b) runs off by more than 2% or not valid, the element ratio (b)/(a)
# over the models both mesh, and one JSON object last.
#
# Environment: LEVEL (default 3), THICKNESS (N, default 2), TIMEOUT
# (seconds per mixoct run, default 120: the 36 closed models of MAX=40 in
# about 16 min on 2 busy cores, 4 (b) runs timing out), THREADS (mixoct --threads),
# MIXOCT_ARGS (more arguments for both runs), MAX (models rendered when
# the corpus is made, default 40), ONLY (a regular expression: only the
# models whose file name matches).
# Exit status: 0 when no run crashed or came out broken, 1 otherwise,
# 2 usage.
MIXOCT=${1:?usage: bench/size_corpus_bench.sh MIXOCT [OUTDIR]}
export LC_ALL=C
[ -x "$MIXOCT" ] || { echo "size_corpus_bench: $MIXOCT is not a program" >&2; exit 2; }
MIXOCT=$(realpath "$MIXOCT")
LEVEL=${LEVEL:-3}
THICKNESS=${THICKNESS:-2}
TIMEOUT=${TIMEOUT:-120}
MIXOCT_ARGS=${MIXOCT_ARGS:-}
here=$(cd "$(dirname "$0")" && pwd)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
corpus=${2:-$W/corpus}
threads=()
[ -n "${THREADS:-}" ] && threads=(--threads "$THREADS")

if ! ls "$corpus"/*.stl >/dev/null 2>&1; then
  echo "# rendering the corpus into $corpus"
  "$here/../tools/openscad_corpus.sh" "$corpus" "${MAX:-40}" | sed 's/^/# /'
  [ "${PIPESTATUS[0]}" -eq 0 ] || { echo "size_corpus_bench: no corpus" >&2; exit 2; }
fi
files=$( (cd "$corpus" && ls *.stl 2>/dev/null) | sort | grep -E -- "${ONLY:-.}")
[ -n "$files" ] || { echo "size_corpus_bench: no .stl in $corpus" >&2; exit 2; }

now() { date +%s.%N; }
dt() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }
# A number (or null) of a one-line JSON object: num JSON KEY.
num() { printf '%s\n' "$1" | sed -n "s/.*[{,] *\"$2\": *\([-0-9.e+a-z]*\)[,}].*/\1/p" | head -1; }
triangles() { # an STL file's facets: ASCII lines, or the binary count
  if [ "$(head -c 5 "$1")" = solid ] && grep -q '^ *facet' "$1"; then
    grep -c '^ *facet' "$1"
  else
    od -An -tu4 -j80 -N4 "$1" | tr -d ' '
  fi
}

# One run: run TAG FILE [ARGS...]; sets the globals r_* for the table.
run() {
  local tag=$1 f=$2
  shift 2
  local out=$W/run.vtu
  rm -f "$out"
  local t0 t1
  t0=$(now)
  timeout -k 10 "$TIMEOUT" "$MIXOCT" -i "$corpus/$f" -s "$LEVEL" "$@" -o "$out" --json \
    "${threads[@]}" $MIXOCT_ARGS >"$W/out" 2>"$W/err"
  r_rc=$?
  t1=$(now)
  r_secs=$(dt "$t0" "$t1")
  r_msg=$(grep -m1 . "$W/err" | sed 's/^mixoct: //' | cut -c1-110)
  local js
  js=$(tail -1 "$W/out")
  r_elems=- r_verr=- r_jmin=- r_lev=- r_src=- r_verr_raw=
  if [ "${js:0:1}" = "{" ]; then
    r_lev=$(num "$js" max_level)
    r_src=$(printf '%s\n' "$js" | sed -n 's/.*"sources": *{"count": *[0-9]*, "curvature": *[0-9]*, "thickness": *\([0-9]*\).*/\1/p')
  fi
  case $r_rc in
  0)
    if [ ! -s "$out" ]; then
      r_class=broken; r_msg="exit 0 but no output file"
    else
      "$MIXOCT" check "$out" --surface "$corpus/$f" --json --quiet >"$W/check" 2>"$W/check.err"
      local crc=$? j
      j=$(tail -1 "$W/check")
      local defects invalid
      defects=$(num "$j" defects) invalid=$(num "$j" invalid)
      r_elems=$(num "$j" elements)
      r_jmin=$(num "$j" jens_min)
      r_verr_raw=$(num "$j" volume_error)
      [ -n "$r_jmin" ] && [ "$r_jmin" != null ] && r_jmin=$(printf '%.3f' "$r_jmin")
      [ -n "$r_verr_raw" ] && [ "$r_verr_raw" != null ] &&
        r_verr=$(awk -v v="$r_verr_raw" 'BEGIN { printf "%+.2f", 100 * v }')
      if [ "$crc" -eq 0 ] && [ "$defects" = 0 ] && [ "$invalid" = 0 ]; then
        r_class=valid
      else
        r_class=broken
        r_msg="check exit $crc, defects ${defects:-?}: $(printf '%s\n' "$j" |
          grep -oE '"(volume_off|boundary_off_surface|invalid|faces_[a-z]+|[a-z_]*hanging[a-z_]*|open_boundary_edges)":[1-9][0-9]*' |
          tr -d '"' | tr '\n' ' ')"
      fi
    fi
    ;;
  2) r_class=refused ;;
  3) r_class=toolarge ;;
  5) r_class=invalid ;;
  124 | 137) r_class=timeout; r_msg="more than $TIMEOUT s" ;;
  *) if [ "$r_rc" -gt 128 ]; then r_class=crashed; else r_class=other; fi ;;
  esac
  r_ok2=0
  [ "$r_class" = valid ] &&
    awk -v v="$r_verr_raw" 'BEGIN { exit !(v != "" && v != "null" && v + 0 >= -0.02 && v + 0 <= 0.02) }' &&
    r_ok2=1
  rm -f "$out"
}

echo "# corpus $corpus: $(echo "$files" | wc -l) rendered model(s)${ONLY:+ matching $ONLY}"
echo "# mixoct $MIXOCT ($("$MIXOCT" --version 2>&1 | head -1)); (a) -s $LEVEL, (b) -s $LEVEL --thickness $THICKNESS; timeout $TIMEOUT s${THREADS:+, $THREADS thread(s)}${MIXOCT_ARGS:+, mixoct $MIXOCT_ARGS}"
start=$(now)
declare -A total
classes="valid ok2 refused invalid toolarge broken crashed timeout other"
for s in a b; do for c in $classes; do total[$s.$c]=0; done; total[$s.secs]=0; done
skipped=() notes=() timeouts=()
closed=0 both=0 el_a=0 el_b=0
printf '%-28s %6s | %-12s %8s %8s %6s %2s %6s | %-12s %8s %8s %6s %2s %6s %8s\n' \
  model tris "(a) exit" elems vol% jmin L s "(b) exit" elems vol% jmin L s sources
for f in $files; do
  name=${f%.stl}
  "$MIXOCT" -i "$corpus/$f" -s 0 --stage octree --quiet >/dev/null 2>"$W/probe"
  if [ $? -eq 2 ] && grep -q 'no well-defined inside' "$W/probe"; then
    skipped+=("$name: $(grep -m1 -o 'refused: [^,(]*' "$W/probe")")
    continue
  fi
  closed=$((closed + 1))
  tris=$(triangles "$corpus/$f")
  line=$(printf '%-28s %6s' "${name:0:28}" "$tris")
  for s in a b; do
    if [ $s = a ]; then run a "$f"; else run b "$f" --thickness "$THICKNESS"; fi
    total[$s.$r_class]=$((total[$s.$r_class] + 1))
    total[$s.ok2]=$((total[$s.ok2] + r_ok2))
    total[$s.secs]=$(awk -v a="${total[$s.secs]}" -v b="$r_secs" 'BEGIN { print a + b }')
    line+=$(printf ' | %3s %-8s %8s %8s %6s %2s %6s' "$r_rc" "$r_class" "$r_elems" "$r_verr" \
      "$r_jmin" "${r_lev:--}" "$r_secs")
    [ "$r_class" = timeout ] && timeouts+=("($s) $name")
    if [ $s = a ]; then
      a_elems=$r_elems
    else
      line+=$(printf ' %8s' "${r_src:--}")
      if [ "$r_ok2" = 0 ]; then
        v=; [ "$r_verr" != - ] && v=" $r_verr%"
        notes+=("$name: $r_class$v${r_msg:+; $r_msg}")
      fi
      if [ "$a_elems" != - ] && [ "$r_elems" != - ]; then
        both=$((both + 1)) el_a=$((el_a + a_elems)) el_b=$((el_b + r_elems))
      fi
    fi
  done
  echo "$line"
done
secs=$(dt "$start" "$(now)")
ratio=$(awk -v a="$el_a" -v b="$el_b" 'BEGIN { if (a > 0) printf "%.2f", b / a; else printf "null" }')

echo
echo "# $closed closed model(s), -s $LEVEL; skipped (no well-defined inside): ${#skipped[@]}"
[ ${#skipped[@]} -gt 0 ] && printf '#   %s\n' "${skipped[@]}"
printf '# %-34s %6s %6s\n' "runs" "(a)" "(b)"
for c in $classes; do
  case $c in
  ok2) what="  of which volume within 2%" ;;
  valid) what="valid (check's volume tolerance)" ;;
  *) what=$c ;;
  esac
  printf '#   %-32s %6d %6d\n' "$what" "${total[a.$c]}" "${total[b.$c]}"
done
printf '#   %-32s %6.1f %6.1f\n' "mixoct seconds" "${total[a.secs]}" "${total[b.secs]}"
echo "# elements (b)/(a): $ratio (over the $both model(s) both runs mesh: $el_a -> $el_b)"
if [ ${#timeouts[@]} -gt 0 ]; then
  echo "# timed out (more than $TIMEOUT s):"
  printf '#   %s\n' "${timeouts[@]}"
fi
if [ ${#notes[@]} -gt 0 ]; then
  echo "# (b) runs not valid within 2%:"
  printf '#   %s\n' "${notes[@]}"
fi
echo "# total $secs s"
printf '{"level":%s,"thickness":%s,"timeout":%s,"closed_models":%d,"skipped":%d' \
  "$LEVEL" "$THICKNESS" "$TIMEOUT" "$closed" "${#skipped[@]}"
for s in a b; do
  printf ',"%s":{' "$s"
  sep=
  for c in $classes; do printf '%s"%s":%d' "$sep" "$c" "${total[$s.$c]}"; sep=,; done
  printf ',"mixoct_seconds":%.1f}' "${total[$s.secs]}"
done
printf ',"elements_ratio":%s,"seconds":%s}\n' "$ratio" "$secs"
[ $((total[a.broken] + total[a.crashed] + total[b.broken] + total[b.crashed])) -eq 0 ]
