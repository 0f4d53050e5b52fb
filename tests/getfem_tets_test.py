#!/usr/bin/python3
"""GetFEM solves the same problem on the mixed mesh and on its tetrahedra
(--tets, mx_params.tets; issue 30, item 2).

Run by meson (test 'getfem_tets') with PYTHONPATH=<build>/python, or by
hand:

    PYTHONPATH=<build>/python /usr/bin/python3 tests/getfem_tets_test.py

The unit cube, from arrays, meshed at L = 2, 3, 4 (surface_level =
all_level = L) twice from the same octree: mixed (tets=False) and split
(tets=True); both written as .getfem by the library and loaded with
getfem.Mesh('load'). Checked on each pair:
  - the same leaves; the tetrahedral mesh's points begin with the mixed
    mesh's, the same coordinates (Steiner nodes only appended);
  - boundary tags: region 1 (the one input) is exactly GetFEM's outer faces
    on both meshes, and the tetrahedral mesh has 2 per outer quadrilateral
    face of the mixed mesh and 1 per outer triangle (each quadrilateral
    cut in two, nothing else on the boundary);
  - -div grad u = f with u = sin(x) exp(y) + z^3 (f = -6z), P1 elements
    (FEM_PK(3,1), FEM_PYRAMID_LAGRANGE(1), FEM_PK_PRISM(3,1), FEM_QK(3,1),
    as tests/getfem_tags_test.py uses them), Dirichlet data u at the mesh
    points on all outer faces. The L2 error against u (integration of
    degree 6) must fall at a rate above 1.5 between successive levels on
    both meshes (P1: 2);
  - the two solutions at the shared mesh points: both are second-order
    approximations of u on the same points, so their difference is O(h^2)
    too. Required: the largest difference falls at a rate above 1.5 from
    level to level, and is below the larger of the two largest nodal
    errors (|u_h - u| at the points) of the level before, i.e. the two
    discretizations differ by less than one coarsening changes either.
    (Not "below the errors of the same level": the triangle inequality
    makes that hold whatever the solutions are.)
Rates, errors and differences are printed.

Without getfem (Debian: python3-getfem) it prints SKIP and exits 77,
unless CI is set, where that is a failure. A few seconds.
"""

import os
import shutil
import sys
import tempfile
import time

import testlib
from testlib import skip


try:
    import numpy as np
    import getfem as gf
except ImportError as e:
    skip("numpy or getfem missing (%s; apt-get install --no-install-recommends "
         "python3-numpy python3-getfem)" % e, "GetFEM")

import mixoct  # noqa: E402

CUBE_V = np.array(testlib.CUBE_V, float)
CUBE_T = np.array(testlib.CUBE_T, np.uint32)
FEM = {"GT_PK(3,1)": "FEM_PK(3,1)", "GT_PYRAMID(1)": "FEM_PYRAMID_LAGRANGE(1)",
       "GT_PRISM(3,1)": "FEM_PK_PRISM(3,1)", "GT_QK(3,1)": "FEM_QK(3,1)"}
EXACT = "(sin(X(1))*exp(X(2))+pow(X(3),3))"
SOURCE = "(-6*X(3))"  # -div grad u
LEVELS = (2, 3, 4)
MIN_RATE = 1.5
MIN_DIFF_RATE = 1.2

check = testlib.Checks()


def exact(p):
    return testlib.exact(p[:, 0], p[:, 1], p[:, 2], np)


def outer_face_counts(m):
    """GetFEM's outer faces, as (triangles, quadrilaterals)."""
    faces = m.outer_faces()
    tri = quad = 0
    for cv, f in faces.T:
        n = len(m.pid_in_faces(np.array([[cv], [f]])))
        tri += n == 3
        quad += n == 4
    return tri, quad, faces


def solve(path):
    """Load, solve; the mesh, L2 error, points, u at the points, and the
    largest nodal error."""
    m = gf.Mesh("load", path)
    gts, cv2gt = m.geotrans()
    if not isinstance(gts, (list, tuple)):
        gts = [gts]
    mf = gf.MeshFem(m, 1)
    for i, g in enumerate(gts):
        mf.set_fem(gf.Fem(FEM[g.char()]), np.flatnonzero(cv2gt == i))
    mim = gf.MeshIm(m, 4)
    mim_err = gf.MeshIm(m, 6)
    cvs = np.arange(m.nbcvs())
    dofs, _ = mf.basic_dof_from_cvid(cvs)
    pids, _ = m.pid_from_cvid(cvs)
    point_of_dof = np.full(mf.nbdof(), -1, dtype=np.int64)
    point_of_dof[dofs] = pids  # each P1 dof is a vertex of its convexes
    P = m.pts().T
    md = gf.Model("real")
    md.add_fem_variable("u", mf)
    md.add_Laplacian_brick(mim, "u")
    md.add_source_term(mim, SOURCE + "*Test_u")
    md.add_initialized_fem_data("g", mf, exact(P[point_of_dof]))
    md.add_Dirichlet_condition_with_simplification("u", 1, "g")
    md.solve()
    u = md.variable("u")
    err = float(np.sqrt(gf.asm_generic(mim_err, 0, "sqr(u - %s)" % EXACT, -1, md)))
    at_point = np.full(m.nbpts(), np.nan)
    at_point[point_of_dof] = u
    return m, err, P, at_point, float(np.nanmax(np.abs(at_point - exact(P))))


def main():
    gf.util_trace_level(0)
    gf.util_warning_level(0)
    work = tempfile.mkdtemp(prefix="mixoct_getfem_tets_")
    rows = []
    try:
        for level in LEVELS:
            t0 = time.time()
            out = {}
            for tets in (False, True):
                me = mixoct.Mesher(surface_level=level, all_level=level, tets=tets)
                me.add_surface_arrays(CUBE_V, CUBE_T)
                me.mesh()
                path = os.path.join(work, "cube%d_%s.getfem" % (level, "tets" if tets else "mixed"))
                me.write(path)
                out[tets] = (me.nleaves, me.counts) + solve(path)
                me.close()
            (l0, c0, m0, e0, P0, u0, n0), (l1, c1, m1, e1, P1, u1, n1) = out[False], out[True]
            check(l0 == l1, "level %d: the same octree (%d, %d leaves)" % (level, l0, l1))
            check(c1["tet"] == m1.nbcvs() and c1["hex"] + c1["prism"] + c1["pyramid"] == 0,
                  "level %d: mixed %s -> %d tetrahedra" % (level, c0, m1.nbcvs()))
            n = len(P0)
            check(len(P1) >= n and np.array_equal(P0, P1[:n]),
                  "level %d: %d points, then %d Steiner points" % (level, n, len(P1) - n))
            tri0, quad0, faces0 = outer_face_counts(m0)
            tri1, quad1, faces1 = outer_face_counts(m1)
            for name, m, faces in (("mixed", m0, faces0), ("tets", m1, faces1)):
                reg = set(map(tuple, m.region(1).T.tolist()))
                check(reg == set(map(tuple, faces.T.tolist())),
                      "level %d, %s: region 1 is the %d outer faces" % (level, name, faces.shape[1]))
            check(quad1 == 0 and tri1 == 2 * quad0 + tri0,
                  "level %d: outer faces %d quads + %d triangles -> %d triangles"
                  % (level, quad0, tri0, tri1))
            diff = float(np.max(np.abs(u0[:n] - u1[:n])))
            rows.append((level, e0, e1, n0, n1, diff))
            print("level %d: L2 error mixed %.4e, tets %.4e; largest nodal error %.3e, %.3e; "
                  "largest difference %.3e (%.2f s)" % (level, e0, e1, n0, n1, diff,
                                                         time.time() - t0), flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    for (la, ea0, ea1, na0, na1, da), (lb, eb0, eb1, nb0, nb1, db) in zip(rows, rows[1:]):
        r0, r1, rd = np.log2(ea0 / eb0), np.log2(ea1 / eb1), np.log2(da / db)
        check(r0 > MIN_RATE and r1 > MIN_RATE,
              "level %d -> %d: L2 rate mixed %.2f, tets %.2f (> %.1f)" % (la, lb, r0, r1, MIN_RATE))
        check(rd > MIN_DIFF_RATE, "level %d -> %d: the difference falls at rate %.2f (> %.1f)"
              % (la, lb, rd, MIN_DIFF_RATE))
        check(db < max(na0, na1), "level %d: difference %.3e below level %d's largest nodal "
              "error %.3e" % (lb, db, la, max(na0, na1)))
    if check.fails:
        print("%d check(s) failed" % check.fails)
        sys.exit(1)


if __name__ == "__main__":
    main()
