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
# Then the tagged boundaries (issue 11, section 5 below): the demo and three
# spheres (two bodies, one with a cavity) written with their tags and bodies
# are read by the Gmsh Python API (physical groups, ElementData) and by
# meshio (blocks per body, tags per format, closed outward tags); meshio's
# time to read the cortex at -s 7 is printed.
#
# Debian packages: gmsh python3-gmsh python3-meshio python3-vtk9 python3-numpy.
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
. "$(cd "$(dirname "$0")" && pwd)/lib.sh"
missing() { # reader description
  if [ -n "${CI:-}" ]; then
    bad "$1 not installed (CI is set: every reader is required)"
  else
    echo "SKIP $1 not installed"
  fi
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

# ---- 5. tagged boundaries (issue 11) ---------------------------------------------
# Two meshes: the demo (one input: tag 1 "demo", one body) and three spheres,
# -i sphere.off -i inner.off -i right.off (tests/make_surfaces.py's sphere;
# inner.off: the sphere scaled 0.4 about its centre, a cavity; right.off: the
# sphere shifted by x + 3): tags 1 2 3, two bodies (the hollow ball, whose
# boundary is tags 1 and 2, and the right ball). Each is written as .msh
# (binary, and ASCII from a second run), .vtu, .vtk, .mesh, .meshb and
# --boundary .vtu, and read by
#   the Gmsh Python API (python3-gmsh)  both .msh: the physical groups (dim 2
#       tag t named after input t, dim 3 tag b "<file> volume b"), the number
#       of elements in each, element tags 1..N, the ElementData views type,
#       level, jens, body with one value per element, consistent with the
#       elements (a face's values are its element's);
#   meshio  every file: volume blocks grouped by body then type (at most 4
#       per body), counts per (body, type) equal across formats and to
#       --json, the tags (msh: gmsh:physical of the 2D blocks, medit:
#       medit:ref, boundary .vtu: surface_tag) giving the same faces under
#       the same tags in every format, exactly the faces used by one element,
#       each outward; every tag closed (each edge used twice) and oriented;
#       the spheres' tags on their spheres; the VTU/VTK point field
#       surface_tag and cell field body; per body, the volume of its
#       elements against the divergence theorem over its faces.
# The per-group counts of Gmsh and meshio (COUNTS2, COUNTS3 lines) must
# agree, and the bodies' elements add up to mixoct's count. Last, meshio
# reads the cortex meshed at -s 7 (.vtu) and the time is printed (INFO, no
# limit).
cat >"$T/tags_meshio.py" <<'EOF'
"""Tagged boundaries read back by meshio (issue 11): see external_readers_test.sh.

usage: tags_meshio.py JSON NAMES NBODIES SPHERES kind=FILE ...
  JSON     mixoct's --json summary of the run (nodes, by_type)
  NAMES    the input file names, comma-separated, in -i order (tag t = name t)
  NBODIES  the number of bodies expected
  SPHERES  "-" or, per tag, "cx:cy:cz:R" comma-separated: the tag's nodes
           must lie on that sphere (within 2 %)
  kind     msh_bin msh_ascii vtu vtk mesh meshb boundary
Prints ok/FAIL/NOTE lines, then COUNTS2 (faces per tag) and COUNTS3
(elements per body), the lines the Gmsh check prints too."""
import json, sys, time, warnings
warnings.simplefilter("ignore")
import numpy as np
import meshio
from volumes import signed_volumes

VOL = ("tetra", "pyramid", "wedge", "hexahedron")
SURF = ("triangle", "quad")
JSON_KEY = {"tetra": "tet", "pyramid": "pyramid", "wedge": "prism", "hexahedron": "hex"}
# The faces of each volume cell in meshio's (VTK's) node order (to find the
# faces used by one cell only: the volume mesh's own boundary).
FACES = {
    "tetra": [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)],
    "pyramid": [(0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
    "wedge": [(0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0)],
    "hexahedron": [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5),
                   (2, 3, 7, 6), (3, 0, 4, 7)],
}

fails = 0
def ok(msg): print("ok   " + msg)
def bad(msg):
    global fails
    fails += 1
    print("FAIL " + msg)

jpath, names, nbodies, spheres = sys.argv[1:5]
J = json.load(open(jpath))
names = names.split(",")
ntags, nbodies = len(names), int(nbodies)
spheres = None if spheres == "-" else [tuple(map(float, s.split(":"))) for s in spheres.split(",")]
files = dict(a.split("=", 1) for a in sys.argv[5:])

def ints(a):
    a = np.asarray(a)
    return np.rint(a.reshape(len(a), -1)[:, 0]).astype(np.int64)

def keyset(rows):
    rows = np.unique(rows, axis=0) if len(rows) else rows.reshape(0, 4)
    return rows

# ---- read every file ------------------------------------------------------------
M = {}
for kind, path in files.items():
    t0 = time.time()
    try:
        M[kind] = meshio.read(path)
    except Exception as e:  # a reader failure is a check failure
        bad("meshio %s: %s: %s" % (path.rsplit("/", 1)[-1], type(e).__name__, str(e)[:200]))
        continue
    ok("meshio reads %s (%.3f s)" % (path.rsplit("/", 1)[-1], time.time() - t0))
if "msh_bin" not in M:
    bad("no .msh to compare with")
    sys.exit(1)

def base(kind): return files[kind].rsplit("/", 1)[-1]

# ---- volume cells: blocks grouped by body then type ---------------------------
def volume_layout(kind, m):
    """[(type, body array)] per volume block, and the per-cell body array of
    each type in file order."""
    blocks = []
    for i, c in enumerate(m.cells):
        if c.type not in VOL:
            continue
        if kind.startswith("msh"):
            body = ints(m.cell_data["gmsh:physical"][i])
        elif kind in ("mesh", "meshb"):
            body = ints(m.cell_data["medit:ref"][i])
        else:
            body = ints(m.cell_data["body"][i])
        blocks.append((c.type, body, np.asarray(c.data, dtype=np.int64)))
    return blocks

per_body = {}   # kind -> {(body, type): count}
conn_by_type = {}  # kind -> {type: connectivity in file order}
body_by_type = {}
for kind, m in M.items():
    if kind == "boundary":
        continue
    name = "meshio " + base(kind)
    if len(m.points) != J["nodes"]:
        bad("%s: %d nodes, mixoct reported %d" % (name, len(m.points), J["nodes"]))
    blocks = volume_layout(kind, m)
    counts = {}
    seq = []
    for t, body, conn in blocks:
        for b in np.unique(body):
            counts[(int(b), t)] = counts.get((int(b), t), 0) + int((body == b).sum())
        if kind not in ("mesh", "meshb"):
            if len(np.unique(body)) != 1:
                bad("%s: a %s block holds bodies %s" % (name, t, np.unique(body).tolist()))
            seq.append((int(body[0]), VOL.index(t)))
        conn_by_type.setdefault(kind, {}).setdefault(t, []).append(conn)
        body_by_type.setdefault(kind, {}).setdefault(t, []).append(body)
    bodies = sorted({b for b, _ in counts})
    if bodies != list(range(1, nbodies + 1)):
        bad("%s: bodies %s, expected 1..%d" % (name, bodies, nbodies))
    if kind in ("mesh", "meshb"):
        types = [t for t, _, _ in blocks]
        if len(types) != len(set(types)):
            bad("%s: %d volume blocks for %d types" % (name, len(types), len(set(types))))
        else:
            ok("%s: %d volume blocks (one per type; bodies from medit:ref)" % (name, len(types)))
    else:
        nblk = {b: sum(1 for s in seq if s[0] == b) for b in bodies}
        if seq != sorted(set(seq)):
            bad("%s: volume blocks not grouped by body then type: %s" % (name, seq))
        else:
            ok("%s: %d volume blocks, by body %s (at most 4 each, grouped by body then type)"
               % (name, len(seq), nblk))
    for t in VOL:
        n = sum(v for (b, tt), v in counts.items() if tt == t)
        if n != J["by_type"][JSON_KEY[t]]:
            bad("%s: %d %s, mixoct reported %d" % (name, n, t, J["by_type"][JSON_KEY[t]]))
    per_body[kind] = counts

ref = per_body["msh_bin"]
for kind, c in per_body.items():
    if c != ref:
        bad("meshio %s: elements per (body, type) %s, %s has %s" % (base(kind), sorted(c.items()), base("msh_bin"), sorted(ref.items())))
ok("elements per body and type agree across %s: %s" % (
    ", ".join(base(k) for k in per_body),
    "; ".join("body %d: %s" % (b, " ".join("%s %d" % (JSON_KEY[t], ref.get((b, t), 0)) for t in VOL))
              for b in range(1, nbodies + 1))))
# the same cells in the same order in each format (per type)
for kind in conn_by_type:
    for t in VOL:
        a = np.concatenate(conn_by_type[kind].get(t, [np.zeros((0, 1), np.int64)]))
        r = np.concatenate(conn_by_type["msh_bin"].get(t, [np.zeros((0, 1), np.int64)]))
        if a.shape != r.shape or not np.array_equal(a, r):
            bad("meshio %s: the %s differ from %s's (order or nodes)" % (base(kind), t, base("msh_bin")))
            break
    else:
        if kind != "msh_bin":
            ok("meshio %s: the same cells in the same order (per type) as %s" % (base(kind), base("msh_bin")))

# ---- the volume mesh's own boundary (faces used once), from the .msh ---------------
m0 = M["msh_bin"]
P = np.asarray(m0.points, dtype=float)
allf, owner_cell = [], []
vol_conn, vol_fields = [], {k: [] for k in ("type", "level", "jens", "body")}
cell0 = 0
for i, c in enumerate(m0.cells):
    if c.type not in VOL:
        continue
    conn = np.asarray(c.data, dtype=np.int64)
    for k in vol_fields:
        vol_fields[k].append(np.asarray(m0.cell_data[k][i], dtype=float).ravel())
    for f in FACES[c.type]:
        fc = conn[:, f]
        if fc.shape[1] == 3:
            fc = np.hstack([fc, np.full((len(fc), 1), -1)])
        allf.append(fc)
        owner_cell.append(cell0 + np.arange(len(conn)))
    vol_conn.append((c.type, conn))
    cell0 += len(conn)
vol_fields = {k: np.concatenate(v) for k, v in vol_fields.items()}
allf = np.vstack(allf)
owner_cell = np.concatenate(owner_cell)
# keys: node ids sorted, triangles padded with -1 (sorted first)
k = np.sort(allf, axis=1)
_, inv, cnt = np.unique(k, axis=0, return_inverse=True, return_counts=True)
inv = inv.ravel()
if (cnt > 2).any():
    bad("%s: %d faces shared by more than two elements" % (base("msh_bin"), int((cnt > 2).sum())))
once = cnt[inv] == 1
bnd_keys = k[once]
bnd_cell = owner_cell[once]
order = np.lexsort(bnd_keys.T[::-1])
bnd_keys, bnd_cell = bnd_keys[order], bnd_cell[order]
# centroid of each cell, for the orientation check
cent = np.concatenate([P[conn].mean(axis=1) for _, conn in vol_conn])

def lookup(fkeys):
    """Row of each face key in the boundary list, -1 when not a boundary face."""
    if len(fkeys) == 0:
        return np.zeros(0, dtype=np.int64)
    allk = np.vstack([bnd_keys, fkeys])
    u, inv2 = np.unique(allk, axis=0, return_inverse=True)
    inv2 = inv2.ravel()
    pos = np.full(len(u), -1)
    pos[inv2[:len(bnd_keys)]] = np.arange(len(bnd_keys))
    return pos[inv2[len(bnd_keys):]]

# ---- tagged faces per format -----------------------------------------------------
def tagged_faces(kind, m):
    """The boundary faces in file order: conn (n, 4; triangles padded with
    -1), tag (n), and the per-face cell fields the format carries."""
    conn_l, tag_l, fields, seq = [], [], {}, []
    for i, c in enumerate(m.cells):
        if c.type not in SURF:
            continue
        conn = np.asarray(c.data, dtype=np.int64)
        if kind.startswith("msh"):
            tag = ints(m.cell_data["gmsh:physical"][i])
            flist = ("type", "level", "jens", "body")
        elif kind in ("mesh", "meshb"):
            tag = ints(m.cell_data["medit:ref"][i])
            flist = ()
        else:
            tag = ints(m.cell_data["surface_tag"][i])
            conn = ints(m.point_data["node"])[conn]
            flist = ("body",)
        for f in flist:
            fields.setdefault(f, []).append(np.asarray(m.cell_data[f][i], dtype=float).ravel())
        if kind.startswith("msh"):
            if len(np.unique(tag)) != 1:
                bad("meshio %s: a %s block holds tags %s" % (base(kind), c.type, np.unique(tag).tolist()))
            seq.append((int(tag[0]), SURF.index(c.type)))
        if conn.shape[1] == 3:
            conn = np.hstack([conn, np.full((len(conn), 1), -1)])
        conn_l.append(conn)
        tag_l.append(tag)
    if kind.startswith("msh") and seq != sorted(set(seq)):
        bad("meshio %s: boundary blocks not one per (tag, type) in order: %s" % (base(kind), seq))
    if not conn_l:
        return np.zeros((0, 4), np.int64), np.zeros(0, np.int64), {}
    return (np.vstack(conn_l), np.concatenate(tag_l),
            {f: np.concatenate(v) for f, v in fields.items()})

face_sets = {}
counts2 = None
for kind, m in M.items():
    if kind in ("vtu", "vtk"):
        continue
    name = "meshio " + base(kind)
    alldir, alltag, fields = tagged_faces(kind, m)
    allk = np.sort(alldir, axis=1)
    tags = sorted(set(alltag.tolist()))
    if tags != list(range(1, ntags + 1)):
        bad("%s: boundary tags %s, expected 1..%d (%s)" % (name, tags, ntags, ",".join(names)))
    per = {t: (int(((alltag == t) & (alldir[:, 3] < 0)).sum()), int(((alltag == t) & (alldir[:, 3] >= 0)).sum()))
           for t in tags}
    face_sets[kind] = {t: keyset(allk[alltag == t]) for t in tags}
    desc = ", ".join("tag %d (%s): %d triangles + %d quads" % (t, names[t - 1] if t <= ntags else "?", *per[t]) for t in tags)
    line = "COUNTS2 " + " ".join("%d=%d" % (t, sum(per[t])) for t in tags)
    if counts2 is None:
        counts2 = line
    ok("%s: %s" % (name, desc))
    # every tagged face is a boundary face of the volume mesh, and every
    # boundary face is tagged, once
    row = lookup(allk)
    if (row < 0).any():
        bad("%s: %d tagged faces are not boundary faces of the volume mesh" % (name, int((row < 0).sum())))
    got = np.zeros(len(bnd_keys), dtype=np.int64)
    np.add.at(got, row[row >= 0], 1)
    if (got != 1).any():
        bad("%s: %d boundary faces untagged, %d tagged twice" % (name, int((got == 0).sum()), int((got > 1).sum())))
    elif (row >= 0).all():
        ok("%s: the tagged faces are exactly the %d boundary faces of the volume mesh" % (name, len(bnd_keys)))
    # closed surfaces: every edge an even number of times within a tag
    for t in tags:
        sel = alltag == t
        d = alldir[sel]
        e = []
        for j in range(4):
            a, b = d[:, j], d[:, (j + 1) % 4]
            tri = d[:, 3] < 0
            if j == 2:
                b = np.where(tri, d[:, 0], b)
            if j == 3:
                keep = ~tri
                a, b = a[keep], b[keep]
            e.append(np.stack([a, b], axis=1))
        e = np.vstack(e)
        und = np.sort(e, axis=1)
        _, c = np.unique(und, axis=0, return_counts=True)
        odd = int((c % 2 == 1).sum())
        if odd:
            bad("%s: tag %d: %d edges used an odd number of times (not closed)" % (name, t, odd))
        # orientation: each directed edge matched by its reverse
        fw = {tuple(x) for x in e.tolist()}
        unmatched = sum(1 for a, b in fw if (b, a) not in fw)
        if unmatched:
            bad("%s: tag %d: %d directed edges without their reverse (orientation)" % (name, t, unmatched))
        if not odd and not unmatched:
            ok("%s: tag %d closed and consistently oriented (%d edges, each used an even number of times, each directed edge matched by its reverse)" % (name, t, len(c)))
    # orientation against the owning element: outward
    rows = row[row >= 0]
    d = alldir[row >= 0]
    tri = d[:, 3] < 0
    q = np.where(d < 0, d[:, :1], d)  # triangles: repeat node 0
    pts = P[q]
    nrm = np.cross(pts[:, 2] - pts[:, 0], pts[:, 3] - pts[:, 1])
    nrm[tri] = np.cross(pts[tri, 1] - pts[tri, 0], pts[tri, 2] - pts[tri, 0])
    fc = np.where(tri[:, None], pts[:, :3].mean(axis=1), pts.mean(axis=1))
    s = np.einsum("ij,ij->i", nrm, fc - cent[bnd_cell[rows]])
    nin = int((s <= 0).sum())
    if nin:
        bad("%s: %d of %d boundary faces turn towards their element (not outward)" % (name, nin, len(s)))
    else:
        ok("%s: every boundary face outward (normal away from its element)" % name)
    # a face's fields are its element's
    for f, v in fields.items():
        own = vol_fields[f][bnd_cell[rows]]
        if len(v) != len(own) or not np.allclose(v, own, rtol=0, atol=1e-12 if f == "jens" else 0):
            bad("%s: the field %s of the faces is not their element's" % (name, f))
        else:
            ok("%s: the faces' field %s is their element's" % (name, f))
    # the tags lie on their input surfaces
    if spheres:
        for t in tags:
            if t > len(spheres):
                continue
            cx, cy, cz, R = spheres[t - 1]
            nodes = np.unique(allk[alltag == t])
            nodes = nodes[nodes >= 0]
            r = np.linalg.norm(P[nodes] - [cx, cy, cz], axis=1) / R
            if r.min() < 0.98 or r.max() > 1.0 + 1e-9:
                bad("%s: tag %d nodes at %.4g..%.4g of the radius of %s" % (name, t, r.min(), r.max(), names[t - 1]))
            else:
                ok("%s: tag %d nodes on %s (radius ratio %.4f..%.4f)" % (name, t, names[t - 1], r.min(), r.max()))
    # the volume by the divergence theorem, per body, against the elements'
    if kind == "msh_bin":
        vb = np.zeros(nbodies + 1)
        cb = vol_fields["body"].astype(int)
        ve = np.concatenate([signed_volumes(P, t, conn) for t, conn in vol_conn])
        np.add.at(vb, cb, ve)
        fb = np.zeros(nbodies + 1)
        # signed volume of the cone from the origin over each face (quads: the
        # mean of both diagonal splits)
        a, b, c4 = pts[:, 0], pts[:, 1], pts[:, 2]
        v1 = np.einsum("ij,ij->i", a, np.cross(b, c4)) / 6
        d4 = pts[:, 3]
        v2 = np.where(tri, 0.0, np.einsum("ij,ij->i", a, np.cross(c4, d4)) / 6)
        w1 = np.einsum("ij,ij->i", a, np.cross(b, d4)) / 6
        w2 = np.einsum("ij,ij->i", b, np.cross(c4, d4)) / 6
        vf = np.where(tri, v1, 0.5 * (v1 + v2 + w1 + w2))
        np.add.at(fb, cb[bnd_cell[rows]], vf)
        for bb in range(1, nbodies + 1):
            rel = abs(vb[bb] - fb[bb]) / abs(vb[bb])
            (ok if rel < 1e-3 else bad)("%s: body %d: volume %.6g from its elements, %.6g from its boundary faces (divergence theorem; rel. diff. %.1e)" % (name, bb, vb[bb], fb[bb], rel))

# the same faces with the same tags in each format
for kind, fs in face_sets.items():
    r = face_sets["msh_bin"]
    same = fs.keys() == r.keys() and all(np.array_equal(fs[t], r[t]) for t in r)
    if not same:
        bad("meshio %s: the tagged faces differ from %s's" % (base(kind), base("msh_bin")))
if len(face_sets) > 1:
    ok("the same faces under the same tags in %s" % ", ".join(base(k) for k in face_sets))

# ---- VTU/VTK point field surface_tag: the smallest tag of a node's faces ----------
want = np.zeros(len(P), dtype=np.int64)
big = ntags + 1000
want[:] = big
for t, ks in face_sets["msh_bin"].items():
    n = ks[ks >= 0]
    want[n] = np.minimum(want[n], t)
want[want == big] = 0
for kind in ("vtu", "vtk"):
    if kind not in M:
        continue
    m = M[kind]
    name = "meshio " + base(kind)
    if "surface_tag" not in m.point_data:
        bad("%s: no point field surface_tag" % name)
        continue
    st = ints(m.point_data["surface_tag"])
    if not np.array_equal(st, want):
        bad("%s: surface_tag differs from the .msh faces' tags at %d nodes" % (name, int((st != want).sum())))
    else:
        ok("%s: point field surface_tag = the smallest tag of each node's faces (%s)"
           % (name, " ".join("%d:%d" % (t, int((st == t).sum())) for t in range(ntags + 1))))
    if "body" not in m.cell_data:
        bad("%s: no cell field body" % name)
    else:
        for t in VOL:
            a = np.concatenate(body_by_type[kind].get(t, [np.zeros(0, np.int64)]))
            r = np.concatenate(body_by_type["msh_bin"].get(t, [np.zeros(0, np.int64)]))
            if not np.array_equal(a, r):
                bad("%s: cell field body of the %s differs from the .msh's" % (name, t))

print(counts2)
print("COUNTS3 " + " ".join("%d=%d" % (b, sum(v for (bb, _), v in ref.items() if bb == b)) for b in range(1, nbodies + 1)))
sys.exit(1 if fails else 0)
EOF
cat >"$T/tags_gmsh.py" <<'EOF'
"""Tagged boundaries read back by Gmsh's Python API (issue 11): see
external_readers_test.sh.

usage: tags_gmsh.py FILE.msh NAMES NBODIES
Prints ok/FAIL lines, then COUNTS2 (elements per dimension-2 physical
group) and COUNTS3 (per dimension-3 group), the lines the meshio check
prints too."""
import sys
import numpy as np
import gmsh

path, names, nbodies = sys.argv[1], sys.argv[2].split(","), int(sys.argv[3])
base = "gmsh-api " + path.rsplit("/", 1)[-1]
fails = 0
def ok(msg): print("ok   %s: %s" % (base, msg))
def bad(msg):
    global fails
    fails += 1
    print("FAIL %s: %s" % (base, msg))

gmsh.initialize(["", "-nopopup"], readConfigFiles=False)
gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(path)
TYPE = {4: 0, 7: 1, 6: 2, 5: 3}      # Gmsh element type -> mixoct type
groups = gmsh.model.getPhysicalGroups()
g2 = sorted(t for d, t in groups if d == 2)
g3 = sorted(t for d, t in groups if d == 3)
if g2 != list(range(1, len(names) + 1)):
    bad("dimension-2 physical groups %s, expected 1..%d" % (g2, len(names)))
if g3 != list(range(1, nbodies + 1)):
    bad("dimension-3 physical groups %s, expected 1..%d" % (g3, nbodies))
count = {}
tag_of = {}        # element tag -> (dim, group)
etype_of = {}
for d, t in groups:
    n = 0
    for e in gmsh.model.getEntitiesForPhysicalGroup(d, t):
        types, tags, _ = gmsh.model.mesh.getElements(d, e)
        for ty, tg in zip(types, tags):
            n += len(tg)
            for x in tg.tolist():
                tag_of[x] = (d, t)
                etype_of[x] = int(ty)
    count[(d, t)] = n
for t in g2:
    name = gmsh.model.getPhysicalName(2, t)
    if t <= len(names) and name != names[t - 1]:
        bad("dimension-2 group %d named %r, expected %r (input %d)" % (t, name, names[t - 1], t))
ok("dimension-2 groups: %s" % ", ".join("%d %r (%d faces)" % (t, gmsh.model.getPhysicalName(2, t), count[(2, t)]) for t in g2))
body_names = {t: gmsh.model.getPhysicalName(3, t) for t in g3}
ok("dimension-3 groups: %s" % ", ".join("%d %r (%d elements)" % (t, body_names[t], count[(3, t)]) for t in g3))

# every element in exactly one group; element tags 1..N
_, all_tags, _ = gmsh.model.mesh.getElements()
all_tags = np.concatenate([np.asarray(x, dtype=np.int64) for x in all_tags]) if all_tags else np.zeros(0, np.int64)
N = len(all_tags)
if sorted(all_tags.tolist()) != list(range(1, N + 1)):
    bad("element tags are not 1..%d" % N)
if len(tag_of) != N:
    bad("%d of %d elements in a physical group" % (len(tag_of), N))

# $ElementData: views type, level, jens, body, one value per element
views = {}
for v in gmsh.view.getTags():
    name = gmsh.option.getString("View[%d].Name" % gmsh.view.getIndex(v))
    dtype, tags, data, _, ncomp = gmsh.view.getModelData(v, 0)
    views[name] = (dtype, np.asarray(tags, dtype=np.int64), np.asarray([x[0] for x in data]), ncomp)
want = ["type", "level", "jens", "body"]
if sorted(views) != sorted(want):
    bad("views %s, expected %s" % (sorted(views), want))
val = {}
for name in want:
    if name not in views:
        continue
    dtype, tags, data, ncomp = views[name]
    if dtype != "ElementData" or ncomp != 1 or len(tags) != N or len(set(tags.tolist())) != N \
            or set(tags.tolist()) != set(all_tags.tolist()):
        bad("view %s: %s, %d values (%d components) for %d elements" % (name, dtype, len(tags), ncomp, N))
    else:
        val[name] = dict(zip(tags.tolist(), data.tolist()))
if len(val) == 4:
    ok("ElementData views %s, one value for each of the %d elements" % (" ".join(want), N))
    vol = [x for x in all_tags.tolist() if tag_of.get(x, (0,))[0] == 3]
    wrong_type = sum(1 for x in vol if val["type"][x] != TYPE[etype_of[x]])
    wrong_body = sum(1 for x in vol if val["body"][x] != tag_of[x][1])
    jens = np.array([val["jens"][x] for x in vol])
    lev = np.array([val["level"][x] for x in vol])
    if wrong_type or wrong_body:
        bad("%d volume elements whose view type is not their type, %d whose view body is not their group"
            % (wrong_type, wrong_body))
    elif not (jens.min() > 0 and jens.max() <= 1 and (lev == np.rint(lev)).all() and lev.min() >= 0):
        bad("jens %g..%g, level %g..%g" % (jens.min(), jens.max(), lev.min(), lev.max()))
    else:
        ok("views agree with the elements: type = element type, body = dimension-3 group, "
           "jens %.3f..%.3f, level %d..%d" % (jens.min(), jens.max(), lev.min(), lev.max()))
    # a face's body is the body of its nodes' elements; the name of body b
    # is "<file of its smallest tag> volume b"
    node_body = {}
    for b in g3:
        for e in gmsh.model.getEntitiesForPhysicalGroup(3, b):
            _, _, nodes = gmsh.model.mesh.getElements(3, e)
            for nn in nodes:
                for x in np.unique(nn).tolist():
                    node_body[x] = b
    smallest = {}
    wrong = 0
    for t in g2:
        for e in gmsh.model.getEntitiesForPhysicalGroup(2, t):
            types, tags, nodes = gmsh.model.mesh.getElements(2, e)
            for ty, tg, nn in zip(types, tags, nodes):
                k = 3 if ty == 2 else 4
                nn = np.asarray(nn).reshape(-1, k)
                for x, row in zip(tg.tolist(), nn.tolist()):
                    b = int(val["body"][x])
                    if any(node_body.get(p) != b for p in row):
                        wrong += 1
                    smallest[b] = min(smallest.get(b, 1 << 30), t)
    if wrong:
        bad("%d boundary faces whose body value is not their nodes' body" % wrong)
    else:
        ok("each boundary face's body value is its element's body")
    for b in g3:
        t = smallest.get(b)
        exp = "%s volume %d" % (names[t - 1], b) if t else None
        if body_names[b] != exp:
            bad("body %d named %r, expected %r" % (b, body_names[b], exp))
gmsh.finalize()
print("COUNTS2 " + " ".join("%d=%d" % (t, count[(2, t)]) for t in g2))
print("COUNTS3 " + " ".join("%d=%d" % (t, count[(3, t)]) for t in g3))
sys.exit(1 if fails else 0)
EOF

# The verdict lines of a check log; FAIL lines count as failures.
verdict_lines() { # log
  local line
  while IFS= read -r line; do
    case "$line" in
      FAIL*) bad "${line#FAIL }" ;;
      *) echo "$line" ;;
    esac
  done < <(grep -E '^(ok|NOTE|FAIL|INFO)' "$1")
}

# The surfaces of the three-sphere case; prints each sphere's centre and
# radius (cx:cy:cz:R per tag, comma-separated).
tag_surfaces() { # dir
  "$JSON_PY" "$SRC_TESTS/make_surfaces.py" "$1" >/dev/null || return 1
  "$JSON_PY" - "$1" <<'EOF'
import sys
d = sys.argv[1]
lines = open(d + "/sphere.off").read().split("\n")
nv, nf = map(int, lines[1].split()[:2])
v = [tuple(map(float, l.split())) for l in lines[2:2 + nv]]
faces = lines[2 + nv:2 + nv + nf]
c = [sum(p[k] for p in v) / nv for k in range(3)]
R = max(sum((p[k] - c[k]) ** 2 for k in range(3)) ** 0.5 for p in v)
def write(name, f):
    with open(d + "/" + name, "w") as o:
        o.write("OFF\n%d %d 0\n" % (nv, nf))
        for p in v:
            o.write("%.17g %.17g %.17g\n" % f(p))
        o.write("\n".join(faces) + "\n")
write("inner.off", lambda p: tuple(c[k] + 0.4 * (p[k] - c[k]) for k in range(3)))
write("right.off", lambda p: (p[0] + 3.0, p[1], p[2]))
print(",".join("%.17g:%.17g:%.17g:%.17g" % s for s in
               [(c[0], c[1], c[2], R), (c[0], c[1], c[2], 0.4 * R), (c[0] + 3.0, c[1], c[2], R)]))
EOF
}

SRC_TESTS=$(cd "$(dirname "$0")" && pwd)
GMSH_PY=$(find_python "gmsh, numpy")
[ -n "$GMSH_PY" ] || missing "python3 gmsh API (Debian: python3-gmsh)"
MESHB=""
case " ${FILES[*]} " in *.meshb" "*) MESHB=1 ;; esac
mkdir -p "$T/tags"
SPHERES=$(tag_surfaces "$T/tags") || bad "cannot make the sphere surfaces (tests/make_surfaces.py)"
# name|inputs|tag names|bodies|spheres
CASES="demo|--demo|demo|1|-
spheres|-i $T/tags/sphere.off -i $T/tags/inner.off -i $T/tags/right.off|sphere.off,inner.off,right.off|2|$SPHERES"
if [ -n "$GMSH_PY$MESHIO_PY" ]; then
  while IFS='|' read -r case inputs tagnames nbodies spheres; do
    [ -n "$spheres" ] || continue
    d="$T/tags/$case"
    mkdir -p "$d"
    m="$d/$case"
    extra=()
    [ -n "$MESHB" ] && extra=(-o "$m.meshb")
    if ! "$MIXOCT" $inputs -s 4 -o "$m.msh" -o "$m.vtu" -o "$m.vtk" -o "$m.mesh" "${extra[@]}" \
        --boundary "${m}_boundary.vtu" --json >"$d/run.out" 2>"$d/run.err" ||
        ! "$MIXOCT" $inputs -s 4 -o "${m}_ascii.msh" --ascii --json >"$d/run_ascii.out" 2>"$d/run_ascii.err"; then
      bad "tags $case: mixoct $inputs failed"
      cat "$d/run.err" "$d/run_ascii.err" 2>/dev/null | tail -n 5
      continue
    fi
    tail -n 1 "$d/run.out" >"$d/run.json"
    tail -n 1 "$d/run_ascii.out" >"$d/run_ascii.json"
    elements=$("$JSON_PY" -c '
import json, sys
j, k = (json.load(open(p)) for p in sys.argv[1:3])
print(j["elements"] if (j["nodes"], j["by_type"]) == (k["nodes"], k["by_type"]) else -1)' \
      "$d/run.json" "$d/run_ascii.json")
    if [ "$elements" = -1 ] || [ -z "$elements" ]; then
      bad "tags $case: the ASCII run reported other counts than the binary run"
    fi
    echo "tags $case: mixoct $(echo "$inputs" | sed "s|$T/tags/||g") -s 4: $elements elements"
    ref2="" ref3=""
    if [ -n "$MESHIO_PY" ]; then
      args=(msh_bin="$m.msh" msh_ascii="${m}_ascii.msh" vtu="$m.vtu" vtk="$m.vtk" mesh="$m.mesh")
      [ -n "$MESHB" ] && args+=(meshb="$m.meshb")
      args+=(boundary="${m}_boundary.vtu")
      (cd "$T" && timeout 300 "$MESHIO_PY" tags_meshio.py "$d/run.json" "$tagnames" "$nbodies" \
        "$spheres" "${args[@]}") >"$d/meshio.log" 2>&1
      code=$?
      verdict_lines "$d/meshio.log"
      ref2=$(sed -n 's/^COUNTS2 //p' "$d/meshio.log")
      ref3=$(sed -n 's/^COUNTS3 //p' "$d/meshio.log")
      if [ "$code" -ne 0 ] && ! grep -q '^FAIL' "$d/meshio.log"; then
        bad "meshio tags $case: exit $code"
        tail -n 5 "$d/meshio.log"
      fi
    fi
    if [ -n "$GMSH_PY" ]; then
      for f in "$m.msh" "${m}_ascii.msh"; do
        name=$(basename "$f")
        timeout 300 "$GMSH_PY" "$T/tags_gmsh.py" "$f" "$tagnames" "$nbodies" >"$d/gmsh.log" 2>&1
        code=$?
        verdict_lines "$d/gmsh.log"
        if [ "$code" -ne 0 ] && ! grep -q '^FAIL' "$d/gmsh.log"; then
          bad "gmsh-api $name: exit $code"
          tail -n 5 "$d/gmsh.log"
          continue
        fi
        g2=$(sed -n 's/^COUNTS2 //p' "$d/gmsh.log")
        g3=$(sed -n 's/^COUNTS3 //p' "$d/gmsh.log")
        total=$(echo "$g3" | tr ' ' '\n' | awk -F= '{s += $2} END {print s + 0}')
        if [ "$total" != "$elements" ]; then
          bad "gmsh-api $name: the dimension-3 groups hold $total elements, mixoct reported $elements"
        elif [ -n "$MESHIO_PY" ] && { [ "$g2" != "$ref2" ] || [ "$g3" != "$ref3" ]; }; then
          bad "gmsh-api $name: groups '$g2' / '$g3', meshio counted '$ref2' / '$ref3'"
        else
          ok "gmsh-api $name: faces per tag $g2, elements per body $g3 (sum = mixoct's count${MESHIO_PY:+, = the meshio counts})"
        fi
      done
    fi
  done <<<"$CASES"
fi

# meshio's time on a larger file: the cortex at -s 7 (printed, no limit)
CORTEX=${MIXOCT_DATA:-$SRC_TESTS/../../shared/data}/surfaces/cortex.off
if [ -z "$MESHIO_PY" ]; then
  :
elif [ ! -f "$CORTEX" ]; then
  echo "NOTE no $CORTEX: meshio's time on the cortex not measured"
elif "$MIXOCT" -i "$CORTEX" -s 7 -o "$T/tags/cortex7.vtu" --json >"$T/tags/cortex.out" 2>"$T/tags/cortex.err"; then
  tail -n 1 "$T/tags/cortex.out" >"$T/tags/cortex.json"
  "$MESHIO_PY" - "$T/tags/cortex7.vtu" "$T/tags/cortex.json" >"$T/tags/cortex.log" 2>&1 <<'EOF'
import json, os, sys, time, warnings
warnings.simplefilter("ignore")
import numpy as np
import meshio
t0 = time.time()
m = meshio.read(sys.argv[1])
dt = time.time() - t0
j = json.load(open(sys.argv[2]))
n = sum(len(c.data) for c in m.cells)
bodies = [int(np.asarray(b).ravel()[0]) for b in m.cell_data["body"]]
per = {b: bodies.count(b) for b in sorted(set(bodies))}
print("INFO meshio.read cortex -s 7 .vtu (%.1f MB, %d nodes, %d cells in %d blocks): %.2f s"
      % (os.path.getsize(sys.argv[1]) / 1e6, len(m.points), n, len(m.cells), dt))
if len(m.points) != j["nodes"] or n != j["elements"] or max(per.values()) > 4:
    print("FAIL meshio cortex7.vtu: %d nodes %d cells, mixoct reported %d %d; blocks per body %s"
          % (len(m.points), n, j["nodes"], j["elements"], per))
else:
    print("ok   meshio cortex7.vtu: counts as mixoct reported, blocks per body %s" % per)
EOF
  verdict_lines "$T/tags/cortex.log"
  grep -q '^ok' "$T/tags/cortex.log" || { bad "meshio cortex7.vtu"; tail -n 5 "$T/tags/cortex.log"; }
else
  bad "mixoct -i cortex.off -s 7 failed"
  tail -n 5 "$T/tags/cortex.err"
fi

if [ "$fails" -eq 0 ]; then
  echo "external readers: all checks passed"
else
  echo "external readers: $fails check(s) failed"
fi
[ "$fails" -eq 0 ]
