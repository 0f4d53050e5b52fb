#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# The boundary faces of the written tags (mesher/output.c, make_tags) looked
# for among the faces of outside and MX_NODE_ON nodes (the boundary stage's
# inside nodes on the surface, kernels/boundary.h) give the same files as
# the leaves' rule (every node of a leaf meeting the input; forced with
# MX_TAG_FACES_LEAVES=1). The L (tests/make_l_shape.py): the unit cube less
# [1/2, 1] x [0, 1] x [1/2, 1], whose inner faces lie in the root's middle
# planes, lattice planes at every level: at -s 5 inside nodes lie exactly
# on them (JSON boundary.on_surface > 0) and some stay on the boundary
# (the files differ when only the outside nodes are taken: tried). The
# cortex at -s 5 when ../shared/data is there.
MIXOCT=${1:?usage: tag_faces_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"
PY=$(find_python json) || { echo "SKIP: no python3"; exit 77; }

"$PY" "$HERE/make_l_shape.py" "$T/L.off" || bad "make_l_shape.py"

compare() { # name, input, level
  expect_exit 0 "$1 -s $3" "$MIXOCT" -i "$2" -s "$3" --no-features --json -o "$T/a.msh" \
    -o "$T/a.vtu"
  tail -1 "$T/out" >"$T/a.json"
  expect_exit 0 "$1 -s $3, the leaves' rule" env MX_TAG_FACES_LEAVES=1 "$MIXOCT" -i "$2" \
    -s "$3" --no-features -o "$T/b.msh" -o "$T/b.vtu"
  for e in msh vtu; do
    if cmp -s "$T/a.$e" "$T/b.$e"; then ok "$1 -s $3: the same .$e"; else bad "$1 -s $3: the .$e files differ"; fi
  done
}

compare "the L" "$T/L.off" 5
if "$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if d['boundary']['on_surface'] > 0 else 1)" "$T/a.json"; then
  ok "the L at -s 5 has inside nodes on the surface"
else
  bad "the L at -s 5: no inside node on the surface ($(head -c 300 "$T/a.json"))"
fi
expect_exit 0 "check the L's .msh against it" "$MIXOCT" check "$T/a.msh" --surface "$T/L.off"
compare "the L" "$T/L.off" 4
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
[ -d "$DATA/surfaces" ] || DATA=$HERE/../../shared/data
CORTEX="$DATA/surfaces/cortex.off"
if [ -f "$CORTEX" ]; then compare "the cortex" "$CORTEX" 5; else echo "skip: $CORTEX not found"; fi

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
