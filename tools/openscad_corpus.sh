#!/usr/bin/env bash
# A corpus of real CAD surfaces for mixoct, rendered with OpenSCAD from the
# example models (Debian package openscad) and the regression-test models
# (Debian package openscad-testing-data).
#
#   tools/openscad_corpus.sh OUTDIR [MAX]
#
# Writes OUTDIR/NAME.stl for up to MAX models (default 40) and copies the
# STL files shipped with openscad-testing-data (inputs a user may try:
# ASCII and binary, a binary file whose header starts with "solid", empty,
# unparseable, too many vertices, a non-numeric vertex, zero-area and
# back-to-back triangles, non-manifold scans...) to OUTDIR/broken/.
#
# The models: first a fixed, varied list (sharp-edged CAD parts, thin walls
# and slivers, holes and internal cavities, curved and revolved parts,
# degenerate and non-manifold polyhedra), then, when MAX is larger, every
# other .scad of the two packages; each list sorted, so the result depends
# only on MAX and the installed packages. A model that fails to render,
# renders nothing 3D (2D-only, echo tests, empty) or takes more than
# OPENSCAD_TIMEOUT seconds (default 30) is skipped. One line per model
# (rendered / skipped and why), a summary at the end, and
# OUTDIR/SOURCES.txt (name, source .scad or .stl).
#
# Only OUTDIR is written (never the source tree nor the package files).
# OUTDIR must be new, empty, or a corpus made by this script (then its
# *.stl and broken/*.stl are replaced).
#
# Environment: OPENSCAD (program, default openscad), OPENSCAD_TIMEOUT (s),
# OPENSCAD_EXAMPLES, OPENSCAD_TESTDATA (the two data directories; found
# with dpkg -L, else under /usr/share/openscad).
# Exit status: 0 when at least one model rendered, 1 otherwise, 2 usage.
set -u
export LC_ALL=C

usage() { echo "usage: tools/openscad_corpus.sh OUTDIR [MAX]" >&2; exit 2; }
[ $# -ge 1 ] && [ $# -le 2 ] || usage
out=$1
max=${2:-40}
case $max in '' | *[!0-9]*) usage ;; esac
OPENSCAD=${OPENSCAD:-openscad}
tmo=${OPENSCAD_TIMEOUT:-30}
command -v "$OPENSCAD" >/dev/null 2>&1 || { echo "openscad_corpus: $OPENSCAD not found (Debian: apt-get install openscad openscad-testing-data)" >&2; exit 1; }

# Never inside the source tree.
root=$(cd "$(dirname "$0")/.." && pwd -P)
out=$(realpath -m -- "$out")
case "$out/" in
  "$root"/*) echo "openscad_corpus: $out is inside the source tree $root; pick a directory elsewhere" >&2; exit 2 ;;
esac
mkdir -p "$out" || exit 1
if [ -n "$(ls -A "$out")" ] && [ ! -f "$out/SOURCES.txt" ]; then
  echo "openscad_corpus: $out is neither empty nor a corpus of this script" >&2; exit 2
fi
rm -f "$out"/*.stl "$out"/broken/*.stl "$out/SOURCES.txt"
mkdir -p "$out/broken" || exit 1

# The two data directories.
pkgdir() { # package suffix-of-a-known-file
  dpkg -L "$1" 2>/dev/null | grep -m1 -- "$2\$" | sed "s|$2\$||"
}
ex=${OPENSCAD_EXAMPLES:-$(pkgdir openscad /Old/example001.scad)}
[ -d "$ex" ] || ex=/usr/share/openscad/examples
td=${OPENSCAD_TESTDATA:-$(pkgdir openscad-testing-data /scad/misc/cube10.scad)}
[ -d "$td" ] || td=/usr/share/openscad/testdata
[ -d "$ex" ] || echo "note: no OpenSCAD examples directory (package openscad)"
[ -d "$td" ] || echo "note: no OpenSCAD testing data (package openscad-testing-data)"
echo "examples: $ex"
echo "testdata: $td"

# The chosen models (E: examples, T: testdata), by kind:
#   sharp CAD parts   CSG LetterBlock text_on_cube example001-004 007 009
#                     012 017 023 issue1258 issue3158 issue835 issue904
#   thin walls        minkowski-thin-cylinder (0.0000001 thick cylinder
#                     swept), issue1105d (hollow ring cut), surface-simple
#                     (height field), offset, rotate_extrude-angle
#   holes, hollows    internal-cavity internal-cavity-polyhedron (hollow
#                     cubes cut open) example001 issue835 issue1803 issue3158
#   curved            rotate_extrude horn-torus (torus with a zero inner
#                     radius) sphere-tests cylinder-tests (cones to a point)
#                     fn_bug linear_extrude (twisted) hull3-tests assert
#   degenerate / odd  polyhedron-concave-test polyhedron-nonplanar-tests
#                     union-coincident-test nonmanifold-polyhedron and
#                     issue964 (a face crossing the others)
#                     polygon-illegal-winding normal-nan
#                     adns2610_dev_circuit_inv (an imported STL scan)
chosen="
E Advanced/assert.scad
E Advanced/offset.scad
E Basics/CSG.scad
E Basics/LetterBlock.scad
E Basics/linear_extrude.scad
E Basics/rotate_extrude.scad
E Basics/text_on_cube.scad
E Old/example001.scad
E Old/example002.scad
E Old/example003.scad
E Old/example004.scad
E Old/example007.scad
E Old/example009.scad
E Old/example012.scad
E Old/example017.scad
E Old/example023.scad
T scad/3D/features/cylinder-tests.scad
T scad/3D/features/hull3-tests.scad
T scad/3D/features/polyhedron-concave-test.scad
T scad/3D/features/polyhedron-nonplanar-tests.scad
T scad/3D/features/rotate_extrude-angle.scad
T scad/3D/features/sphere-tests.scad
T scad/3D/features/surface-simple.scad
T scad/3D/features/union-coincident-test.scad
T scad/3D/issues/adns2610_dev_circuit_inv.scad
T scad/3D/issues/fn_bug.scad
T scad/3D/issues/horn-torus.scad
T scad/3D/issues/issue1105d.scad
T scad/3D/issues/issue1258.scad
T scad/3D/issues/issue1803.scad
T scad/3D/issues/issue3158.scad
T scad/3D/issues/issue835.scad
T scad/3D/issues/issue904.scad
T scad/3D/issues/issue964.scad
T scad/3D/issues/minkowski-thin-cylinder.scad
T scad/3D/issues/polygon-illegal-winding.scad
T scad/misc/internal-cavity.scad
T scad/misc/internal-cavity-polyhedron.scad
T scad/misc/nonmanifold-polyhedron.scad
T scad/misc/normal-nan.scad
"

list=$(mktemp)
work=$(mktemp -d)
trap 'rm -rf "$list" "$work"' EXIT
echo "$chosen" | while read -r k p; do
  [ -n "$k" ] || continue
  if [ "$k" = E ]; then echo "$ex/$p"; else echo "$td/$p"; fi
done | sort >"$list"
# The rest, for a larger MAX.
{
  [ -d "$ex" ] && find "$ex" -name '*.scad'
  [ -d "$td/scad" ] && find "$td/scad/3D" "$td/scad/misc" -name '*.scad' 2>/dev/null
} | sort | grep -vxF -f "$list" >>"$list"

# A name per model: the file's base name, with its directory in front when
# the base name is taken.
rendered=0 skipped=0 t_all=$(date +%s)
declare -A used
while read -r scad; do
  [ "$rendered" -lt "$max" ] || break
  base=$(basename "$scad" .scad)
  name=$base
  [ -n "${used[$name]:-}" ] && name="$(basename "$(dirname "$scad")")_$base"
  case $scad in
    "$ex"/*) short=examples/${scad#"$ex"/} ;;
    "$td"/*) short=testdata/${scad#"$td"/} ;;
    *) short=$scad ;;
  esac
  if [ ! -f "$scad" ]; then
    echo "skipped  $name: $short not installed"; skipped=$((skipped + 1)); continue
  fi
  t0=$(date +%s.%N)
  # In a scratch directory: some models write nothing, but OpenSCAD resolves
  # relative imports against the .scad's own directory anyway.
  (cd "$work" && timeout -k 5 "$tmo" "$OPENSCAD" -o "$work/m.stl" "$scad") >"$work/log" 2>&1
  rc=$?
  secs=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  facets=0
  if [ -s "$work/m.stl" ]; then
    if [ "$(head -c 5 "$work/m.stl")" = solid ]; then
      facets=$(grep -c '^ *facet' "$work/m.stl")
    else # binary: the count after the 80-byte header
      facets=$(od -An -tu4 -j80 -N4 "$work/m.stl" | tr -d ' ')
    fi
  fi
  if [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ]; then
    why="more than $tmo s"
  elif [ "$rc" -ne 0 ]; then
    why="openscad exit $rc: $(grep -m1 -E 'ERROR|error|WARNING' "$work/log" | cut -c1-90)"
  elif [ "$facets" -eq 0 ]; then
    why="no 3D object: $(grep -m1 -E 'ERROR|WARNING|empty|not a 3D' "$work/log" | cut -c1-90)"
  else
    why=
  fi
  if [ -n "$why" ]; then
    echo "skipped  $name ($short, $secs s): $why"
    skipped=$((skipped + 1))
    rm -f "$work/m.stl"
    continue
  fi
  used[$name]=1
  mv "$work/m.stl" "$out/$name.stl"
  note=$(grep -m1 'WARNING' "$work/log" | cut -c1-80)
  [ -n "$note" ] && note="  (openscad: $note)"
  printf 'rendered %-34s %7d facets %5s s  %s%s\n' "$name.stl" "$facets" "$secs" "$short" "$note"
  printf '%s.stl\t%s\n' "$name" "$scad" >>"$out/SOURCES.txt"
  rendered=$((rendered + 1))
done <"$list"

# The STL files of the testing data, flattened to DIR_NAME.stl; identical
# files once.
copied=0
declare -A seen
if [ -d "$td" ]; then
  while read -r f; do
    sum=$(md5sum <"$f" | cut -c1-32)
    name="$(basename "$(dirname "$f")")_$(basename "$f")"
    if [ -n "${seen[$sum]:-}" ]; then
      echo "broken   $name: same bytes as ${seen[$sum]}, not copied"; continue
    fi
    seen[$sum]=$name
    cp "$f" "$out/broken/$name"
    printf 'broken   %-40s %8d bytes  %s\n' "$name" "$(stat -c %s "$f")" "${f#"$td"/}"
    printf 'broken/%s\t%s\n' "$name" "$f" >>"$out/SOURCES.txt"
    copied=$((copied + 1))
  done < <(find "$td" -iname '*.stl' | sort)
fi

echo "rendered $rendered model(s), skipped $skipped, copied $copied STL file(s) to $out/broken ($(( $(date +%s) - t_all )) s)"
[ "$rendered" -gt 0 ]
