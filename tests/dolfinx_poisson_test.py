#!/usr/bin/python3
"""dolfinx solves on mixoct's tetrahedral meshes (--tets, mx_params.tets;
issue 30, item 2): a solver that takes one cell type.

Run by meson (test 'dolfinx_poisson') with PYTHONPATH=<build>/python, or by
hand:

    PYTHONPATH=<build>/python /usr/bin/python3 tests/dolfinx_poisson_test.py

The unit cube, from arrays (8 vertices, 12 triangles), meshed with
Mesher(surface_level=L, all_level=L, tets=True) at L = 2, 3, 4 (octants of
side about 1 / 2^L everywhere, so h halves from level to level). Each mesh
must be all tetrahedra, every one of positive volume (computed here), and
fill the cube (the sum of their volumes 1 within 1e-9: the cube's edges
and corners are kept as features). It is handed to dolfinx
(dolfinx.mesh.create_mesh with a P1 tetrahedron coordinate element,
dolfinx 0.5 on Debian 12) and -div grad u = f is solved with P1 elements,
u = sin(x) exp(y) + z^3 (f from it by UFL), Dirichlet data the
interpolant of u on the whole boundary. The L2 error against the exact u
(quadrature of degree 6) must fall at a rate above 1.5 between successive
levels (P1 on quasi-uniform meshes: 2). The rates are printed.

Without dolfinx (Debian: python3-dolfinx) it prints SKIP and exits 77
(meson's "skipped"), unless CI is set, where that is a failure. A few
seconds (dolfinx compiles its forms once, in its cache).
"""

import sys
import time

import testlib
from testlib import skip


try:
    import numpy as np
    import ufl
    from mpi4py import MPI
    from dolfinx import fem
    from dolfinx import mesh as dmesh
    from dolfinx.fem.petsc import LinearProblem
except ImportError as e:
    skip("dolfinx missing (%s; apt-get install --no-install-recommends "
         "python3-dolfinx)" % e, "dolfinx")

import mixoct  # noqa: E402

CUBE_V = np.array(testlib.CUBE_V, float)
CUBE_T = np.array(testlib.CUBE_T, np.uint32)
LEVELS = (2, 3, 4)
MIN_RATE = 1.5

check = testlib.Checks()


def exact_np(p):
    return testlib.exact(p[0], p[1], p[2], np)


def tet_mesh(level):
    """The cube's tetrahedra: nodes (n x 3), cells (m x 4)."""
    m = mixoct.Mesher(surface_level=level, all_level=level, tets=True)
    m.add_surface_arrays(CUBE_V, CUBE_T)
    m.mesh()
    a = m.arrays(copy=True)
    types = a["types"]
    check(len(types) > 0 and bool((types == mixoct.TET).all()),
          "level %d: %d cells, all tetrahedra" % (level, len(types)))
    x = np.ascontiguousarray(a["nodes"], dtype=np.float64)
    cells = np.ascontiguousarray(a["conn"][:, :4], dtype=np.int64)
    p = x[cells]
    vol = np.einsum("ij,ij->i", p[:, 1] - p[:, 0],
                    np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])) / 6.0
    check(vol.min() > 0, "level %d: every tetrahedron of positive volume (least %.3g)"
          % (level, vol.min()))
    check(abs(vol.sum() - 1.0) < 1e-9, "level %d: volume %.15g (the cube's: 1)"
          % (level, vol.sum()))
    m.close()
    return x, cells


def solve(x, cells):
    """The P1 solution's L2 error on the mesh."""
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", "tetrahedron", 1))
    msh = dmesh.create_mesh(MPI.COMM_SELF, cells, x, domain)
    V = fem.FunctionSpace(msh, ("Lagrange", 1))
    X = ufl.SpatialCoordinate(msh)
    uex = ufl.sin(X[0]) * ufl.exp(X[1]) + X[2] ** 3
    f = -ufl.div(ufl.grad(uex))
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim - 1, tdim)
    facets = dmesh.exterior_facet_indices(msh.topology)
    uD = fem.Function(V)
    uD.interpolate(exact_np)
    bc = fem.dirichletbc(uD, fem.locate_dofs_topological(V, tdim - 1, facets))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    problem = LinearProblem(ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx, f * v * ufl.dx,
                            bcs=[bc], petsc_options={"ksp_type": "cg", "pc_type": "gamg",
                                                     "ksp_rtol": 1e-12})
    uh = problem.solve()
    dx = ufl.Measure("dx", domain=msh, metadata={"quadrature_degree": 6})
    return float(np.sqrt(fem.assemble_scalar(fem.form((uh - uex) ** 2 * dx))))


def main():
    errors = []
    for level in LEVELS:
        t0 = time.time()
        x, cells = tet_mesh(level)
        e = solve(x, cells)
        errors.append(e)
        rate = np.log2(errors[-2] / e) if len(errors) > 1 else float("nan")
        print("level %d: %d nodes, %d tetrahedra, L2 error %.4e, rate %.2f (%.2f s)"
              % (level, len(x), len(cells), e, rate, time.time() - t0), flush=True)
        if len(errors) > 1:
            check(rate > MIN_RATE, "level %d -> %d: L2 rate %.2f > %.1f"
                  % (level - 1, level, rate, MIN_RATE))
    if check.fails:
        print("%d check(s) failed" % check.fails)
        sys.exit(1)


if __name__ == "__main__":
    main()
