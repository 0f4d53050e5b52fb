#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# `mixoct check` with feature distances (issue 29, item 5;
# src/verify/check_features.c): the ridges and corners of the surface (at
# --feature-angle, default 30) or of a polylines file (--features), their
# distance to the mesh's boundary edges and nodes, reported, and a defect
# with --feature-tol. The files (python3 writes them): the unit cube as a
# surface (each side 3 x 3 squares, 2 triangles each), as hexahedra (4 x 4
# x 4: the cube's edges are boundary edges, its corners nodes), the cube's
# 12 edges as polylines (two closed squares and four segments), and the same
# hexahedra with their nodes pulled halfway to the sphere around the cube
# (rounded: the corners 0.5 (sqrt 3 - 1) / 2 = 0.183 inside along the
# diagonal, the edges' midpoints 0.5 (sqrt 2 - 1) / 2 = 0.1036 inside).
# Derived, not recorded: 12 ridges and 8 corners on the cube at 30 degrees,
# none at 95; distances 0 for the cube's own hexahedra; for the rounded one
# the corner distance is 0.18301 (the corner node moved along the diagonal)
# and the ridge distance at least the edge midpoints' 0.10355.
MIXOCT=${1:?usage: check_features_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"
json_ok() { # file, python expression on d, description
  if python3 -c "import json,sys; d=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1]); sys.exit(0 if ($2) else 1)" "$1" 2>/dev/null; then
    ok "$3"; else bad "$3: $(tail -c 600 "$1")"; fi
}

python3 - "$T" <<'EOF'
import math, sys
d = sys.argv[1]

def box(n=3):
    index, verts, tris = {}, [], []
    def vertex(p):
        if p not in index:
            index[p] = len(verts)
            verts.append(p)
        return index[p]
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        for side in (0, 1):
            for i in range(n):
                for j in range(n):
                    q = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0.0, 0.0, 0.0]
                        p[a] = float(side)
                        p[b] = (i + di) / n
                        p[c] = (j + dj) / n
                        q.append(vertex(tuple(p)))
                    t1, t2 = (q[0], q[1], q[2]), (q[0], q[2], q[3])
                    if side == 0:
                        t1, t2 = t1[::-1], t2[::-1]
                    tris += [t1, t2]
    with open(d + "/cube.off", "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(verts), len(tris)))
        f.writelines("%.17g %.17g %.17g\n" % p for p in verts)
        f.writelines("3 %d %d %d\n" % t for t in tris)

def hexes(path, n=4, alpha=0.0):
    """The unit cube as n^3 hexahedra; alpha > 0: the nodes pulled that far
    towards the sphere through the cube's corners... along their ray from
    the centre, to the radius of the box's max norm (a rounded cube)."""
    pts = []
    for k in range(n + 1):
        for j in range(n + 1):
            for i in range(n + 1):
                q = [2.0 * i / n - 1, 2.0 * j / n - 1, 2.0 * k / n - 1]
                m, l = max(abs(x) for x in q), math.sqrt(sum(x * x for x in q))
                s = (1 - alpha) + alpha * (m / l if l > 0 else 1.0)
                pts.append(tuple(0.5 + 0.5 * x * s for x in q))
    vid = lambda i, j, k: (k * (n + 1) + j) * (n + 1) + i
    cells = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                cells.append((vid(i, j, k), vid(i + 1, j, k), vid(i + 1, j + 1, k), vid(i, j + 1, k),
                              vid(i, j, k + 1), vid(i + 1, j, k + 1), vid(i + 1, j + 1, k + 1),
                              vid(i, j + 1, k + 1)))
    with open(path, "w") as f:
        f.write("# vtk DataFile Version 3.0\nhexahedra\nASCII\nDATASET UNSTRUCTURED_GRID\n")
        f.write("POINTS %d double\n" % len(pts))
        f.writelines("%.17g %.17g %.17g\n" % p for p in pts)
        f.write("CELLS %d %d\n" % (len(cells), 9 * len(cells)))
        f.writelines("8 " + " ".join(map(str, c)) + "\n" for c in cells)
        f.write("CELL_TYPES %d\n" % len(cells))
        f.writelines("12\n" for c in cells)

box()
hexes(d + "/cube.vtk")
hexes(d + "/round.vtk", alpha=0.5)
with open(d + "/cube.polylines.txt", "w") as f:
    f.write("# the unit cube's edges\n")
    f.write("5 0 0 0 1 0 0 1 1 0 0 1 0 0 0 0\n\n5 0 0 1 1 0 1 1 1 1 0 1 1 0 0 1\n")
    for x, y in ((0, 0), (1, 0), (1, 1), (0, 1)):
        f.write("2 %d %d 0 %d %d 1\n" % (x, y, x, y))
with open(d + "/bad.polylines.txt", "w") as f:
    f.write("# fine, then a point too few\n2 0 0 0 1 1 1\n3 0 0 0 1 1 1\n")
EOF

# the cube's own hexahedra: the features on the boundary exactly
expect_exit 0 "cube hexahedra against cube.off" "$MIXOCT" check "$T/cube.vtk" --surface "$T/cube.off"
has "$T/out" "features  *12 ridges, 8 corners; ridge distance 0 (0 of the diagonal), corner distance 0 (0 of the diagonal)" "12 ridges and 8 corners found on the surface at distance 0"
has "$T/out" "found on the surface at 30 degrees" "the default angle, 30"
has "$T/out" "OK, no defect" "no defect"
expect_exit 0 "the same, --json" "$MIXOCT" check "$T/cube.vtk" --surface "$T/cube.off" --json
json_ok "$T/out" "d['features']['ridges'] == 12 and d['features']['corners'] == 8 and d['features']['ridge_dist'] == 0 and d['features']['corner_dist'] == 0 and d['features']['source'] == 'surface' and d['features']['off'] == 0 and d['features']['tolerance'] is None and abs(d['features']['length'] - 12) < 1e-12 and d['defects'] == 0" "JSON: 12 ridges, 8 corners, distances 0, length 12"
expect_exit 0 "--feature-tol 1e-9" "$MIXOCT" check "$T/cube.vtk" --surface "$T/cube.off" --feature-tol 1e-9
has "$T/out" "features off  *0" "no feature off"
expect_exit 0 "--feature-angle 95: no features" "$MIXOCT" check "$T/cube.vtk" --surface "$T/cube.off" --feature-angle 95 --json
json_ok "$T/out" "d['features']['ridges'] == 0 and d['features']['corners'] == 0 and d['features']['ridge_dist'] is None" "at 95 degrees: no ridge, no corner"
expect_exit 0 "--feature-angle 0: not measured" "$MIXOCT" check "$T/cube.vtk" --surface "$T/cube.off" --feature-angle=0 --json
json_ok "$T/out" "d['features'] is None" "at 0: \"features\": null"
expect_exit 0 "--features cube.polylines.txt" "$MIXOCT" check "$T/cube.vtk" --features "$T/cube.polylines.txt" --json
json_ok "$T/out" "d['features']['ridges'] == 12 and d['features']['corners'] == 8 and d['features']['ridge_dist'] == 0 and d['features']['corner_dist'] == 0 and d['features']['source'].endswith('cube.polylines.txt') and abs(d['features']['diagonal'] - 3 ** 0.5) < 1e-12" "polylines: 12 ridges, 8 corners, distance 0, the mesh's diagonal"
expect_exit 0 "no surface, no features file: nothing measured" "$MIXOCT" check "$T/cube.vtk" --json
json_ok "$T/out" "d['features'] is None" "without surface: \"features\": null"

# rounded: away from the features, reported, a defect only with --feature-tol
expect_exit 0 "rounded hexahedra against the cube's polylines" "$MIXOCT" check "$T/round.vtk" --features "$T/cube.polylines.txt" --json
json_ok "$T/out" "abs(d['features']['corner_dist_abs'] - 0.5 * (3 ** 0.5 - 1) / 2) < 1e-9 and d['features']['ridge_dist_abs'] >= 0.5 * (2 ** 0.5 - 1) / 2 - 1e-9 and d['features']['off'] == 0 and d['defects'] == 0" "rounded: corner distance 0.183, ridge distance 0.1036 or more, no defect"
expect_exit 5 "rounded, --feature-tol 0.01" "$MIXOCT" check "$T/round.vtk" --features "$T/cube.polylines.txt" --feature-tol 0.01
has "$T/out" "features off  *2" "both distances off"
has "$T/out" "result  *2 defects" "2 defects"
expect_exit 5 "rounded, --feature-tol 0.01 --json" "$MIXOCT" check "$T/round.vtk" --features "$T/cube.polylines.txt" --feature-tol=0.01 --json
json_ok "$T/out" "d['features']['off'] == 2 and d['defects'] == 2 and d['features']['tolerance'] == 0.01" "JSON: off 2, defects 2"
expect_exit 0 "rounded, --feature-tol 0.2" "$MIXOCT" check "$T/round.vtk" --features "$T/cube.polylines.txt" --feature-tol 0.2

# the mesher's own cube: reported (how far depends on the mesher)
expect_exit 0 "mesh cube.off at -s 3" "$MIXOCT" -i "$T/cube.off" -s 3 -o "$T/m.vtu" --quiet
expect_exit 0 "check it with its surface" "$MIXOCT" check "$T/m.vtu" --surface "$T/cube.off" --json
json_ok "$T/out" "d['features']['ridges'] == 12 and d['features']['corners'] == 8 and d['features']['ridge_dist'] >= 0 and d['features']['corner_dist'] >= 0" "the mesher's cube: 12 ridges, 8 corners measured"

# bad input
expect_exit 2 "a bad polylines file" "$MIXOCT" check "$T/cube.vtk" --features "$T/bad.polylines.txt"
has "$T/err" "bad.polylines.txt:3:" "the message names the file and line"
expect_exit 2 "a missing polylines file" "$MIXOCT" check "$T/cube.vtk" --features "$T/none.txt"
has "$T/err" "none.txt" "the missing file is named"
expect_exit 2 "--feature-angle 180" "$MIXOCT" check "$T/cube.vtk" --surface "$T/cube.off" --feature-angle 180
expect_exit 2 "--feature-angle x" "$MIXOCT" check "$T/cube.vtk" --feature-angle x
expect_exit 2 "--feature-tol 0" "$MIXOCT" check "$T/cube.vtk" --feature-tol 0
expect_exit 2 "--features without a file" "$MIXOCT" check "$T/cube.vtk" --features

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
