#!/usr/bin/env bash
# `mixoct check` reads what other programs write (issue 30, item 3). The demo
# (-s 3) is written by mixoct as .vtu and .msh, then converted at test time
# (tests/reader_variants.py) by
#   meshio 5  .vtu zlib (its default, inline base64), lzma, inline base64
#             uncompressed, ASCII; legacy .vtk binary and ASCII; MSH 2.2
#             binary and ASCII;
#   VTK 9     .vtu with VTK's defaults (appended base64, zlib), appended
#             raw (zlib, LZ4, LZMA, none), appended base64
#             (zlib, none), inline base64 (zlib, none), ASCII, header_type
#             UInt32 and UInt64, BigEndian (with LZ4 base64 UInt32, inline
#             LZMA); legacy .vtk ASCII and binary (file version 5.1:
#             OFFSETS/CONNECTIVITY; and 4.2, the count-prefixed list);
#   gmsh      MSH 2.2 ASCII and binary, legacy .vtk ASCII and binary (the
#             volume cells with the boundary triangles and quadrilaterals)
# and each variant is checked: exit 0, nodes and elements by type as in
# mixoct's own file, the mesh hash (order-independent: io/mesh_hash.c) equal
# to the original's; for the writers that print fewer digits than a double
# needs (meshio's ASCII .vtu, VTK's ASCII legacy, gmsh's ASCII files), equal
# to the hash of the file meshio (legacy .vtk: VTK) reads and writes back in
# binary instead (the same numbers parsed by another program). Gmsh's files must also bring the
# boundary faces (the 2.2 triangles and quadrangles, the .vtk's 2D cells) as
# tagged faces covering exactly the boundary (as many as in mixoct's .msh).
# Then broken files give exit 2 and a message naming the file: a byte
# flipped in a zlib stream, a block cut short, a block size past the end of
# the file, a block size no zlib stream can give, a character that is not
# base64, a binary MSH 2.2 cut in its elements. Last, the size map reader
# (--size FILE) reads the field h from zlib, LZ4 base64 UInt32, inline LZMA
# big-endian and uncompressed files: the same mesh from each, another than
# without the map.
#
# Debian: python3-meshio python3-vtk9 python3-numpy gmsh. Missing: SKIP
# (exit 77), a failure when the environment variable CI is set.
MIXOCT=${1:?usage: reader_variants_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/lib.sh"
missing() {
  if [ -n "${CI:-}" ]; then
    echo "FAIL $1 not installed (CI is set)"
    exit 1
  fi
  echo "SKIP $1 not installed"
  exit 77
}
PY=$(find_python "meshio, vtk, numpy") || missing "python3 meshio and vtk (Debian: python3-meshio python3-vtk9 python3-numpy)"
GMSH=${GMSH:-gmsh}
command -v "$GMSH" >/dev/null 2>&1 || missing gmsh

# A check's figures, one line: nodes, elements by type, hash, exit code,
# tagged faces, tagged faces off the boundary, boundary faces untagged.
summary() { # file
  "$MIXOCT" check "$1" --json >"$T/check.out" 2>"$T/check.err"
  local code=$?
  tail -n 1 "$T/check.out" | "$PY" -c '
import json, sys
try:
    j = json.load(sys.stdin)
except ValueError:
    print("exit=%s unreadable" % sys.argv[1]); sys.exit()
b = j["by_type"]
faces = sum(t["triangles"] + t["quads"] for t in j.get("boundary_tags") or [])
print("nodes=%d tet=%d pyramid=%d prism=%d hex=%d hash=%s exit=%s faces=%d off=%d untagged=%d" % (
    j["nodes"], b["tet"], b["pyramid"], b["prism"], b["hex"], j["mesh_hash"], sys.argv[1],
    faces, j["tagged_not_boundary"], j["boundary_untagged"]))' "$code"
}
field() { echo "$1" | tr ' ' '\n' | sed -n "s/^$2=//p"; }
counts() { echo "$1" | sed 's/ hash=.*//'; }

"$MIXOCT" --demo -s 3 -o "$T/demo.vtu" -o "$T/demo.msh" >/dev/null 2>"$T/err" ||
  { cat "$T/err"; echo "FAIL mixoct --demo"; exit 1; }
REF=$(summary "$T/demo.vtu")
REFMSH=$(summary "$T/demo.msh")
echo "demo.vtu: $REF"
[ "$(field "$REF" exit)" = 0 ] || bad "demo.vtu: exit $(field "$REF" exit)"
NFACES=$(field "$REFMSH" faces)
[ "$NFACES" -gt 0 ] 2>/dev/null || bad "demo.msh: no tagged faces ($REFMSH)"

mkdir -p "$T/v"
"$PY" "$HERE/reader_variants.py" make "$T/v" "$T/demo.vtu" >"$T/list" 2>"$T/err" ||
  { cat "$T/err"; echo "FAIL reader_variants.py make"; exit 1; }
for spec in "msh22:gmsh22a.msh:" "msh22:gmsh22b.msh:-bin" "vtk:gmsh_ascii.vtk:" "vtk:gmsh_bin.vtk:-bin"; do
  IFS=: read -r fmt name opt <<<"$spec"
  if timeout 120 "$GMSH" "$T/demo.msh" -save -format "$fmt" $opt -o "$T/v/$name" >"$T/gmsh.log" 2>&1; then
    lossy=0
    [ -z "$opt" ] && lossy=1 # gmsh prints 16 digits
    echo "$name $lossy" >>"$T/list"
  else
    bad "gmsh -format $fmt $opt: failed"
    tail -n 3 "$T/gmsh.log"
  fi
done

# ---- every variant --------------------------------------------------------------
n=0
while read -r name lossy; do
  case "$name" in sz_*) continue ;; esac
  f="$T/v/$name"
  got=$(summary "$f")
  n=$((n + 1))
  if [ "$(field "$got" exit)" != 0 ]; then
    bad "$name: exit $(field "$got" exit): $(head -c 300 "$T/check.err")"
    continue
  fi
  same "$(counts "$got" | sed 's/ exit=.*//')" "$(counts "$REF" | sed 's/ exit=.*//')" "$name: counts"
  want=$(field "$REF" hash)
  how="the original's"
  if [ "$lossy" = 1 ]; then
    "$PY" "$HERE/reader_variants.py" ref "$f" "$T/ref.vtu" >/dev/null 2>"$T/err" || { bad "$name: meshio cannot read it back"; continue; }
    want=$(field "$(summary "$T/ref.vtu")" hash)
    how="its numbers written back by meshio"
  fi
  same "$(field "$got" hash)" "$want" "$name: mesh hash = $how"
  case "$name" in
    gmsh*)
      same "$(field "$got" faces) $(field "$got" off) $(field "$got" untagged)" "$NFACES 0 0" \
        "$name: $NFACES tagged faces, all on the boundary, covering it" ;;
  esac
done <"$T/list"
[ "$n" -ge 29 ] || bad "only $n variants written"

# ---- broken files ---------------------------------------------------------------
broken() { # description file
  "$MIXOCT" check "$2" >"$T/out" 2>"$T/err"
  local code=$?
  if [ "$code" = 2 ] && grep -q "$(basename "$2")" "$T/err"; then
    ok "$1: exit 2, $(head -n 1 "$T/err" | sed "s|$T/||" | cut -c1-160)"
  else
    bad "$1: exit $code, $(head -c 300 "$T/err")"
  fi
}
for spec in flip:vtk_zlib cut:vtk_zlib huge:vtk_zlib ratio:vtk_zlib flip:vtk_be huge:vtk_u32 \
            cut:vtk_lz4 b64:vtk_b64 huge:vtk_lzma; do
  kind=${spec%%:*} src=${spec#*:}
  out="$T/${src}_$kind.vtu"
  "$PY" "$HERE/reader_variants.py" corrupt "$kind" "$T/v/$src.vtu" "$out" ||
    { bad "corrupt $kind $src"; continue; }
  broken "$src.vtu, $kind" "$out"
done
for name in gmsh22b mio22b; do
  el=$(grep -a -b -o '\$Elements' "$T/v/$name.msh" | head -n 1 | cut -d: -f1)
  el_end=$(grep -a -b -o '\$EndElements' "$T/v/$name.msh" | head -n 1 | cut -d: -f1)
  head -c $(( (el + el_end) / 2 )) "$T/v/$name.msh" >"$T/${name}_cut.msh"
  broken "$name.msh cut in its elements" "$T/${name}_cut.msh"
done

# ---- size maps --------------------------------------------------------------------
base=$("$MIXOCT" --demo -s 2 -o "$T/plain.vtu" >/dev/null 2>&1 && field "$(summary "$T/plain.vtu")" hash)
first=""
for sz in sz_zlib sz_lz4_b64 sz_inline_lzma_be sz_raw; do
  if ! "$MIXOCT" --demo -s 2 --size "$T/v/$sz.vtu" --size-field h -o "$T/m_$sz.vtu" >/dev/null 2>"$T/err"; then
    bad "--size $sz.vtu: $(head -c 300 "$T/err")"
    continue
  fi
  h=$(field "$(summary "$T/m_$sz.vtu")" hash)
  if [ -z "$first" ]; then
    first=$h
    if [ "$h" != "$base" ] && [ -n "$base" ]; then ok "--size $sz.vtu: mesh $h, not the plain $base"; else bad "--size $sz.vtu: the same mesh as without it"; fi
  else
    same "$h" "$first" "--size $sz.vtu: the same mesh as from sz_zlib.vtu"
  fi
done

echo "reader variants: $n files, $fails failure(s)"
[ "$fails" -eq 0 ]
