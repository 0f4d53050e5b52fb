#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# The boundary tags (mesher/output.c, make_tags) and the node states' inside
# nodes on the surface (MX_NODE_ON, kernels/boundary.h). The L
# (tests/make_l_shape.py): the unit cube less [1/2, 1] x [0, 1] x [1/2, 1],
# whose inner faces lie in the root's middle planes, lattice planes at every
# level: at -s 5 inside nodes lie exactly on them (JSON boundary.on_surface
# > 0, 0 when the states ignore the distance), and every boundary face of
# its .msh and .vtu is tagged (mixoct check --surface finds the boundary on
# its own and counts the faces without a tag as defects). The same at -s 4
# and for the cortex at -s 5 when ../shared/data is there. The point field
# "boundary" of the .vtu flags exactly the nodes of the faces used once
# (tests/boundary_flags_check.py, meshio; with the outside nodes alone it
# missed the L's 90 inside nodes lying on its faces). (The tags once
# looked for boundary faces among the faces of outside and MX_NODE_ON nodes
# only: not enough where a triangle lies in the plane of a leaf's face;
# see make_tags.)
MIXOCT=${1:?usage: tag_faces_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"
PY=$(find_python json) || { echo "SKIP: no python3"; exit 77; }
MPY=$(find_python meshio,numpy) || MPY=

"$PY" "$HERE/make_l_shape.py" "$T/L.off" || bad "make_l_shape.py"

mesh_check() { # name, input, level
  expect_exit 0 "$1 -s $3" "$MIXOCT" -i "$2" -s "$3" --no-features --json -o "$T/a.msh" \
    -o "$T/a.vtu"
  tail -1 "$T/out" >"$T/a.json"
  for e in msh vtu; do
    expect_exit 0 "$1 -s $3: check the .$e against the input" "$MIXOCT" check "$T/a.$e" \
      --surface "$2"
  done
  expect_exit 0 "$1 -s $3: the .vtu's boundary flags checked" "$MIXOCT" check "$T/a.vtu" --json
  has "$T/out" '"boundary_flags_off":0,' "$1 -s $3: mixoct check compares the boundary flags"
  if [ -n "$MPY" ]; then
    if "$MPY" "$HERE/boundary_flags_check.py" "$T/a.vtu" >"$T/bf" 2>&1; then
      ok "$1 -s $3: the boundary flags are the boundary faces' nodes"
    else
      bad "$1 -s $3: boundary flags: $(cat "$T/bf")"
    fi
  else
    echo "skip: the boundary flags (no meshio)"
  fi
}

mesh_check "the L" "$T/L.off" 5
if "$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if d['boundary']['on_surface'] > 0 else 1)" "$T/a.json"; then
  ok "the L at -s 5 has inside nodes on the surface"
else
  bad "the L at -s 5: no inside node on the surface ($(head -c 300 "$T/a.json"))"
fi
mesh_check "the L" "$T/L.off" 4
# one flag turned off by meshio: mixoct check names that node
if [ -n "$MPY" ]; then
  "$MPY" - "$T/a.vtu" "$T/flip.vtu" <<'EOS' >"$T/flip"
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
b = np.asarray(m.point_data["boundary"]).astype(np.uint8).copy()
v = int(np.nonzero(b)[0][0])
b[v] = 0
m.point_data = {"boundary": b}
m.cell_data = {}
meshio.write(sys.argv[2], m, binary=True, compression=None)
print(v)
EOS
  expect_exit 5 "a .vtu with one boundary flag off: a defect" "$MIXOCT" check "$T/flip.vtu" --json
  has "$T/out" '"boundary_flags_off":1,' "mixoct check counts the flag off"
  has "$T/out" "\"boundary_flags_off\":\[$(cat "$T/flip")\]" "mixoct check names its node"
fi
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
[ -d "$DATA/surfaces" ] || DATA=$HERE/../../shared/data
CORTEX="$DATA/surfaces/cortex.off"
if [ -f "$CORTEX" ]; then mesh_check "the cortex" "$CORTEX" 5; else echo "skip: $CORTEX not found"; fi

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
