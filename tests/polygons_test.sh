#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# Surfaces made of polygons, end to end (io/polygon_split.c): closed
# polyhedra with non-convex faces (an L-shaped prism, a notched cube, a star
# prism) mesh with exit 0 and `mixoct check --surface` accepts the mesh with
# the surface's volume; a non-planar face is split with a warning naming it;
# a face that crosses itself is refused naming it; the defects of an open
# surface made of polygons are named by face, triangle and line. The
# surfaces are written by python3.
MIXOCT=${1:?usage: polygons_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"

python3 - "$T" <<'EOF'
import math, sys
d = sys.argv[1]

def prism(name, xy, h, drop_top=False, move=None):
    """The profile xy (counter-clockwise) from z = 0 to h: the bottom from
    its last corner (the old fan from there crossed the outside), the top,
    the sides; move = (vertex, (x, y, z)) displaces one vertex."""
    n = len(xy)
    v = [(x, y, 0.0) for x, y in xy] + [(x, y, h) for x, y in xy]
    if move:
        v[move[0]] = move[1]
    f = [list(range(n - 1, -1, -1))]
    if not drop_top:
        f.append([n + i for i in range(n)])
    f += [[i, (i + 1) % n, (i + 1) % n + n, i + n] for i in range(n)]
    with open(f"{d}/{name}", "w") as o:
        o.write(f"OFF\n{len(v)} {len(f)} 0\n")
        for p in v:
            o.write("%.17g %.17g %.17g\n" % p)
        for face in f:
            o.write(" ".join(map(str, [len(face)] + face)) + "\n")

L = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
prism("lprism.off", L, 1.0)
prism("lopen.off", L, 1.0, drop_top=True)
prism("notched.off", [(0, 0), (3, 0), (3, 3), (2, 3), (2, 2), (1, 2), (1, 3), (0, 3)], 3.0)
star = [((0.8 if i % 2 else 2.0) * math.cos(math.pi / 2 + i * math.pi / 5),
         (0.8 if i % 2 else 2.0) * math.sin(math.pi / 2 + i * math.pi / 5)) for i in range(10)]
prism("star.off", star, 1.0)
# the unit cube of quads with corner (1, 1, 1) raised: its top is not planar
prism("raised.off", [(0, 0), (1, 0), (1, 1), (0, 1)], 1.0, move=(6, (1, 1, 1.5)))
EOF
# the L prism's bottom (line 15) as a hexagon that crosses itself
sed '15s/.*/6 5 4 3 1 2 0/' "$T/lprism.off" >"$T/lcross.off"

# mesh, then check against the surface: exit 0, no defect, the volume
mesh_and_check() { # file, level, surface volume, what
  expect_exit 0 "$4 meshes" "$MIXOCT" -i "$T/$1" -s "$2" -o "$T/$1.vtu"
  "$MIXOCT" check "$T/$1.vtu" --surface "$T/$1" --json >"$T/check.json" 2>"$T/check.err"
  local rc=$?
  [ -s "$T/check.json" ] && tail -1 "$T/check.json" | python3 -c '
import json, sys
d = json.load(sys.stdin)
assert d["defects"] == 0, d
assert d["surface_open_edges"] == 0, d
assert abs(d["surface_volume"] - float(sys.argv[1])) < 1e-9 * float(sys.argv[1]), d["surface_volume"]
print("  surface volume %.12g, mesh volume %.12g" % (d["surface_volume"], d["volume"]))
' "$3" && [ $rc -eq 0 ] && ok "$4: check --surface passes, surface volume $3" ||
    { bad "$4: check --surface (exit $rc)"; cat "$T/check.err"; }
}

mesh_and_check lprism.off 4 3 "L-shaped prism (two non-convex hexagons)"
mesh_and_check notched.off 3 24 "notched cube (two non-convex octagons)"
mesh_and_check star.off 4 "$(python3 -c 'import math; print(repr(5 * 2.0 * 0.8 * math.sin(math.pi / 5)))')" \
  "star prism (two 10-gons, 5 reflex corners each)"
mesh_and_check raised.off 3 "$(python3 -c 'print(repr(1 + 1 / 6))')" "cube with a non-planar top"
has "$T/err" "raised.off:12: face 1 is not planar" "the non-planar face is named with its line"

expect_exit 2 "a face that crosses itself is refused" "$MIXOCT" -i "$T/lcross.off" -s 3 -o "$T/x.vtu"
has "$T/err" "lcross.off:15: face 0: a polygon of 6 corners crosses or touches itself" \
  "the crossing face is named with its line"
absent "$T/x.vtu" "nothing written for a refused surface"

expect_exit 2 "an open surface of polygons is refused" "$MIXOCT" -i "$T/lopen.off" -s 3 -o "$T/x.vtu"
has "$T/err" "6 open edges (used by one triangle only), e.g. edge of face 1 (triangle 2 of 2, line 16)" \
  "its open edges are named by face, triangle within the face and line"

[ $fails -eq 0 ] && echo "polygons: all passed" || echo "polygons: $fails failed"
exit $((fails > 0))
