#!/usr/bin/env bash
# Sharp features side by side (issue 29): mixoct, CGAL's Mesh_3 with
# features (bench/cgal/mesh3_features.cpp, built here with g++ against
# Debian's libcgal-dev) and Gmsh's STL remeshing with a feature angle
# (ClassifySurfaces at 30 degrees, CreateGeometry, a volume, Mesh 3), on
# the shapes of tests/make_feature_shapes.py. Every result is read by
# `mixoct check --surface` (Gmsh's .msh through meshio to an ASCII .vtk): elements,
# seconds (the mesher's run), worst J_ENS, ridge and corner distances over
# the diagonal, volume error. Sizes: mixoct -s LEVEL (default 5); CGAL and
# Gmsh at the diagonal over SIZE_DIV (default 40), about mixoct's surface
# elements at -s 5 on these shapes. Figures, not assertions.
#
#   bench/features_compare.sh MIXOCT [LEVEL] [SIZE_DIV]
set -u
MIXOCT=$1
LEVEL=${2:-5}
DIV=${3:-40}
PY=/usr/bin/python3
HERE=$(cd "$(dirname "$0")" && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$PY" "$HERE/../tests/make_feature_shapes.py" "$T" >/dev/null
CGAL=""
if g++ -O2 -DNDEBUG -std=c++17 "$HERE/cgal/mesh3_features.cpp" -o "$T/mesh3_features" -lgmp -lmpfr 2>/dev/null; then
  CGAL="$T/mesh3_features"
fi
figures() { # MESH SURFACE SECONDS: the row's figures
  "$MIXOCT" check "$1" --surface "$2" --json --quiet 2>/dev/null | "$PY" -c "
import json, sys
d = json.load(sys.stdin)
f = d.get('features') or {}
g = lambda x: '-' if x is None else '%.2g' % x
print('%8d %7s %6.3f %9s %9s %9s' % (d.get('elements', 0), '$3',
      d['jens_min'], g(f.get('ridge_dist')), g(f.get('corner_dist')), g(d.get('volume_error'))))" 2>/dev/null || echo "   (no mesh)"
}
secs() { "$PY" -c "print('%.2f' % ($2 - $1))"; }
printf '%-10s %-7s %8s %7s %6s %9s %9s %9s\n' shape mesher elements seconds jmin ridge corner volume
for s in lbracket wedge tet cylinder step; do
  f="$T/$s.off"
  h=$("$PY" -c "
tok = open('$f').read().split(); nv = int(tok[1])
v = [[float(x) for x in tok[4 + 3 * i:7 + 3 * i]] for i in range(nv)]
import math
print(math.dist([min(p[a] for p in v) for a in range(3)], [max(p[a] for p in v) for a in range(3)]) / $DIV)")
  rm -f "$T/m.vtu" "$T/c.mesh" "$T/g.stl" "$T/g.msh" "$T/g.vtk" # no stale result read
  t0=$(date +%s.%N); "$MIXOCT" -i "$f" -s "$LEVEL" -o "$T/m.vtu" --quiet 2>/dev/null; t1=$(date +%s.%N)
  printf '%-10s %-7s %s\n' "$s" mixoct "$(figures "$T/m.vtu" "$f" "$(secs "$t0" "$t1")")"
  if [ -n "$CGAL" ]; then
    t0=$(date +%s.%N); timeout -k 10 300 "$CGAL" "$f" "$T/c.mesh" "$h" 30 >/dev/null 2>&1; t1=$(date +%s.%N)
    printf '%-10s %-7s %s\n' "$s" cgal "$(figures "$T/c.mesh" "$f" "$(secs "$t0" "$t1")")"
  fi
  if command -v gmsh >/dev/null; then
    "$PY" -c "import meshio; m = meshio.read('$f'); meshio.write('$T/g.stl', m)" 2>/dev/null
    cat >"$T/g.geo" <<GEO
Merge "$T/g.stl";
ClassifySurfaces{30 * Pi / 180, 1, 1, Pi};
CreateGeometry;
Surface Loop(1) = Surface{:};
Volume(1) = {1};
Mesh.MeshSizeMax = $h;
GEO
    t0=$(date +%s.%N); timeout -k 10 300 gmsh "$T/g.geo" -3 -format msh22 -o "$T/g.msh" >/dev/null 2>&1; t1=$(date +%s.%N)
    "$PY" -c "
import meshio
m = meshio.read('$T/g.msh')
m = meshio.Mesh(m.points, [c for c in m.cells if c.type == 'tetra'])
meshio.write('$T/g.vtk', m, binary=False)" 2>/dev/null
    printf '%-10s %-7s %s\n' "$s" gmsh "$(figures "$T/g.vtk" "$f" "$(secs "$t0" "$t1")")"
  fi
done
