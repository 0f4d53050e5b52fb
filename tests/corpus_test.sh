#!/usr/bin/env bash
# "Exit 0 means a valid mesh", on real CAD surfaces: a handful of OpenSCAD
# models (Debian openscad: its examples; openscad-testing-data: regression
# models and the odd STL files shipped with them) are rendered to STL and
# meshed at -s 3, 4 and 5:
#   mixoct -i X.stl -s L -o X_L.vtu --quiet
# Allowed outcomes:
#   exit 0  the file exists and `mixoct check X_L.vtu --surface X.stl`
#           exits 0 with "defects":0 and "invalid":0 (every defect kind of
#           the checker counts, the volume error and boundary distance
#           tolerances of --surface too: the table says "volume/distance
#           only" when those are the only ones);
#   exit 2  input refused, with a message on stderr, nothing written;
#   exit 5  the result breaks the contract (elements with J_ENS < 1e-6 or
#           contacts left), with a message on stderr,
#           nothing written (no --keep-invalid).
# Anything else is a failure: exit 0 with no file or a mesh that check
# rejects, exit 1, 3, 4, a signal (139: segfault), a timeout (120 s), exit 2
# or 5 without a message or with a file.
# One table line per run: model, level, exit, check result, seconds (mesh
# plus check), and the first stderr line when the exit is not 0.
# The models (about 1 s each to render): example001 (sphere drilled by three
# cylinders), LetterBlock (text cut into a cube), issue835 (plate with
# round holes), internal-cavity (a hollow cube cut in half: an open box,
# walls a quarter of its width), horn-torus (torus with a zero inner
# radius), issue1105d (a hollow ring, cut: thin walls),
# minkowski-thin-cylinder (a cube swept by a 1e-7 thick cylinder),
# nonmanifold-polyhedron (six faces, one of them crossing the others: not a
# closed 2-manifold); the
# STL files: import_bin_solid.stl (binary, header starting with "solid"),
# issue1580-back-to-back.stl (coincident opposite faces), invalidvertex.stl
# (a non-numeric coordinate). A model given as PATH:L,L... is meshed at
# those levels instead: example023 (a knot of extruded text: at -s 3 two
# sheets of the boundary met on a sharp edge, a node on another element's
# face, exit 0 before the mesher checked for such contacts), example009
# (-s 6: the same on a face) and offset (-s 7: lattice nodes on a flat top
# were moved off the surface by the untangling). The whole corpus:
# tools/openscad_corpus.sh
# and bench/corpus_bench.sh.
# Environment: CORPUS_LEVELS (default "3 4 5"), CORPUS_CHECK_ARGS (more
# arguments for `mixoct check`, e.g. "--volume-tol 0.5"; none by default).
# Without openscad: SKIP (exit 77), a failure when the environment variable
# CI is set. Runtime: about a minute and a half on 2 cores.
MIXOCT=${1:?usage: corpus_test.sh path/to/mixoct}
export LC_ALL=C
OPENSCAD=${OPENSCAD:-openscad}
LEVELS=${CORPUS_LEVELS:-"3 4 5"}
CHECK_ARGS=${CORPUS_CHECK_ARGS:-}

skip() {
  if [ -n "${CI:-}" ]; then
    echo "FAIL $* (CI is set: openscad and openscad-testing-data are required)"
    exit 1
  fi
  echo "SKIP $*"
  exit 77
}
command -v "$OPENSCAD" >/dev/null 2>&1 || skip "openscad not installed (Debian: openscad openscad-testing-data)"

pkgdir() { dpkg -L "$1" 2>/dev/null | grep -m1 -- "$2\$" | sed "s|$2\$||"; }
ex=${OPENSCAD_EXAMPLES:-$(pkgdir openscad /Old/example001.scad)}
[ -d "$ex" ] || ex=/usr/share/openscad/examples
td=${OPENSCAD_TESTDATA:-$(pkgdir openscad-testing-data /scad/misc/cube10.scad)}
[ -d "$td" ] || td=/usr/share/openscad/testdata

models="
$ex/Old/example001.scad
$ex/Basics/LetterBlock.scad
$td/scad/3D/issues/issue835.scad
$td/scad/misc/internal-cavity.scad
$td/scad/3D/issues/horn-torus.scad
$td/scad/3D/issues/issue1105d.scad
$td/scad/3D/issues/minkowski-thin-cylinder.scad
$td/scad/misc/nonmanifold-polyhedron.scad
$ex/Old/example023.scad
$ex/Old/example009.scad:6
$ex/Advanced/offset.scad:7
"
stls="
$td/scad/3D/features/import_bin_solid.stl
$td/scad/bugs/issue1580-back-to-back.stl
$td/stl/invalidvertex.stl
"

T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
start=$(now)

# Render (or copy) the inputs.
inputs=
for spec in $models; do
  f=${spec%%:*}
  n=$(basename "$f" .scad)
  case $spec in *:*) eval "levels_$(printf '%s' "$n" | tr -c 'A-Za-z0-9_\n' _)=\"$(printf '%s' "${spec#*:}" | tr , ' ')\"" ;; esac
  if [ ! -f "$f" ]; then echo "note: $f not installed"; continue; fi
  (cd "$T" && timeout -k 5 60 "$OPENSCAD" -o "$T/$n.stl" "$f") >"$T/render.log" 2>&1
  if [ $? -ne 0 ] || [ ! -s "$T/$n.stl" ]; then
    echo "note: openscad could not render $f:"; tail -3 "$T/render.log"
    rm -f "$T/$n.stl"; continue
  fi
  inputs="$inputs $n"
done
for f in $stls; do
  [ -f "$f" ] || { echo "note: $f not installed"; continue; }
  n=stl_$(basename "$f" .stl)
  cp "$f" "$T/$n.stl"
  inputs="$inputs $n"
done
set -- $inputs
[ $# -ge 3 ] || skip "fewer than 3 inputs rendered ($inputs)"
echo "inputs ($# in $(elapsed "$start") s):$inputs"

# The non-zero defect counts of a `mixoct check --json` object, as
# "key:count ..." (every integer field but the sizes and non-defect counts).
defect_counts() {
  printf '%s\n' "$1" | sed 's/"tolerances".*//; s/"by_type":{[^}]*}//' |
    tr ',{' '\n\n' | grep -E '^"[a-z_]+":[0-9]+$' |
    grep -vE '^"(nodes|elements|faces_interior|faces_boundary|nonmanifold_edges|surface_open_edges|defects|volume|surface_volume|volume_error|boundary_max_dist|hausdorff_[a-z_]+|jens_min|jens_mean)":' |
    grep -v ':0$' | tr -d '"' | tr '\n' ' '
}

printf '     %-26s %5s %4s  %-34s %6s\n' model level exit check seconds
for n in $inputs; do
  var=levels_$(printf '%s' "$n" | tr -c 'A-Za-z0-9_\n' _)
  eval "levs=\${$var:-\$LEVELS}"
  for k in $levs; do
    out="$T/${n}_$k.vtu"
    t0=$(now)
    timeout -k 5 120 "$MIXOCT" -i "$T/$n.stl" -s "$k" -o "$out" --quiet >"$T/out" 2>"$T/err"
    rc=$?
    check=- verdict=ok
    msg=$(grep -m1 . "$T/err" | cut -c1-100)
    case $rc in
    0)
      if [ ! -s "$out" ]; then
        check="NO OUTPUT FILE"; verdict=bad
      else
        "$MIXOCT" check "$out" --surface "$T/$n.stl" $CHECK_ARGS --json --quiet >"$T/check" 2>"$T/check.err"
        crc=$?
        j=$(tail -1 "$T/check")
        num() { printf '%s\n' "$j" | sed -n "s/.*[{,]\"$1\":\([-0-9.e+]*\)[,}].*/\1/p"; }
        defects=$(num defects) invalid=$(num invalid)
        if [ "$crc" -eq 0 ] && [ "$defects" = 0 ] && [ "$invalid" = 0 ]; then
          check=OK
        else
          verdict=bad
          if [ -z "$defects" ]; then
            check="check exit $crc, no JSON"
          else
            msg=$(defect_counts "$j")
            case " $msg" in
            *" volume_off:"* | *" boundary_off_surface:"*)
              if [ -n "$msg" ] && [ -z "$(printf '%s\n' $msg | grep -vE '^(volume_off|boundary_off_surface):')" ]; then
                check="REJECTED (volume/distance only)"
              else
                check="REJECTED"
              fi ;;
            *) check="REJECTED" ;;
            esac
            msg="check exit $crc, defects $defects: $msg"
          fi
          [ -s "$T/check.err" ] && msg="$msg $(head -1 "$T/check.err")"
        fi
      fi
      ;;
    2 | 5)
      [ $rc -eq 2 ] && check="refused" || check="contract broken (exit 5)"
      if [ -z "$msg" ]; then
        verdict=bad; check="$check, NO MESSAGE on stderr"
      fi
      if [ -e "$out" ]; then
        verdict=bad; check="$check, BUT A FILE WAS WRITTEN"
      fi
      ;;
    124 | 137) check="TIMEOUT (120 s)"; verdict=bad ;;
    *)
      if [ $rc -gt 128 ]; then check="CRASH (signal $((rc - 128)))"; else check="UNEXPECTED EXIT"; fi
      verdict=bad
      ;;
    esac
    line=$(printf '%-26s %5s %4s  %-34s %6s' "$n" "$k" "$rc" "$check" "$(elapsed "$t0")")
    if [ $verdict = ok ]; then
      echo "ok   $line${msg:+  [$msg]}"
    else
      echo "FAIL $line${msg:+  [$msg]}"
      fails=$((fails + 1))
    fi
    rm -f "$out"
  done
done

echo "total $(elapsed "$start") s"
echo "$fails failure(s)"
[ "$fails" -eq 0 ]
