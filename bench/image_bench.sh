#!/usr/bin/env bash
# Label images (issue 28): mixoct on a segmented image side by side with
# CGAL's Mesh_3 over a labelled image domain (bench/cgal/mesh3_image.cpp).
#
#   bench/image_bench.sh MIXOCT [N] [REPEAT]          (default 256, 3)
#
# The image: tools/make_label_image.py's `brain`, N^3 voxels of 1 mm, five
# labels (1 white matter with a folded surface, 2 a folded grey layer of 2-5
# voxels, 3 CSF and a ventricle inside 1, 4 skull, 5 scalp), every interface
# an analytic surface |x - C| = r_k(direction) (the ventricle an ellipsoid),
# written as brain.nii.gz for mixoct and brain.inr for CGAL (the same
# voxels, voxel (i, j, k) centred at (i, j, k) mm in both).
#
#   - mixoct: `MIXOCT -i brain.nii.gz -o out.vtu $MIXOCT_ARGS` (e.g.
#     MIXOCT_ARGS="-s 7"), all threads; MIXOCT_INPUT=nii gives it the
#     uncompressed brain.nii instead. A mixoct that fails on the image
#     (it does not read images yet) is reported as "mixoct: cannot read
#     images yet" with its exit code and last stderr line, and the CGAL half
#     still runs.
#   - CGAL: one run per criteria choice, CGAL_CRITERIA="FS:FD:CS ..." in
#     voxels (facet_size : facet_distance : cell_size; default "2:0.5:4
#     2:0.5:8 3:1:8": a facet distance of half a voxel and facets of 2
#     voxels with cells of 4 then 8 voxels, then a coarser surface),
#     facet_angle 30, cell radius-edge ratio 3, perturb and
#     exude on (CGAL's defaults); sequential (its parallel mode needs TBB).
# Each tool: wall time (median of REPEAT runs), peak RSS (/usr/bin/time -v,
# "Maximum resident set size", the largest of the runs), nodes, elements;
# then, from its mesh (the .vtu's cell field `material`, the .mesh's
# tetrahedra references; read with meshio):
#   - per-label volume (each element cut into tetrahedra from its centroid
#     to its faces, a quadrilateral face into 4 triangles about its
#     centroid: the same cut from both sides of a face, so the volumes add
#     up to the watertight union) against (a) the voxel count x the voxel
#     volume and (b) the analytic volume (quadrature of the radial
#     functions; tools/make_label_image.py);
#   - the interfaces: faces shared by two elements of different labels, and
#     the boundary faces as label pair (0, label); per label pair, the max
#     and mean distance of their nodes and of their faces' centroids to the
#     exact interface (make_label_image.Shape.interface_distance: Newton
#     projection along the gradient of the surface's implicit function; a
#     pair with no interface in the shape, e.g. 2-4 where a mesher lost the
#     CSF, against the nearest surface bounding either label), and how many
#     centroids lie farther than 2 voxels ("far": e.g. faces of 1-3 away
#     from the ventricle, where a mesher lost the thin grey layer). A node or
#     centroid sits within half a voxel diagonal (0.87 mm) of the surface at
#     best for a voxel-faithful mesh; CGAL's facet_distance bounds its
#     facets' distance to its own interpolated image surface.
# The mixoct mesh's frame: the bounding box of its nodes is matched against
# the image's labelled voxels under the NIfTI affine as written and under
# the RAS->LPS flip (x, y negated); the one that fits is used, and with
# neither the interface distances are left out (volumes do not depend on it).
# A table, then one JSON object on the last line, with the ratios of wall
# time CGAL / mixoct per choice. Slow at N 256 (minutes; CGAL's several GB
# at the finest choices): not in CI. Needs /usr/bin/python3 with numpy,
# nibabel and meshio (Debian: python3-numpy python3-nibabel python3-meshio).
#
# MESH3_IMAGE=path skips the build (a mesh3_image built before); otherwise it
# is built with g++ -O2 into the temporary directory (about a minute), and
# the CGAL half is skipped (a message) without the CGAL headers.
# IFACE_SAMPLE=M measures the interface distances on at most M random
# points per label pair and kind (default: all).
set -u
BIN=${1:?usage: image_bench.sh MIXOCT [N] [REPEAT]}
N=${2:-256}
REPEAT=${3:-3}
HERE=$(cd "$(dirname "$0")" && pwd)
PY=${PYTHON:-/usr/bin/python3}
T=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_image_bench.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT

if ! "$PY" -c "import numpy, nibabel, meshio" 2>/dev/null; then
  echo "image_bench: skipped: $PY lacks numpy, nibabel or meshio (Debian: python3-numpy python3-nibabel python3-meshio)"
  exit 0
fi
if [ ! -x /usr/bin/time ]; then
  echo "image_bench: skipped: no /usr/bin/time (Debian: time)"
  exit 0
fi

CGAL_BIN=${MESH3_IMAGE:-}
if [ -z "$CGAL_BIN" ]; then
  CXX=${CXX:-g++}
  if ! command -v "$CXX" >/dev/null 2>&1; then
    echo "image_bench: no C++ compiler ($CXX): the CGAL half is skipped"
  elif ! printf '#include <CGAL/Labeled_mesh_domain_3.h>\n#include <CGAL/Image_3.h>\n' |
    "$CXX" -x c++ -std=c++17 -fsyntax-only - >/dev/null 2>&1; then
    echo "image_bench: CGAL's Mesh_3 headers not found (Debian: libcgal-dev): the CGAL half is skipped"
  else
    echo "building bench/cgal/mesh3_image.cpp (CGAL, about a minute)..."
    CGAL_BIN=$T/mesh3_image
    "$CXX" -O2 -DNDEBUG -std=c++17 "$HERE/cgal/mesh3_image.cpp" -o "$CGAL_BIN" \
      -lgmp -lmpfr || exit 1
  fi
fi

echo "making the brain image, N = $N..."
"$PY" "$HERE/../tools/make_label_image.py" "$T/brain.nii.gz" --shape brain --n "$N" \
  --inr "$T/brain.inr" >/dev/null || exit 1

"$PY" - "$BIN" "$CGAL_BIN" "$T" "$N" "$REPEAT" "$HERE/../tools" \
  "${CGAL_CRITERIA:-2:0.5:4 2:0.5:8 3:1:8}" "${MIXOCT_ARGS:-}" "${IFACE_SAMPLE:-0}" \
  "${MIXOCT_INPUT:-nii.gz}" <<'EOF'
import json, os, re, shlex, statistics, subprocess, sys, time

import numpy as np

MIXOCT, CGAL, T, N, REPEAT, TOOLS, CHOICES, MARGS, SAMPLE, MINPUT = sys.argv[1:11]
N, REPEAT, SAMPLE = int(N), int(REPEAT), int(SAMPLE)
sys.path.insert(0, TOOLS)
import meshio
from make_label_image import Shape

SIDE = json.load(open(os.path.join(T, "brain.json")))
SHAPE = Shape.from_json(SIDE)
H = SHAPE.h
LABELS = sorted(int(k) for k in SIDE["labels"])
RNG = np.random.default_rng(1)
FAR = 2.0 * H  # "far": farther than 2 voxels from the pair's surface

# ---- running ------------------------------------------------------------------


def run_timed(cmd):
    """(wall s, peak RSS MB, returncode, stdout, stderr) under /usr/bin/time -v"""
    tf = os.path.join(T, "time.txt")
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-v", "-o", tf] + cmd, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    rss = None
    try:
        m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", open(tf).read())
        rss = int(m.group(1)) / 1024 if m else None
    except OSError:
        pass
    return wall, rss, p.returncode, p.stdout, p.stderr


def repeat(cmd, first=None):
    """median wall, max RSS of REPEAT runs (first: a run already done)"""
    runs = [first] if first else []
    while len(runs) < REPEAT:
        r = run_timed(cmd)
        if r[2] != 0:
            sys.exit("image_bench: %s failed (%d): %s" % (" ".join(cmd), r[2], r[4].strip()[-500:]))
        runs.append(r)
    rss = [r[1] for r in runs if r[1] is not None]
    return {"wall_s": statistics.median(r[0] for r in runs), "walls": [r[0] for r in runs],
            "peak_rss_mb": max(rss) if rss else None}, runs[-1]

# ---- a mesh's figures -----------------------------------------------------------

# faces as VTK node positions (the order mixoct's .vtu and CGAL's tetrahedra use)
FACES = {
    "tetra": ([(0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)], []),
    "pyramid": ([(0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)], [(0, 1, 2, 3)]),
    "wedge": ([(0, 1, 2), (3, 4, 5)], [(0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)]),
    "hexahedron": ([], [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                        (3, 0, 4, 7)]),
}


def tet_vol(a, b, c, d):
    return np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))) / 6


def read_mesh(path, field):
    """(points, [(type, conn, labels)]) of the 3D cells"""
    m = meshio.read(path)
    blocks = []
    for i, cb in enumerate(m.cells):
        if cb.type not in FACES:
            continue
        lab = np.asarray(m.cell_data[field][i]).astype(np.int64).ravel()
        blocks.append((cb.type, np.asarray(cb.data, dtype=np.int64), lab))
    return np.asarray(m.points, dtype=float)[:, :3], blocks


def volumes(p, blocks):
    vol = {}
    for kind, conn, lab in blocks:
        x = p[conn]
        c = x.mean(axis=1)
        v = np.zeros(len(conn))
        tris, quads = FACES[kind]
        for f in tris:
            v += tet_vol(c, x[:, f[0]], x[:, f[1]], x[:, f[2]])
        for f in quads:
            fc = x[:, list(f)].mean(axis=1)
            for a in range(4):
                v += tet_vol(c, fc, x[:, f[a]], x[:, f[(a + 1) % 4]])
        u, inv = np.unique(lab, return_inverse=True)
        sums = np.bincount(inv, weights=v, minlength=len(u))
        for l, s in zip(u, sums):
            vol[int(l)] = vol.get(int(l), 0.0) + float(s)
    return vol


def interface_faces(blocks):
    """{(a, b): [face node arrays (m x 3) or (m x 4)]}: faces of two elements
    of different labels, boundary faces as (0, label)"""
    out, nonmanifold = {}, 0
    for size in (3, 4):
        rows, labs = [], []
        for kind, conn, lab in blocks:
            for f in FACES[kind][0 if size == 3 else 1]:
                rows.append(conn[:, list(f)])
                labs.append(lab)
        if not rows:
            continue
        F = np.concatenate(rows)
        L = np.concatenate(labs)
        S = np.sort(F, axis=1)
        order = np.lexsort(S.T[::-1])
        S, F, L = S[order], F[order], L[order]
        new = np.ones(len(S), dtype=bool)
        new[1:] = np.any(S[1:] != S[:-1], axis=1)
        start = np.flatnonzero(new)
        count = np.diff(np.append(start, len(S)))
        nonmanifold += int(np.sum(count > 2))
        one = start[count == 1]
        two = start[count == 2]
        for idx, a, b in ((one, np.zeros(len(one), np.int64), L[one]),
                          (two, L[two], L[two + 1] if len(two) else L[two])):
            lo, hi = np.minimum(a, b), np.maximum(a, b)
            keep = lo != hi
            idx, lo, hi = idx[keep], lo[keep], hi[keep]
            for pa, pb in set(zip(lo.tolist(), hi.tolist())):
                sel = idx[(lo == pa) & (hi == pb)]
                out.setdefault((pa, pb), []).append(F[sel])
    return out, nonmanifold


def stats(d):
    if d is None or len(d) == 0:
        return None
    return {"max": float(np.max(d)), "mean": float(np.mean(d)),
            "far": int(np.sum(d > FAR)), "of": int(len(d))}


def sample(x):
    if SAMPLE and len(x) > SAMPLE:
        return x[RNG.choice(len(x), SAMPLE, replace=False)]
    return x


def interfaces(p, blocks):
    faces, nonmanifold = interface_faces(blocks)
    res = {}
    for (a, b), parts in sorted(faces.items()):
        nodes = np.unique(np.concatenate([f.ravel() for f in parts]))
        cent = np.concatenate([p[f].mean(axis=1) for f in parts])
        res["%d-%d" % (a, b)] = {
            "faces": int(sum(len(f) for f in parts)), "nodes": int(len(nodes)),
            "expected": "%d-%d" % (a, b) in SIDE["interfaces"],
            "node_dist": stats(SHAPE.interface_distance(sample(p[nodes]), a, b)),
            "face_dist": stats(SHAPE.interface_distance(sample(cent), a, b))}
    return res, nonmanifold


def frame(p):
    """the transform (mesh -> image world) that makes the mesh's bounding box
    fit the labelled voxels' (None: neither fits)"""
    img = np.asarray(__import__("nibabel").load(os.path.join(T, "brain.nii.gz")).dataobj)
    idx = np.argwhere(img > 0)
    lo, hi = idx.min(axis=0) * H, idx.max(axis=0) * H
    best = None
    for name, s in (("as written", np.array([1.0, 1.0, 1.0])),
                    ("LPS (x, y negated)", np.array([-1.0, -1.0, 1.0]))):
        q = p * s
        err = max(np.max(np.abs(q.min(axis=0) - lo)), np.max(np.abs(q.max(axis=0) - hi)))
        if best is None or err < best[2]:
            best = (name, s, err)
    return best if best[2] <= 2.0 * H else (best[0], None, best[2])


def judge(path, field, fix_frame):
    p, blocks = read_mesh(path, field)
    r = {"nodes": int(len(p)), "elements": int(sum(len(b[1]) for b in blocks)),
         "by_type": {k: int(len(c)) for k, c, _ in blocks}}
    vol = volumes(p, blocks)
    r["volumes"] = {str(k): v for k, v in sorted(vol.items())}
    ev, ea = {}, {}
    for l in LABELS:
        e = SIDE["labels"][str(l)]
        v = vol.get(l, 0.0)
        ev[str(l)] = (v - e["voxel_volume"]) / e["voxel_volume"]
        if "analytic_volume" in e:
            ea[str(l)] = (v - e["analytic_volume"]) / e["analytic_volume"]
    r["volume_error_voxels"], r["volume_error_analytic"] = ev, ea
    r["frame"] = "as written"
    if fix_frame:
        name, s, err = frame(p)
        r["frame"], r["frame_fit"] = name, err
        if s is None:
            r["interfaces"] = None
            r["note"] = "mesh frame does not fit the image (bbox off by %.3g): no distances" % err
            return r
        p = p * s
    r["interfaces"], r["nonmanifold_faces"] = interfaces(p, blocks)
    return r

# ---- the runs ---------------------------------------------------------------------


res = {"bench": "image", "shape": "brain", "n": N, "voxel": H, "repeat": REPEAT,
       "cpus": os.cpu_count(), "load_before": os.getloadavg()[0],
       "image": {"labels": SIDE["labels"], "interfaces": SIDE["interfaces"],
                 "analytic_volume_quadrature_error": SIDE["analytic_volume_quadrature_error"]}}
NII, INR = os.path.join(T, "brain.nii.gz"), os.path.join(T, "brain.inr")
if MINPUT == "nii":
    import gzip, shutil
    with gzip.open(NII, "rb") as src, open(NII[:-3], "wb") as dst:
        shutil.copyfileobj(src, dst)
    NII = NII[:-3]
elif MINPUT != "nii.gz":
    sys.exit("image_bench: MIXOCT_INPUT must be nii.gz or nii")

vtu = os.path.join(T, "out.vtu")
cmd = [MIXOCT, "-i", NII, "-o", vtu] + shlex.split(MARGS)
first = run_timed(cmd)
if first[2] != 0 or not os.path.exists(vtu):
    last = (first[4].strip().splitlines() or [""])[-1]
    print("mixoct: cannot read images yet (exit %d: %s)" % (first[2], last))
    res["mixoct"] = {"error": "cannot read images yet", "exit": first[2], "stderr": last,
                     "cmd": " ".join(cmd)}
else:
    m, _ = repeat(cmd, first)
    m["cmd"] = " ".join(cmd)
    m.update(judge(vtu, "material", True))
    res["mixoct"] = m

res["cgal"] = []
if CGAL:
    for ch in CHOICES.split():
        fs, fd, cs = (float(x) * H for x in ch.split(":"))
        mesh = os.path.join(T, "cgal.mesh")
        ccmd = [CGAL, INR, mesh, "--facet-size", "%g" % fs, "--facet-distance", "%g" % fd,
                "--cell-size", "%g" % cs]
        c, last = repeat(ccmd)
        info = json.loads(last[3].strip().splitlines()[-1])
        c.update({"criteria": ch, "facet_size": fs, "facet_distance": fd, "cell_size": cs,
                  "cmd": " ".join(ccmd), "make_mesh_3_s": info["seconds"]["mesh"]})
        c.update(judge(mesh, "medit:ref", False))
        if "wall_s" in res["mixoct"]:
            c["cgal_over_mixoct_wall"] = c["wall_s"] / res["mixoct"]["wall_s"]
        res["cgal"].append(c)
else:
    print("CGAL: not run (no mesh3_image)")

# ---- the table --------------------------------------------------------------------

rows = []
if "wall_s" in res["mixoct"]:
    rows.append(("mixoct", MARGS or "(default)", res["mixoct"]))
for c in res["cgal"]:
    rows.append(("CGAL Mesh_3", "fs:fd:cs " + c["criteria"], c))
print("brain N=%d (voxel %g mm): labels %s; analytic volumes' quadrature error %.3g mm^3"
      % (N, H, " ".join("%d: %d vox" % (l, SIDE["labels"][str(l)]["voxels"]) for l in LABELS),
         SIDE["analytic_volume_quadrature_error"]))
fmt = "%-11s %-18s %9s %9s %8s %8s %6s"
print(fmt % ("tool", "options", "nodes", "elements", "wall s", "RSS MB", "x mix"))
for tool, opt, r in rows:
    ratio = r.get("cgal_over_mixoct_wall")
    print(fmt % (tool, opt, r["nodes"], r["elements"], "%.2f" % r["wall_s"],
                 "%.0f" % r["peak_rss_mb"] if r["peak_rss_mb"] else "?",
                 "%.2f" % ratio if ratio else "-"))
print("volume error per label, vs voxels / vs analytic (%):")
for tool, opt, r in rows:
    print("  %-11s %-18s " % (tool, opt) + "  ".join(
        "%d: %+.2f/%s" % (l, 100 * r["volume_error_voxels"][str(l)],
                          "%+.2f" % (100 * r["volume_error_analytic"][str(l)])
                          if str(l) in r["volume_error_analytic"] else "-") for l in LABELS))
print("interfaces (faces between two labels; 0 = outside): node / face-centroid distance "
      "to the exact surface, max/mean mm")
for tool, opt, r in rows:
    if r.get("interfaces") is None:
        print("  %-11s %-18s %s" % (tool, opt, r.get("note", "-")))
        continue
    for pair, i in r["interfaces"].items():
        nd, fd = i["node_dist"], i["face_dist"]
        print("  %-11s %-18s %-4s %s %8d faces  nodes %s  faces %s" % (
            tool, opt, pair, " " if i["expected"] else "!", i["faces"],
            "%.3f/%.3f" % (nd["max"], nd["mean"]) if nd else "-",
            "%.3f/%.3f (%d far)" % (fd["max"], fd["mean"], fd["far"]) if fd else "-"))
print("('!': a pair of labels that do not touch in the analytic image; far: centroids farther "
      "than %g mm, e.g. 1-3 faces away from the ventricle where the grey layer was lost; wall: "
      "median of %d, RSS: the largest)" % (FAR, REPEAT))
print(json.dumps(res))
EOF
