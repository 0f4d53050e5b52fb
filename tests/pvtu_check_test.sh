#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# `mixoct check` on parallel VTU files (io/pvtu.h, io/read_mesh.h): the
# demo mesh written whole (mesh.vtu), in 3 pieces with GlobalNodeId
# (mesh3.pvtu) and in 2 pieces without (coords2.pvtu) by
# `test_pvtu --write DIR`; the three checks report the same node, element,
# face and defect counts and the same mesh hash, in JSON and in the text
# report; VTK's reader (when python3 has vtk) reads the master and its
# pieces. A mesh of another level has another hash; a master naming a
# missing piece is bad input (exit 2, the master's file and line).
# Arguments: the mixoct program and the test_pvtu program.
BIN=${1:?usage: pvtu_check_test.sh path/to/mixoct path/to/test_pvtu}
WRITER=${2:?usage: pvtu_check_test.sh path/to/mixoct path/to/test_pvtu}
BIN=$(readlink -f "$BIN")
WRITER=$(readlink -f "$WRITER")
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cd "$T" || exit 1
. "$HERE/lib.sh"

# The value of a key of the one-line JSON object in a file.
key() { grep -o "\"$1\":[^,}]*" "$2" | head -1 | cut -d: -f2 | tr -d '"'; }

"$WRITER" --write "$T" >"$T/w.out" 2>&1 || { cat "$T/w.out"; bad "test_pvtu --write"; exit 1; }
for m in mesh.vtu mesh3.pvtu coords2.pvtu; do
  expect_exit 0 "check $m" "$BIN" check "$m" --json
  cp "$T/out" "$T/$m.json"
done
hash=$(key mesh_hash mesh.vtu.json)
if [[ "$hash" =~ ^[0-9a-f]{16}$ ]]; then ok "mesh_hash $hash"; else bad "mesh_hash '$hash'"; fi
nodes=$(key nodes mesh.vtu.json)
elements=$(key elements mesh.vtu.json)
[ "$nodes" -gt 1000 ] 2>/dev/null && ok "nodes $nodes" || bad "nodes: '$nodes'"
for m in mesh3.pvtu coords2.pvtu; do
  for k in nodes elements hex prism pyramid tet faces_interior faces_boundary unused_nodes \
           duplicate_nodes invalid defects mesh_hash; do
    same "$(key $k $m.json)" "$(key $k mesh.vtu.json)" "$m: $k"
  done
done

# The text report's line.
expect_exit 0 "check mesh3.pvtu (text)" "$BIN" check mesh3.pvtu
has "$T/out" "mesh hash *$hash" "text report: mesh hash"

# Another mesh, another hash.
expect_exit 0 "demo -s 3" "$BIN" --demo -s 3 -o other.vtu
expect_exit 0 "check other.vtu" "$BIN" check other.vtu --json
other=$(key mesh_hash "$T/out")
if [ -n "$other" ] && [ "$other" != "$hash" ]; then ok "another mesh, another hash"
else bad "another mesh's hash '$other' (the demo's $hash)"; fi

# VTK's own reader (ParaView's) takes the master and its pieces: every
# piece's points (not merged), the cells, the arrays with their types, and
# as many distinct GlobalNodeIds as nodes (python3 with vtk, Debian
# python3-vtk9; skipped without it).
PY=
for p in python3 /usr/bin/python3; do
  if command -v "$p" >/dev/null && "$p" -c "import vtk" 2>/dev/null; then PY=$p; break; fi
done
if [ -n "$PY" ]; then
  if "$PY" - "$nodes" "$elements" >"$T/vtk.out" 2>&1 <<'PYEOF'
import sys, vtk
nodes, cells = int(sys.argv[1]), int(sys.argv[2])
r = vtk.vtkXMLPUnstructuredGridReader()
r.SetFileName("mesh3.pvtu")
r.Update()
g = r.GetOutput()
pd, cd = g.GetPointData(), g.GetCellData()
assert g.GetNumberOfCells() == cells, g.GetNumberOfCells()
assert g.GetNumberOfPoints() >= nodes, g.GetNumberOfPoints()
ids = pd.GetArray("GlobalNodeId")
assert ids is not None and ids.GetDataTypeAsString() in ("long long", "long"), ids
assert len({int(ids.GetTuple1(i)) for i in range(ids.GetNumberOfTuples())}) == nodes
assert pd.GetArray("surface_tag").GetDataTypeAsString() == "int"
assert cd.GetArray("jens").GetDataTypeAsString() == "double"
print("vtk: %d points, %d cells" % (g.GetNumberOfPoints(), g.GetNumberOfCells()))
PYEOF
  then
    ok "VTK reads mesh3.pvtu ($(tail -1 "$T/vtk.out"))"
  else
    bad "VTK on mesh3.pvtu"
    cat "$T/vtk.out"
  fi
else
  echo "SKIP VTK's reader: no python3 with vtk"
fi

# A missing piece.
rm mesh3_2.vtu
expect_exit 2 "check with a missing piece" "$BIN" check mesh3.pvtu
has "$T/err" "mesh3.pvtu:[0-9]*: piece 2: cannot read" "the missing piece: file:line"

if [ "$fails" -ne 0 ]; then echo "$fails failure(s)"; exit 1; fi
echo "all passed"
