#!/usr/bin/env python3
"""GetFEM reads mixoct's boundary tags and solves with them (issue 11).

usage: getfem_tags_test.py MIXOCT WORKDIR [DATA_DIR]

mixoct writes a .getfem file with one region per boundary tag (BEGIN REGION
t, "convex/face" lines, END REGION t; src/io/write_getfem.c). Loaded with
getfem.Mesh('load', ...), each mesh is checked and solved:

  regions   exactly one per tag (1..n in -i order); every region face is an
            outer face of the mesh (Mesh.outer_faces), no face in two
            regions, and together they are all the outer faces; each
            region's faces (their nodes, through GetFEM's own face
            numbering, CvStruct.facepts) are the faces --boundary FILE.vtu
            tags t; the nodes of region t lie on input t (spheres: radius).
  patch     -Laplace(u) = 0 with u = g on the Dirichlet tags and
            du/dn = grad(g).n on the Neumann tags, g = 1 + 2x - y + 0.5z.
            The P1 spaces on the mixed mesh (FEM_PK(3,1), FEM_PYRAMID_
            LAGRANGE(1), FEM_PK_PRISM(3,1), FEM_QK(3,1), as
            examples/adaptive_poisson.py uses them) hold g, so the solution
            must be g at every node (max |u - g| / max |g| < 1e-8): the
            Neumann data only balances if its faces are boundary faces of
            the right elements, taken with GetFEM's outward normals.

Meshes: "shell" (-i sphere.off -i inner.off: tests/make_surfaces.py's unit
sphere and a copy scaled 0.4 about its centre, a cavity): Dirichlet on tag
1, Neumann on tag 2. "spheres" (the same plus right.off, the sphere shifted
by x + 3: two bodies): Dirichlet on tags 1 and 3, Neumann on tag 2.
"cortex" (DATA_DIR/surfaces/cortex.off at -s 5, one input): Dirichlet on
tag 1 (all of the boundary); skipped with a NOTE without DATA_DIR.

Two GetFEM 5.4 details the test works around (not mixoct's):
  - the classical pyramid integration method (IM_PYRAMID(...)) has no
    points on the pyramid's face 4 (nodes 0 2 4): a Neumann term there
    integrates to 0. The boundary term is integrated with
    IM_PYRAMID_COMPOSITE(IM_TETRAHEDRON(5)) on pyramids (exact for the
    P1 data on their triangular faces); a NOTE says when the classical
    method misses a face.
  - MeshFem.basic_dof_nodes puts a pyramid's apex dof up to ~1e-5 away
    from the mesh point (the rational transformation is evaluated near,
    not at, the apex); g is taken at the mesh points (each dof's point
    from basic_dof_from_cvid / pid_from_cvid), not at the dof nodes.

Prints ok/FAIL/NOTE lines; exits 1 on any failure.
"""
import json
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np
import getfem as gf

HERE = os.path.dirname(os.path.abspath(__file__))
FEM = {"GT_PK(3,1)": "FEM_PK(3,1)", "GT_PYRAMID(1)": "FEM_PYRAMID_LAGRANGE(1)",
       "GT_PRISM(3,1)": "FEM_PK_PRISM(3,1)", "GT_QK(3,1)": "FEM_QK(3,1)"}
PYRAMID_BOUNDARY_IM = "IM_PYRAMID_COMPOSITE(IM_TETRAHEDRON(5))"
A = np.array([2.0, -1.0, 0.5])      # g = 1 + A.x
B = 1.0
TOL = 1e-8

fails = 0


def ok(msg):
    print("ok   " + msg, flush=True)


def bad(msg):
    global fails
    fails += 1
    print("FAIL " + msg, flush=True)


def note(msg):
    print("NOTE " + msg, flush=True)


# ---- inputs -----------------------------------------------------------------------

def read_off(path):
    with open(path) as f:
        words = [l.split() for l in f if l.strip() and not l.startswith("#")]
    nv, nf = int(words[1][0]), int(words[1][1])
    return np.array(words[2:2 + nv], dtype=float), [" ".join(w) for w in words[2 + nv:2 + nv + nf]]


def write_off(path, v, faces):
    with open(path, "w") as o:
        o.write("OFF\n%d %d 0\n" % (len(v), len(faces)))
        for p in v:
            o.write("%.17g %.17g %.17g\n" % tuple(p))
        o.write("\n".join(faces) + "\n")


def make_surfaces(work):
    """sphere.off, inner.off (scaled 0.4 about the centre), right.off
    (x + 3); returns {name: (centre, radius)}."""
    subprocess.run([sys.executable, os.path.join(HERE, "make_surfaces.py"), work],
                   check=True, stdout=subprocess.DEVNULL)
    v, f = read_off(os.path.join(work, "sphere.off"))
    c = v.mean(axis=0)
    r = np.linalg.norm(v - c, axis=1).max()
    write_off(os.path.join(work, "inner.off"), c + 0.4 * (v - c), f)
    write_off(os.path.join(work, "right.off"), v + [3.0, 0.0, 0.0], f)
    return {"sphere.off": (c, r), "inner.off": (c, 0.4 * r),
            "right.off": (c + [3.0, 0.0, 0.0], r)}


def run_mixoct(mixoct, inputs, level, out):
    cmd = [mixoct]
    for i in inputs:
        cmd += ["-i", i]
    cmd += ["-s", str(level), "-o", out + ".getfem", "--boundary", out + "_boundary.vtu",
            "--json"]
    t0 = time.time()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        bad("%s: exit %d\n%s" % (" ".join(cmd), p.returncode, p.stderr[-2000:]))
        return None
    j = json.loads(p.stdout.strip().splitlines()[-1])
    j["_seconds"] = time.time() - t0
    return j


def read_boundary_vtu(path):
    """The faces of a --boundary .vtu (ASCII VTK XML): {tag: sorted node
    tuples}, nodes as volume-mesh indices (the point field 'node')."""
    root = ET.parse(path).getroot()
    arrays = {}
    for da in root.iter("DataArray"):
        arrays[da.get("Name")] = np.array((da.text or "").split(), dtype=float)
    node = arrays["node"].astype(np.int64)
    conn = arrays["connectivity"].astype(np.int64)
    offs = arrays["offsets"].astype(np.int64)
    tag = arrays["surface_tag"].astype(np.int64)
    start = np.concatenate([[0], offs[:-1]])
    out = {}
    for s, e, t in zip(start, offs, tag):
        out.setdefault(int(t), []).append(tuple(sorted(node[conn[s:e]].tolist())))
    return {t: sorted(v) for t, v in out.items()}


# ---- GetFEM ------------------------------------------------------------------------

def pyramid_face_note():
    """A NOTE when GetFEM's classical pyramid integration misses a face."""
    m = gf.Mesh("empty", 3)
    pts = np.array([[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0], [0, 0, 1]], float)
    m.add_convex(gf.GeoTrans("GT_PYRAMID(1)"), pts.T)
    mim = gf.MeshIm(m, 4)
    md = gf.Model("real")
    mf = gf.MeshFem(m, 1)
    mf.set_fem(gf.Fem("FEM_PYRAMID_LAGRANGE(1)"))
    md.add_fem_variable("u", mf)
    missing = []
    for f in range(5):
        m.set_region(1, np.array([[0], [f]]))
        area = gf.asm_generic(mim, 0, "1", 1, md)
        if abs(area - (4.0 if f == 0 else np.sqrt(2.0))) > 1e-9:
            missing.append((f, area))
    if missing:
        note("GetFEM's classical pyramid integration (%s) gives the reference "
             "pyramid's face(s) %s an area of %s: Neumann terms are integrated with "
             "%s on pyramids" % (mim.integ(0)[0].char(), [f for f, _ in missing],
                                 [round(a, 6) for _, a in missing], PYRAMID_BOUNDARY_IM))


def face_nodes(m, faces):
    """Sorted node tuples of the faces (2 x n array of convex, face), in
    GetFEM's own face numbering."""
    structs, cv2s = m.cvstruct()
    nfaces = {4: 4, 5: 5, 6: 5, 8: 6}   # tet, pyramid, prism, hex
    facepts = [[np.asarray(s.facepts(f), dtype=np.int64) for f in range(nfaces[int(s.nbpts())])]
               for s in structs]
    pids, idx = m.pid_from_cvid(np.unique(faces[0]))
    where = {cv: k for k, cv in enumerate(np.unique(faces[0]).tolist())}
    out = []
    for cv, f in faces.T.tolist():
        k = where[cv]
        cvp = pids[idx[k]:idx[k + 1]]
        out.append(tuple(sorted(cvp[facepts[cv2s[cv]][f]].tolist())))
    return out


def check_mesh(name, path, j, tag_names, spheres, boundary):
    """Load; check points, convexes and regions. Returns the mesh or None."""
    t0 = time.time()
    m = gf.Mesh("load", path)
    ntags = len(tag_names)
    if m.nbpts() != j["nodes"] or m.nbcvs() != j["elements"]:
        bad("%s: GetFEM read %d points, %d convexes; mixoct reported %d nodes, %d elements"
            % (name, m.nbpts(), m.nbcvs(), j["nodes"], j["elements"]))
        return None
    regions = sorted(int(r) for r in m.regions())
    if regions != list(range(1, ntags + 1)):
        bad("%s: regions %s, expected one per tag 1..%d (%s)" % (name, regions, ntags, ", ".join(tag_names)))
        return None
    outer = m.outer_faces()
    outer_set = set(map(tuple, outer.T.tolist()))
    seen = {}
    counts = []
    for r in regions:
        faces = m.region(r)
        fs = list(map(tuple, faces.T.tolist()))
        not_outer = sum(1 for f in fs if f not in outer_set)
        twice = sum(1 for f in fs if f in seen)
        for f in fs:
            seen[f] = r
        if not_outer or twice or len(set(fs)) != len(fs):
            bad("%s: region %d: %d faces not outer faces, %d in an earlier region, %d repeated"
                % (name, r, not_outer, twice, len(fs) - len(set(fs))))
        counts.append("region %d (%s): %d faces" % (r, tag_names[r - 1], len(fs)))
        # the same faces as the boundary file's tag r
        mine = sorted(face_nodes(m, faces))
        if boundary is not None and mine != boundary.get(r, []):
            bad("%s: region %d's faces are not the faces --boundary tags %d (%d vs %d)"
                % (name, r, r, len(mine), len(boundary.get(r, []))))
        # on the input surface
        if spheres:
            c, rad = spheres[tag_names[r - 1]]
            p = m.pts()[:, m.pid_in_regions(r)].T
            ratio = np.linalg.norm(p - c, axis=1) / rad
            if ratio.min() < 0.98 or ratio.max() > 1 + 1e-9:
                bad("%s: region %d's nodes at %.4f..%.4f of the radius of %s"
                    % (name, r, ratio.min(), ratio.max(), tag_names[r - 1]))
            else:
                counts[-1] += " on %s (radius ratio %.4f..%.4f)" % (tag_names[r - 1], ratio.min(), ratio.max())
    missing = len(outer_set - set(seen))
    if missing:
        bad("%s: %d of the %d outer faces in no region" % (name, missing, len(outer_set)))
    else:
        ok("%s: %d points, %d convexes; %s; together exactly the %d outer faces%s (%.2f s)"
           % (name, m.nbpts(), m.nbcvs(), "; ".join(counts), len(outer_set),
              ", the faces --boundary tags" if boundary is not None else "", time.time() - t0))
    return m


def patch_test(name, m, dirichlet, neumann):
    """u = g on the Dirichlet regions, du/dn = A.n on the Neumann ones."""
    t0 = time.time()
    gts, cv2gt = m.geotrans()
    mf = gf.MeshFem(m, 1)
    mimb = gf.MeshIm(m, 4)
    for i, g in enumerate(gts):
        sel = np.flatnonzero(cv2gt == i)
        mf.set_fem(gf.Fem(FEM[g.char()]), sel)
        if g.char() == "GT_PYRAMID(1)":
            mimb.set_integ(gf.Integ(PYRAMID_BOUNDARY_IM), sel)
    mim = gf.MeshIm(m, 4)   # classical rules, per type
    # g at the mesh points: each dof is a vertex of its convexes
    cvs = np.arange(m.nbcvs())
    dofs, didx = mf.basic_dof_from_cvid(cvs)
    pids, pidx = m.pid_from_cvid(cvs)
    if not np.array_equal(didx, pidx):
        bad("%s: dofs and points per convex differ in number" % name)
        return
    point_of_dof = np.full(mf.nbdof(), -1, dtype=np.int64)
    point_of_dof[dofs] = pids
    if (point_of_dof < 0).any() or not np.array_equal(point_of_dof[dofs], pids):
        bad("%s: a P1 dof is not one mesh point" % name)
        return
    gval = m.pts()[:, point_of_dof].T @ A + B
    md = gf.Model("real")
    md.add_fem_variable("u", mf)
    md.add_initialized_data("a", A)
    md.add_Laplacian_brick(mim, "u")
    md.add_initialized_fem_data("g", mf, gval)
    for r in dirichlet:
        md.add_Dirichlet_condition_with_simplification("u", r, "g")
    for r in neumann:
        md.add_source_term(mimb, "(a.Normal)*Test_u", r)
    md.solve()
    u = md.variable("u")
    err = np.abs(u - gval).max() / np.abs(gval).max()
    msg = ("%s: patch test, Dirichlet on %s, Neumann on %s: max |u - g| / max |g| = %.2e "
           "(%d dofs, %.2f s)" % (name, dirichlet, neumann or "none", err, mf.nbdof(), time.time() - t0))
    (ok if err < TOL else bad)(msg + ("" if err < TOL else ", limit %g" % TOL))


def materials_case(mixoct, work, spheres):
    """Several materials (issue 26): the sphere and the inner sphere with
    --materials, numbered 3 and 8 (--material): GetFEM loads a region of
    whole convexes per material (1000 + its number), which together are
    every convex once, the interface as a face region (tag 2), and the
    inner material's volume (GetFEM's convex_area) within the staircase's
    error (15% at -s 4) of the inner sphere's."""
    out = os.path.join(work, "materials.getfem")
    cmd = [mixoct, "-i", os.path.join(work, "sphere.off"), "--material", "3:outer",
           "-i", os.path.join(work, "inner.off"), "--material", "8:inner", "-s", "4",
           "--materials", "-o", out, "--quiet"]
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        bad("%s: exit %d\n%s" % (" ".join(cmd), p.returncode, p.stderr[-2000:]))
        return
    m = gf.Mesh("load", out)
    regions = list(m.regions())
    if 1003 not in regions or 1008 not in regions or 2 not in regions:
        bad("materials: regions %s, wanted 1003, 1008 and the interface 2" % regions)
        return
    a, b = m.region(1003), m.region(1008)
    whole = bool(np.all(a[1] == 65535)) and bool(np.all(b[1] == 65535))
    cvs = np.sort(np.concatenate([a[0], b[0]]))
    every = cvs.size == m.nbcvs() and bool(np.all(cvs == np.arange(m.nbcvs())))
    (ok if whole and every else bad)(
        "materials: regions 1003 (%d convexes) and 1008 (%d) whole convexes, every convex "
        "once" % (a.shape[1], b.shape[1]))
    vin = float(np.sum(m.convex_area(b[0])))
    c, r = spheres["inner.off"]
    exact = 4.0 / 3.0 * np.pi * r ** 3
    (ok if abs(vin - exact) < 0.15 * exact else bad)(
        "materials: inner material's volume %.4f, the inner sphere's %.4f" % (vin, exact))
    nif = m.region(2).shape[1]
    (ok if nif > 0 else bad)("materials: the interface region holds %d faces" % nif)


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    mixoct, work = sys.argv[1], sys.argv[2]
    data = sys.argv[3] if len(sys.argv) > 3 and sys.argv[3] else None
    os.makedirs(work, exist_ok=True)
    gf.util_trace_level(0)
    gf.util_warning_level(0)
    pyramid_face_note()
    spheres = make_surfaces(work)
    S = lambda n: os.path.join(work, n)
    cases = [
        ("shell", ["sphere.off", "inner.off"], 4, [1], [2]),
        ("spheres", ["sphere.off", "inner.off", "right.off"], 4, [1, 3], [2]),
    ]
    cortex = os.path.join(data, "surfaces", "cortex.off") if data else None
    if cortex and os.path.isfile(cortex):
        cases.append(("cortex", [cortex], 5, [1], []))
    else:
        note("cortex.off not found (DATA_DIR %s): the cortex case is skipped" % data)
    for name, inputs, level, dirichlet, neumann in cases:
        paths = [i if os.path.isabs(i) else S(i) for i in inputs]
        out = S(name)
        j = run_mixoct(mixoct, paths, level, out)
        if j is None:
            continue
        print("%s: mixoct -s %d %s: %d nodes, %d elements (%.2f s)"
              % (name, level, " ".join(os.path.basename(p) for p in paths), j["nodes"], j["elements"], j["_seconds"]),
              flush=True)
        names = [os.path.basename(p) for p in paths]
        boundary = read_boundary_vtu(out + "_boundary.vtu")
        m = check_mesh(name, out + ".getfem", j, names,
                       spheres if name != "cortex" else None, boundary)
        if m is not None:
            patch_test(name, m, dirichlet, neumann)
    materials_case(mixoct, work, spheres)
    print("getfem tags: %s" % ("all checks passed" if not fails else "%d check(s) failed" % fails))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
