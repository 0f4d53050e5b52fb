#!/usr/bin/env bash
# Other programs read mixoct's files (issue 5, item 7): the built-in demo is
# meshed into every output format (.vtk binary and ASCII, .vtu, .msh binary
# and ASCII, .mesh and .meshb when their writer exists) and each file is
# read back by
#   gmsh          .msh (and .mesh, .vtk): node and element counts, and the
#                 minimum Jacobian determinant of its AnalyseMeshQuality
#                 plugin (> 0: every element positive in Gmsh's convention);
#   python3 meshio  every format: counts, and signed volumes per element;
#   python3 vtk     .vtk and .vtu: counts, and vtkCellSizeFilter volumes.
# Counts must equal those mixoct reports in --json (nodes, elements, by_type).
#
# Debian packages: gmsh python3-meshio python3-vtk9 python3-numpy.
# A missing reader prints "SKIP <reader> not installed"; when the
# environment variable CI is set, a missing reader is a failure instead.
# GMSH=path picks another gmsh, PYTHON=path a python3 tried first.
#
# Prism orientation: mixoct's prisms have the triangle 0-1-2 turning
# counter-clockwise seen from 3-4-5 (Gmsh's reference prism); VTK's wedge is
# the other way round (vtkWedge's documentation, vtkCellSizeFilter, ParaView),
# so the VTK writers write prisms as 0,2,1,3,5,4 (src/soa/mesh.h,
# mx_vtk_order) and VTK and meshio see them positive. Gmsh's own VTK reader
# does not reorder wedges, so in Gmsh the prisms of a .vtk file look
# inverted: for .vtk files read by Gmsh only the counts are compared (a NOTE
# says so). Any element with a volume <= 0 elsewhere is a failure.
MIXOCT=${1:?usage: external_readers_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fails=$((fails + 1)); }
missing() { # reader description
  if [ -n "${CI:-}" ]; then
    bad "$1 not installed (CI is set: every reader is required)"
  else
    echo "SKIP $1 not installed"
  fi
}

# A python3 that can import the given modules ($PYTHON first, then the
# system's, then the one on PATH).
find_python() {
  local py
  for py in ${PYTHON:-} /usr/bin/python3 python3; do
    command -v "$py" >/dev/null 2>&1 || continue
    if "$py" -c "import $1" >/dev/null 2>&1; then
      echo "$py"
      return 0
    fi
  done
  return 1
}
JSON_PY=$(find_python json) || { echo "FAIL no python3 to read the JSON summary"; exit 1; }

# ---- 1. mesh the demo into every format ---------------------------------------
# name:extension:options
FORMATS="vtk_bin:vtk: vtk_ascii:vtk:--ascii vtu:vtu: msh_bin:msh: msh_ascii:msh:--ascii mesh:mesh: meshb:meshb:"
EXPECT=""   # "nodes=N tet=a pyramid=b prism=c hex=d"
ELEMENTS=""
FILES=()
for spec in $FORMATS; do
  IFS=: read -r name ext opt <<<"$spec"
  out="$T/demo_$name.$ext"
  "$MIXOCT" --demo -s 4 -o "$out" $opt --json >"$T/run.out" 2>"$T/run.err"
  code=$?
  if [ "$code" -ne 0 ] && grep -q "not available yet" "$T/run.err"; then
    echo "SKIP .$ext writer not available yet ($(tail -n 1 "$T/run.err"))"
    continue
  fi
  if [ "$code" -ne 0 ] || [ ! -s "$out" ]; then
    bad "mixoct --demo -o $(basename "$out") $opt: exit $code"
    cat "$T/run.err"
    continue
  fi
  counts=$(tail -n 1 "$T/run.out" | "$JSON_PY" -c '
import json, sys
j = json.load(sys.stdin)
b = j["by_type"]
assert j["elements"] == b["tet"] + b["pyramid"] + b["prism"] + b["hex"]
print("nodes=%d tet=%d pyramid=%d prism=%d hex=%d" % (j["nodes"], b["tet"], b["pyramid"], b["prism"], b["hex"]))
print(j["elements"])') || { bad "$name: cannot read the --json summary"; continue; }
  c=$(echo "$counts" | head -n 1)
  if [ -z "$EXPECT" ]; then
    EXPECT=$c
    ELEMENTS=$(echo "$counts" | tail -n 1)
    echo "mixoct --json: $EXPECT (elements $ELEMENTS)"
  elif [ "$c" != "$EXPECT" ]; then
    bad "$name: mixoct reported '$c', earlier runs '$EXPECT'"
  fi
  FILES+=("$out")
done
[ -n "$EXPECT" ] || { echo "FAIL no file written"; exit 1; }

compare() { # reader file got [want]
  local want=${4:-$EXPECT}
  if [ "$3" = "$want" ]; then ok "$1 $(basename "$2"): $3"; else bad "$1 $(basename "$2"): read '$3', mixoct reported '$want'"; fi
}
# The expected counts without the types a reader cannot see.
expect_only() { # types...
  local s="" kv
  for kv in $EXPECT; do
    case " nodes $* " in *" ${kv%%=*} "*) s="$s $kv" ;; esac
  done
  echo "${s# }"
}

# ---- 2. gmsh --------------------------------------------------------------------
GMSH=${GMSH:-gmsh} # another gmsh, or a missing one to test the SKIP/CI logic
if command -v "$GMSH" >/dev/null 2>&1; then
  echo "gmsh: $("$GMSH" --version 2>&1 | tail -n 1) ($(command -v "$GMSH"))"
  for f in "${FILES[@]}"; do
    case "$f" in *.msh | *.mesh | *.vtk) ;; *) continue ;; esac
    cat >"$T/count.geo" <<EOF
Merge "$f";
Plugin(AnalyseMeshQuality).JacobianDeterminant = 1;
Plugin(AnalyseMeshQuality).IGEMeasure = 0;
Plugin(AnalyseMeshQuality).ICNMeasure = 0;
Plugin(AnalyseMeshQuality).CreateView = 0;
Plugin(AnalyseMeshQuality).Recompute = 1;
Plugin(AnalyseMeshQuality).DimensionOfElements = 3;
Plugin(AnalyseMeshQuality).Run;
Printf("COUNTS nodes=%g tet=%g pyramid=%g prism=%g hex=%g", Mesh.NbNodes, Mesh.NbTetrahedra, Mesh.NbPyramids, Mesh.NbPrisms, Mesh.NbHexahedra);
EOF
    timeout 300 "$GMSH" -nopopup "$T/count.geo" - >"$T/gmsh.raw" 2>&1
    code=$?
    tr '\r' '\n' <"$T/gmsh.raw" >"$T/gmsh.log" # progress lines end in \r
    got=$(sed -n 's/^COUNTS //p' "$T/gmsh.log" | tail -n 1)
    if [ "$code" -ne 0 ] || [ -z "$got" ] || grep -q "^Error" "$T/gmsh.log"; then
      bad "gmsh $(basename "$f"): exit $code"
      grep -E "Error|COUNTS" "$T/gmsh.log" | head -n 5
      continue
    fi
    case "$f" in
      *.mesh)
        # Gmsh 4.8's Medit reader reads Vertices, Tetrahedra, Hexahedra,
        # Triangles and Quadrilaterals only; its node count is the one it
        # reads (Mesh.NbNodes leaves out nodes of elements it skipped).
        read_nodes=$(sed -n 's/^Info *: \([0-9]*\) nodes$/\1/p' "$T/gmsh.log" | head -n 1)
        got="nodes=$read_nodes $(echo "$got" | sed 's/^nodes=[0-9]* //')"
        npyr=$(echo "$got" | sed 's/.*pyramid=\([0-9]*\).*/\1/')
        if [ "$npyr" = 0 ]; then
          echo "NOTE gmsh $(basename "$f"): this Gmsh's Medit reader skips Prisms and Pyramids; comparing nodes, tetrahedra and hexahedra"
          got=$(echo "$got" | sed 's/ pyramid=[0-9]*//; s/ prism=[0-9]*//')
          compare gmsh "$f" "$got" "$(expect_only tet hex)"
        else
          compare gmsh "$f" "$got"
        fi
        ;;
      *) compare gmsh "$f" "$got" ;;
    esac
    minj=$(sed -n 's/^Info *: minJ *= *\([-0-9.e+]*\),.*/\1/p' "$T/gmsh.log" | head -n 1)
    if [ "${f##*.}" = vtk ]; then
      echo "NOTE gmsh $(basename "$f"): Gmsh's VTK reader keeps VTK wedges in Gmsh's prism order, so their Jacobians are not compared (smallest $minj)"
    elif [ -z "$minj" ]; then
      bad "gmsh $(basename "$f"): no Jacobian report"
    elif "$JSON_PY" -c "import sys; sys.exit(0 if float('$minj') > 0 else 1)"; then
      ok "gmsh $(basename "$f"): smallest Jacobian determinant $minj > 0"
    else
      bad "gmsh $(basename "$f"): smallest Jacobian determinant $minj <= 0"
    fi
  done
else
  missing gmsh
fi

# ---- shared Python: signed volumes by type -------------------------------------
# Each element is cut into tetrahedra listed in VTK's node order; with VTK's
# parametric coordinates (and Gmsh's reference elements) every one of them
# has a positive volume, so a valid element has a positive sum. For wedges
# VTK's documentation takes the other orientation: their sign is reported.
cat >"$T/volumes.py" <<'EOF'
import numpy as np

DECOMP = {
    "tetra": [(0, 1, 2, 3)],
    "pyramid": [(0, 1, 2, 4), (0, 2, 3, 4)],
    "wedge": [(0, 1, 2, 3), (1, 2, 3, 4), (2, 3, 4, 5)],
    "hexahedron": [(0, 1, 3, 4), (1, 2, 3, 6), (1, 4, 5, 6), (3, 4, 6, 7), (1, 3, 4, 6)],
}

def signed_volumes(points, kind, conn):
    p = np.asarray(points, dtype=float)
    conn = np.asarray(conn)
    vol = np.zeros(len(conn))
    for a, b, c, d in DECOMP[kind]:
        pa = p[conn[:, a]]
        u, v, w = p[conn[:, b]] - pa, p[conn[:, c]] - pa, p[conn[:, d]] - pa
        vol += np.einsum("ij,ij->i", np.cross(u, v), w) / 6.0
    return vol

def verdict(kind, vol, name):
    """Lines 'ok ...' / 'FAIL ...' / 'NOTE ...' about one type's volumes."""
    n = len(vol)
    if n == 0:
        return []
    pos, neg = int((vol > 0).sum()), int((vol < 0).sum())
    rng = "min %.6g max %.6g" % (vol.min(), vol.max())
    if pos == n:
        return ["ok   %s: %d %s volumes > 0 (%s)" % (name, n, kind, rng)]
    if kind == "wedge" and neg == n:
        return ["NOTE %s: all %d wedge volumes < 0 (%s)" % (name, n, rng)]
    return ["FAIL %s: %d of %d %s volumes <= 0 (%s)" % (name, n - pos, n, kind, rng)]
EOF

# The volume verdicts printed by the Python checks. "FAIL" lines fail.
# "NOTE" lines say every wedge of a file is negative in the reader's
# convention: a failure for .msh, .vtk and .vtu (whose prism orders Gmsh and
# VTK define); for other formats reported as is.
volume_lines() { # file log
  local line
  while IFS= read -r line; do
    case "$line" in
      ok*) echo "$line" ;;
      FAIL*) bad "${line#FAIL }" ;;
      NOTE*)
        case "$1" in
          *.msh) bad "${line#NOTE }" ;;
          *.vtk | *.vtu) bad "${line#NOTE }" ;;
          *) echo "$line" ;;
        esac ;;
    esac
  done < <(grep -E '^(ok|NOTE|FAIL)' "$2")
}

# ---- 3. meshio -----------------------------------------------------------------
cat >"$T/meshio_check.py" <<'EOF'
import sys, warnings
warnings.simplefilter("ignore")
import meshio
from volumes import signed_volumes, verdict
m = meshio.read(sys.argv[1])
name = "meshio " + sys.argv[1].rsplit("/", 1)[-1]
count = {"tetra": 0, "pyramid": 0, "wedge": 0, "hexahedron": 0}
blocks = {k: [] for k in count}
for c in m.cells:
    if c.type in count:
        count[c.type] += len(c.data)
        blocks[c.type].append(c.data)
print("COUNTS nodes=%d tet=%d pyramid=%d prism=%d hex=%d" % (
    len(m.points), count["tetra"], count["pyramid"], count["wedge"], count["hexahedron"]))
import numpy as np
for kind, parts in blocks.items():
    if parts:
        for line in verdict(kind, signed_volumes(m.points, kind, np.concatenate(parts)), name):
            print(line)
EOF
MESHIO_PY=$(find_python "meshio, numpy")
if [ -n "$MESHIO_PY" ]; then
  echo "meshio: $("$MESHIO_PY" -c 'import meshio; print(meshio.__version__)') ($MESHIO_PY)"
  for f in "${FILES[@]}"; do
    (cd "$T" && timeout 300 "$MESHIO_PY" meshio_check.py "$f") >"$T/meshio.log" 2>&1
    code=$?
    got=$(sed -n 's/^COUNTS //p' "$T/meshio.log")
    if [ "$code" -ne 0 ] || [ -z "$got" ]; then
      bad "meshio $(basename "$f"): exit $code"
      tail -n 5 "$T/meshio.log"
      continue
    fi
    compare meshio "$f" "$got"
    volume_lines "$f" "$T/meshio.log"
  done
else
  missing "python3 meshio (Debian: python3-meshio python3-numpy)"
fi

# ---- 4. VTK --------------------------------------------------------------------
cat >"$T/vtk_check.py" <<'EOF'
import os, sys
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy
from volumes import signed_volumes, verdict
path = sys.argv[1]
name = "vtk " + path.rsplit("/", 1)[-1]
if path.endswith(".vtu"):
    r = vtk.vtkXMLUnstructuredGridReader()
else:
    r = vtk.vtkUnstructuredGridReader()
r.SetFileName(path)
r.Update()
g = r.GetOutput()
types = vtk_to_numpy(g.GetCellTypesArray()) if g.GetNumberOfCells() else np.zeros(0)
kinds = {10: "tetra", 14: "pyramid", 13: "wedge", 12: "hexahedron"}
n = {k: int((types == t).sum()) for t, k in kinds.items()}
print("COUNTS nodes=%d tet=%d pyramid=%d prism=%d hex=%d" % (
    g.GetNumberOfPoints(), n["tetra"], n["pyramid"], n["wedge"], n["hexahedron"]))
if int(sum(n.values())) != g.GetNumberOfCells():
    print("FAIL %s: %d cells of other types" % (name, g.GetNumberOfCells() - sum(n.values())))
# volumes from vtkCellSizeFilter, VTK's own convention per cell type
f = vtk.vtkCellSizeFilter()
f.SetInputData(g)
f.ComputeVolumeOn()
f.Update()
vol = vtk_to_numpy(f.GetOutput().GetCellData().GetArray("Volume"))
for t, kind in kinds.items():
    for line in verdict(kind, vol[types == t], name + " vtkCellSizeFilter"):
        print(line)
EOF
VTK_PY=$(find_python "vtk, numpy")
if [ -n "$VTK_PY" ]; then
  echo "vtk: $("$VTK_PY" -c 'import vtk; print(vtk.vtkVersion.GetVTKVersion())') ($VTK_PY)"
  for f in "${FILES[@]}"; do
    case "$f" in *.vtk | *.vtu) ;; *) continue ;; esac
    (cd "$T" && timeout 300 "$VTK_PY" vtk_check.py "$f") >"$T/vtk.log" 2>&1
    code=$?
    got=$(sed -n 's/^COUNTS //p' "$T/vtk.log")
    if [ "$code" -ne 0 ] || [ -z "$got" ]; then
      bad "vtk $(basename "$f"): exit $code"
      tail -n 5 "$T/vtk.log"
      continue
    fi
    compare vtk "$f" "$got"
    volume_lines "$f" "$T/vtk.log"
  done
else
  missing "python3 vtk (Debian: python3-vtk9 python3-numpy)"
fi

if [ "$fails" -eq 0 ]; then
  echo "external readers: all checks passed"
else
  echo "external readers: $fails check(s) failed"
fi
[ "$fails" -eq 0 ]
