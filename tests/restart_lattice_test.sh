#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# Re-meshing from a restart file of an input with faces in lattice planes
# (mesher/restart_octree.c, split_orphans). The L (tests/make_l_shape.py) at
# -s 5: its run splits octants outside the L that touch its inner faces and
# drops all their children; the restart file has no trace of them but their
# absence. Re-meshed without -s (as the README's re-meshing commands do),
# the octree rebuilt from the file must be the file's: before the fix it
# kept those octants as leaves (11,040 against 10,800) and refused the
# element list (exit 2, "the restart file's mesh cannot be made again").
# For the text (.oct) and binary (.octb) files: an empty list gives the
# mesh written with the file (the same mesh hash, leaves and elements);
# lists of 31 elements give valid meshes whose boundary faces are all
# tagged (mixoct check --surface; elements 8000-8030 split leaves beside
# the notch's floor whose own triangle lists missed it by rounding: 19
# faces untagged before kernels/leaves.c's mx_leaves_meeting).
MIXOCT=${1:?usage: restart_lattice_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"
PY=$(find_python json) || { echo "SKIP: no python3"; exit 77; }
"$PY" "$HERE/make_l_shape.py" "$T/L.off" || bad "make_l_shape.py"
field() { "$PY" -c "import json,sys; print(json.load(open(sys.argv[1])).get(sys.argv[2]))" "$@"; }
: >"$T/empty.txt"
seq 2000 2030 >"$T/list2000.txt"
seq 8000 8030 >"$T/list8000.txt"
for ext in oct octb; do
  expect_exit 0 "the L at -s 5 with a .$ext" "$MIXOCT" -i "$T/L.off" -s 5 --no-features \
    --json -o "$T/a.vtu" --restart "$T/L.$ext"
  tail -1 "$T/out" >"$T/a.json"
  expect_exit 0 "check the mesh written" "$MIXOCT" check "$T/a.vtu" --json
  tail -1 "$T/out" >"$T/ca.json"
  expect_exit 0 "the .$ext re-meshed with an empty list, no -s" "$MIXOCT" remesh -c "$T/L.$ext" \
    -i "$T/L.off" --no-features -l "$T/empty.txt" --json -o "$T/b.vtu"
  tail -1 "$T/out" >"$T/b.json"
  same "$(field "$T/b.json" leaves)" "$(field "$T/a.json" leaves)" ".$ext: the file's leaves"
  same "$(field "$T/b.json" elements)" "$(field "$T/a.json" elements)" ".$ext: the file's elements"
  expect_exit 0 "check the re-meshed mesh" "$MIXOCT" check "$T/b.vtu" --json
  tail -1 "$T/out" >"$T/cb.json"
  same "$(field "$T/cb.json" mesh_hash)" "$(field "$T/ca.json" mesh_hash)" ".$ext: the mesh written with the file"
  for first in 2000 8000; do
    expect_exit 0 "the .$ext re-meshed with elements $first-$((first + 30)) listed" "$MIXOCT" \
      remesh -c "$T/L.$ext" -i "$T/L.off" --no-features -l "$T/list$first.txt" --json \
      -o "$T/c.vtu" -o "$T/c.msh"
    tail -1 "$T/out" >"$T/c.json"
    "$PY" -c "import json,sys; sys.exit(0 if json.load(open(sys.argv[1]))['refined_listed'] > 0 else 1)" \
      "$T/c.json" && ok ".$ext: leaves split" || bad ".$ext: no leaf split ($(head -c 300 "$T/c.json"))"
    for e in vtu msh; do
      expect_exit 0 "check its .$e against the L" "$MIXOCT" check "$T/c.$e" --surface "$T/L.off"
    done
  done
done
# A local re-mesh from the .octb (the binding, remesh_full=-1: local or
# nothing): the file's states say inside or outside, the patch's also say
# on the surface (MX_NODE_ON); the splice compares the shared nodes as
# inside or not, and takes the patch (it refused it before: remesh_local 0),
# the same mesh as a full re-mesh.
NPY=$(find_python numpy) || NPY=
BUILD=$(cd "$(dirname "$MIXOCT")" && pwd)
if [ -n "$NPY" ] && [ -d "$BUILD/python/mixoct" ]; then
  PYTHONPATH="$BUILD/python" "$NPY" - "$T/L.off" "$T/L.octb" >"$T/py" 2>&1 <<'EOS'
import sys
import numpy as np
import mixoct
meshes = {}
for full in (-1, True):
    m = mixoct.Mesher(remesh_full=full)
    m.add_surface(sys.argv[1])
    m.set_features(angle=0)
    m.load_restart(sys.argv[2], elements=list(range(5000, 5031)))
    a = m.arrays()
    meshes[full] = (m.stats()["remesh_local"], np.array(a["nodes"]), np.array(a["conn"]))
local, x1, c1 = meshes[-1]
_, x2, c2 = meshes[True]
print("local", local, "same", np.array_equal(x1, x2) and np.array_equal(c1, c2))
EOS
  has "$T/py" "local 1 same True" "a local re-mesh from the .octb, the full re-mesh's mesh"
else
  echo "skip: the binding (no numpy or no build/python)"
fi
echo "$fails failure(s)"
[ "$fails" -eq 0 ]
