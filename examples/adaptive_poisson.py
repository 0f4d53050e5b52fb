#!/usr/bin/python3
"""Simulate, estimate, refine: the adaptive loop of Jaillet & Lobos (2021).

mixoct meshes a domain (the built-in demo surface, or --surface FILE); GetFEM
solves the Poisson problem

    -Laplace(u) = f  in the domain,    u = u_exact  on its boundary,

on that mesh, with every element type as it is (tetrahedra, pyramids,
prisms, hexahedra: P1, the rational pyramid, P1 x P1 prism and Q1 Lagrange
elements, one GetFEM convex per mixoct element). The exact solution has a
sharp feature, a steep Gaussian bump

    u_exact(x) = exp(-|x - c|^2 / (2 s^2)),   f = u_exact (3/s^2 - |x - c|^2/s^4),

with s = --width (default 4 %) of the domain's largest extent and c an
interior point near the middle of the domain (or --center). The error of
each element (its share of |u_h - u_exact|^2 in the H1 semi-norm, or L2 with
--estimator l2) is summed per octree leaf (the unit that gets split); the
bulk (Doerfler) criterion marks the fewest leaves holding --theta (0.7) of
the squared error (--mark elements: the same over the elements), and
Mesher.refine_elements, given every element of the marked leaves, splits
those leaves once (Algorithm 3), restores balance and meshes again.

--refine sizemap turns the estimate into a size field instead (issue 27): an
element's error goes as h^2.5 (P1, 3D), so each element above the target
error (--reduction times the root mean square of the elements' errors) gets
the size that would bring it there, and Mesher.set_size_elements (each size
over its element's box; --at centroids: set_size_points at the centroids)
with Mesher.refine refines the octree to the field, several levels at once
where the error asks for it (bench/adaptive_sizemap_bench.sh compares the
two ways).

The meshes of successive rounds are not nested (transition elements are
re-patterned, surface nodes move), so the error is not bound to fall every
round while the bump is under-resolved; with the defaults (-s 4, theta 0.7)
it does on the demo surface. Each round prints the nodes, the elements by type,
the global errors, and the seconds spent in mixoct (meshing) and in GetFEM
(mesh conversion, assembly, solve, estimate).

    PYTHONPATH=build/python /usr/bin/python3 examples/adaptive_poisson.py
    ... --surface ../shared/data/surfaces/cortex.off -s 4 --rounds 5
    ... --check /tmp/rounds --json     # the meshes (.vtu) and JSON lines

Timing: the mixoct calls use OpenMP threads (--threads); on a machine
shared with other jobs, OMP_WAIT_POLICY=passive keeps idle threads from
spinning (tests/python_test.sh sets it).

--linear-check also solves with a linear exact solution, which every
element reproduces exactly when the geometric transformations and the node
orders are right: its error (printed as lin_err) must be at rounding level.

Node orders (mixoct: VTK's for tet, pyramid, hex, Gmsh's for prisms;
GetFEM: its reference convexes, checked with getfem.GeoTrans(...).pts()):

    tet     GT_PK(3,1)     GetFEM (0 1 2 3)         = mixoct (0 1 2 3)
    pyramid GT_PYRAMID(1)  GetFEM (0 1 2 3 4)       = mixoct (0 1 3 2 4)
    prism   GT_PRISM(3,1)  GetFEM (0 1 2 3 4 5)     = mixoct (0 1 2 3 4 5)
    hex     GT_QK(3,1)     GetFEM (0 1 2 3 4 5 6 7) = mixoct (0 1 3 2 4 5 7 6)

(the quadrilaterals go in tensor order in GetFEM, around the face in VTK;
Gmsh's prism and GetFEM's both turn 0 1 2 towards 3 4 5). --verify-orders
checks, through GetFEM itself, that the Jacobian determinant is positive at
every quadrature point of every element.
"""

import argparse
import json
import os
import sys
import time

import numpy as np

try:
    import getfem as gf
except ImportError:  # pragma: no cover - reported by main()
    gf = None

import mixoct

# GetFEM's geometric transformations and, for each, GetFEM's node k is
# mixoct's node GF_ORDER[t][k] (the same table as src/io/write_getfem.c).
GF_GEOTRANS = ("GT_PK(3,1)", "GT_PYRAMID(1)", "GT_PRISM(3,1)", "GT_QK(3,1)")
GF_FEM = ("FEM_PK(3,1)", "FEM_PYRAMID_LAGRANGE(1)", "FEM_PK_PRISM(3,1)",
          "FEM_QK(3,1)")
GF_FEM0 = ("FEM_PK(3,0)", "FEM_PYRAMID_LAGRANGE(0)", "FEM_PK_PRISM(3,0)",
           "FEM_QK(3,0)")
GF_ORDER = ((0, 1, 2, 3), (0, 1, 3, 2, 4), (0, 1, 2, 3, 4, 5),
            (0, 1, 3, 2, 4, 5, 7, 6))


# ---- the GetFEM side -----------------------------------------------------------

class GetfemMesh:
    """A GetFEM mesh of a mixoct mesh: one convex per element.

    cv_of_elem[e] is element e's convex, elem_of_cv the inverse (convexes are
    added type by type, so their numbers differ from the elements')."""

    def __init__(self, nodes, conn, types):
        nodes = np.asarray(nodes, dtype=np.float64)
        ne = len(types)
        self.mesh = m = gf.Mesh("empty", 3)
        pids = m.add_point(nodes.T)
        if m.nbpts() != len(nodes) or not np.array_equal(
                pids, np.arange(len(nodes))):
            raise RuntimeError("GetFEM merged mixoct nodes closer than its "
                               "point tolerance (%d of %d points kept)"
                               % (m.nbpts(), len(nodes)))
        self.cv_of_elem = np.empty(ne, dtype=np.int64)
        for t in range(4):
            sel = np.flatnonzero(types == t)
            if sel.size == 0:
                continue
            rows = conn[sel][:, GF_ORDER[t]].astype(np.int64)
            # dim x nodes-per-convex x convexes, as add_convex wants it
            pts = np.ascontiguousarray(np.transpose(nodes[rows], (2, 1, 0)))
            ids = m.add_convex(gf.GeoTrans(GF_GEOTRANS[t]),
                               np.asfortranarray(pts))
            self.cv_of_elem[sel] = np.asarray(ids, dtype=np.int64).ravel()
        if m.nbpts() != len(nodes) or m.nbcvs() != ne:
            raise RuntimeError("GetFEM mesh: %d points, %d convexes for %d "
                               "nodes, %d elements" % (m.nbpts(), m.nbcvs(),
                                                       len(nodes), ne))
        self.elem_of_cv = np.empty(ne, dtype=np.int64)
        self.elem_of_cv[self.cv_of_elem] = np.arange(ne)
        self.types = np.asarray(types)

    def set_fems(self, mf, fems):
        for t in range(4):
            sel = np.flatnonzero(self.types == t)
            if sel.size:
                mf.set_fem(gf.Fem(fems[t]), self.cv_of_elem[sel])


class Poisson:
    """-Laplace(u) = f with u = g on the whole boundary, on a GetFEM mesh."""

    BND = 1

    def __init__(self, gm, degree=4, err_degree=6, solver="auto"):
        self.gm = gm
        m = gm.mesh
        self.mf = gf.MeshFem(m, 1)
        gm.set_fems(self.mf, GF_FEM)
        self.mim = gf.MeshIm(m, degree)       # classical rules, per type
        self.mim_err = gf.MeshIm(m, err_degree)
        m.set_region(self.BND, m.outer_faces())
        self.solver = solver
        self.dof_xyz = self.mf.basic_dof_nodes().T   # (ndof, 3)
        self._mfk = None       # P0 fem(s) for per-element integrals

    def solve(self, data, f_expr, g_nodal):
        """data: {name: value} for the expressions; f_expr: GWFL of f;
        g_nodal: the Dirichlet values at the dofs (numpy)."""
        md = gf.Model("real")
        md.add_fem_variable("u", self.mf)
        for k, v in data.items():
            md.add_initialized_data(k, v)
        md.add_Laplacian_brick(self.mim, "u")
        if f_expr:
            # a source term: the right-hand side (add_linear_term would put
            # it on the left, i.e. with the opposite sign)
            md.add_source_term(self.mim, "(%s)*Test_u" % f_expr)
        # nodal values from numpy: GetFEM's own interpolation of an
        # expression in X is off by ~1e-6 at pyramid apexes (the rational
        # basis is singular there)
        md.add_initialized_fem_data("g", self.mf, g_nodal)
        md.add_Dirichlet_condition_with_simplification("u", self.BND, "g")
        if self.solver == "auto":
            md.solve()
        else:
            md.solve("lsolver", self.solver)
        self.md = md
        return md.variable("u")

    def per_element(self, *exprs):
        """The integrals of the expressions over each element: an array
        (nelements, len(exprs)) in element order, from one assembly."""
        k = len(exprs)
        if self._mfk is None or self._mfk.qdim() != k:
            self._mfk = gf.MeshFem(self.gm.mesh, k)   # k P0 dofs per element
            self.gm.set_fems(self._mfk, GF_FEM0)
            d = self._mfk.basic_dof_from_cv(np.arange(self.gm.mesh.nbcvs()))
            d = np.asarray(d, dtype=np.int64).reshape(-1, k)
            self._dofs_k = d[self.gm.cv_of_elem]
        z = np.zeros(self._mfk.nbdof())
        v = gf.asm_generic(self.mim_err, 1,
                           "[%s].Test_p" % ", ".join(exprs), -1,
                           self.md, "p", 1, self._mfk, z,
                           "select_output", "p")
        return np.asarray(v)[self._dofs_k]

    def min_jacobian_sign_check(self):
        """The number of elements of each type with a quadrature point (of
        the error integrals) where the Jacobian determinant of GetFEM's
        geometric transformation is <= 0 (after solve())."""
        v = self.per_element("Heaviside(-Det(element_K))")[:, 0]
        bad = v > 0
        return [int(np.count_nonzero(bad & (self.gm.types == t)))
                for t in range(4)]


def gaussian_problem(c, s):
    """Data, GWFL expressions and numpy function of the Gaussian bump."""
    data = {"c": np.asarray(c, dtype=np.float64), "s2": float(s) ** 2}
    u = "exp(-Norm_sqr(X-c)/(2*s2))"
    exprs = {
        "u": u,
        "f": "%s*(3/s2 - Norm_sqr(X-c)/(s2*s2))" % u,
        "grad": "(-(X-c)/s2*%s)" % u,
    }

    def u_np(x):
        r2 = np.sum((x - data["c"]) ** 2, axis=1)
        return np.exp(-r2 / (2 * data["s2"]))

    return data, exprs, u_np


def linear_problem():
    a = np.array([0.3, -1.7, 2.1])
    data = {"a": a, "b": 5.0}
    exprs = {"u": "(a.X + b)", "f": None, "grad": "a"}
    return data, exprs, (lambda x: x @ a + 5.0)


def solve_and_estimate(pb, problem):
    """Solve; per element: |u_h - u|^2 (L2), |grad(u_h - u)|^2 (H1 semi-norm)
    and |grad u|^2 (for the relative error)."""
    data, ex, u_np = problem
    U = pb.solve(data, ex["f"], u_np(pb.dof_xyz))
    e = pb.per_element("sqr(u - %s)" % ex["u"],
                       "Norm_sqr(Grad_u - %s)" % ex["grad"],
                       "Norm_sqr(%s)" % ex["grad"])
    e = np.maximum(e, 0.0)
    return U, e[:, 0], e[:, 1], float(np.sum(e[:, 2]))


def element_centroids(nodes, conn, types):
    """Each element's centroid (the mean of its nodes)."""
    nn = np.array(mixoct.NODES_PER_TYPE)[types]
    pad = conn == mixoct.NO_NODE
    xyz = nodes[np.where(pad, 0, conn)]
    xyz[pad] = 0.0
    return xyz.sum(axis=1) / nn[:, None]


def size_map(nodes, conn, types, err2, reduction):
    """A size per element from the estimate: an element's error goes as
    h^(p + d/2) = h^2.5 (P1, 3D), so an element of size h (its box's
    largest side) and squared error e2 reaches the target error t =
    reduction * rms(error) at the size h (t / sqrt(e2))^0.4; elements
    already below the target keep their size (1e300: no request). The
    octree is refined, never coarsened, by the field (graded: sizes grow by
    at most 2 between neighbours)."""
    nn = np.array(mixoct.NODES_PER_TYPE)[types]
    pad = conn == mixoct.NO_NODE
    xyz = nodes[np.where(pad, 0, conn)]
    lo = np.where(pad[:, :, None], np.inf, xyz).min(axis=1)
    hi = np.where(pad[:, :, None], -np.inf, xyz).max(axis=1)
    h = (hi - lo).max(axis=1)
    del nn
    e = np.sqrt(np.maximum(err2, 0.0))
    t = reduction * np.sqrt(np.mean(err2))
    out = np.full(len(h), 1e300)
    big = e > t
    out[big] = h[big] * (t / e[big]) ** 0.4
    return out


def doerfler(err2, theta):
    """The fewest elements whose squared errors add up to theta of the total."""
    order = np.argsort(-err2, kind="stable")
    csum = np.cumsum(err2[order])
    if csum[-1] <= 0:
        return order[:0]
    k = int(np.searchsorted(csum, theta * csum[-1])) + 1
    return order[:min(k, len(order))]


# ---- the loop ---------------------------------------------------------------------

def parse_args(argv):
    ap = argparse.ArgumentParser(
        description="Adaptive Poisson solve with mixoct and GetFEM "
                    "(simulate, estimate, refine).")
    ap.add_argument("--surface", action="append", default=[],
                    help="a closed surface (OFF, MDL, STL, OBJ; repeatable); "
                         "default: the built-in demo surface")
    ap.add_argument("-s", "--surface-level", type=int, default=4,
                    help="initial refinement level at the surface (4)")
    ap.add_argument("-a", "--all-level", type=int, default=-1,
                    help="initial level of every octant (-1: none)")
    ap.add_argument("--rounds", type=int, default=5,
                    help="solve-estimate-refine rounds (5)")
    ap.add_argument("--theta", type=float, default=0.7,
                    help="Doerfler bulk fraction of the squared error to "
                         "refine (0.7)")
    ap.add_argument("--refine", choices=("mark", "sizemap"), default="mark",
                    help="mark: Doerfler marking, the marked leaves split once "
                         "(default); sizemap: a size per element from the "
                         "error estimate, handed to mixoct as a size field")
    ap.add_argument("--reduction", type=float, default=0.5,
                    help="sizemap: each element's target error, this times "
                         "the root mean square of the elements' errors (0.5)")
    ap.add_argument("--at", choices=("elements", "centroids"), default="elements",
                    help="sizemap: each size over its element's box "
                         "(set_size_elements) or at its centroid (set_size_points)")
    ap.add_argument("--gradation", type=float, default=0.0,
                    help="sizemap: the field's gradation ratio (0: mixoct's "
                         "default, 2)")
    ap.add_argument("--mark", choices=("leaves", "elements"), default="leaves",
                    help="Doerfler over the octree leaves (each leaf's error "
                         "the sum of its elements') or over the elements "
                         "(leaves)")
    ap.add_argument("--estimator", choices=("h1", "l2"), default="h1",
                    help="per-element error that marks elements (h1)")
    ap.add_argument("--width", type=float, default=0.04,
                    help="Gaussian width s over the largest extent (0.04)")
    ap.add_argument("--center", default=None,
                    help="x,y,z of the bump (default: an interior node near "
                         "the middle of the domain)")
    ap.add_argument("--degree", type=int, default=4,
                    help="quadrature degree of the assembly (4)")
    ap.add_argument("--err-degree", type=int, default=6,
                    help="quadrature degree of the error integrals (6)")
    ap.add_argument("--solver", default="auto",
                    choices=("auto", "mumps", "cg/ildlt", "gmres/ilu"),
                    help="GetFEM linear solver (auto: MUMPS here; 'superlu' "
                         "is left out: it crashes in Debian's "
                         "python3-getfem 5.4)")
    ap.add_argument("--threads", type=int, default=0,
                    help="mixoct threads (0: OpenMP's default)")
    ap.add_argument("--linear-check", action="store_true",
                    help="also solve a linear exact solution each round "
                         "(must be exact: proves the node orders)")
    ap.add_argument("--verify-orders", action="store_true",
                    help="check det(J) > 0 at every quadrature point "
                         "through GetFEM, each round")
    ap.add_argument("--check", metavar="DIR",
                    help="write each round's mesh as DIR/round<k>.vtu")
    ap.add_argument("--json", action="store_true",
                    help="one JSON line per round at the end")
    return ap.parse_args(argv)


def pick_center(nodes, boundary):
    mid = 0.5 * (nodes.min(axis=0) + nodes.max(axis=0))
    inner = np.flatnonzero(boundary == 0)
    if inner.size == 0:
        return mid
    k = inner[np.argmin(np.sum((nodes[inner] - mid) ** 2, axis=1))]
    return nodes[k].copy()


def main(argv=None):
    args = parse_args(argv)
    if gf is None:
        print("adaptive_poisson: python3-getfem is not installed",
              file=sys.stderr)
        return 77
    gf.util_trace_level(0)
    gf.util_warning_level(0)
    if args.check:
        os.makedirs(args.check, exist_ok=True)

    rows = []
    t_mesh_total = t_solve_total = 0.0
    with mixoct.Mesher(surface_level=args.surface_level,
                       all_level=args.all_level,
                       threads=args.threads) as mx:
        t0 = time.perf_counter()
        if args.surface:
            for s in args.surface:
                mx.add_surface(s)
        else:
            mx.add_demo_surface()
        mx.mesh()
        t_mesh = time.perf_counter() - t0
        problem = None
        marked = np.zeros(0, dtype=np.int64)
        hdr = ("%5s %8s %8s %7s %7s %7s %7s %11s %11s %9s %7s %7s"
               % ("round", "nodes", "elems", "tet", "pyr", "prism", "hex",
                  "L2 err", "H1 err", "rel H1", "mesh s", "solve s"))
        print(hdr)
        for rnd in range(args.rounds):
            if rnd > 0:
                t0 = time.perf_counter()
                if args.refine == "sizemap":
                    if args.gradation:
                        mx.set_gradation(args.gradation)
                    if args.at == "centroids":
                        ok = target < 1e300
                        mx.set_size_points(cen[ok], target[ok])
                    else:
                        mx.set_size_elements(target)
                    mx.refine()
                else:
                    mx.refine_elements(marked)
                t_mesh = time.perf_counter() - t0
            if args.check:
                mx.write(os.path.join(args.check, "round%d.vtu" % rnd))
            nodes, conn, types = mx.nodes, mx.conn, mx.types
            counts = mx.counts
            if problem is None:
                ext = float(np.max(nodes.max(axis=0) - nodes.min(axis=0)))
                c = (np.array([float(v) for v in args.center.split(",")])
                     if args.center else pick_center(nodes, mx.boundary))
                s = args.width * ext
                problem = gaussian_problem(c, s)

            # GetFEM: mesh, assembly, solve, per-element errors
            t0 = time.perf_counter()
            gm = GetfemMesh(nodes, conn, types)
            t_conv = time.perf_counter() - t0
            pb = Poisson(gm, args.degree, args.err_degree, args.solver)
            U, e_l2, e_h1, u_h1 = solve_and_estimate(pb, problem)
            t_solve = time.perf_counter() - t0
            lin_err = None
            if args.linear_check:
                Ul = solve_and_estimate(pb, linear_problem())[0]
                lin_err = float(np.max(np.abs(
                    Ul - linear_problem()[2](pb.dof_xyz))))
            bad_jac = pb.min_jacobian_sign_check() if args.verify_orders \
                else None

            err = e_h1 if args.estimator == "h1" else e_l2
            if args.refine == "sizemap":
                target = size_map(nodes, conn, types, err, args.reduction)
                cen = element_centroids(nodes, conn, types)
                marked = np.flatnonzero(np.isfinite(target) & (target < 1e300))
                nmarked_leaves = int(np.unique(mx.leaf[marked]).size)
            elif args.mark == "leaves":
                # a leaf is what gets split: mark leaves by their total error
                # and pass every element of a marked leaf
                leaf = mx.leaf
                lerr = np.bincount(leaf, weights=err, minlength=mx.nleaves)
                mleaves = doerfler(lerr, args.theta)
                hit = np.zeros(len(lerr), dtype=bool)
                hit[mleaves] = True
                marked = np.flatnonzero(hit[leaf])
                nmarked_leaves = int(mleaves.size)
                del leaf
            else:
                marked = doerfler(err, args.theta)
                nmarked_leaves = int(np.unique(mx.leaf[marked]).size)
            row = {
                "round": rnd,
                "nodes": int(len(nodes)),
                "elements": int(len(types)),
                "by_type": counts,
                "leaves": int(mx.nleaves),
                "dofs": int(pb.mf.nbdof()),
                "l2": float(np.sqrt(np.sum(e_l2))),
                "h1": float(np.sqrt(np.sum(e_h1))),
                "rel_h1": float(np.sqrt(np.sum(e_h1) / u_h1)),
                "marked": int(marked.size),
                "marked_leaves": nmarked_leaves,
                "mesh_s": t_mesh,
                "solve_s": t_solve,
                "convert_s": t_conv,
                "jens_min": float(mx.jens_min),
            }
            if lin_err is not None:
                row["linear_max_err"] = lin_err
            if bad_jac is not None:
                row["bad_jacobian"] = dict(zip(mixoct.TYPE_NAMES, bad_jac))
            rows.append(row)
            t_mesh_total += t_mesh
            t_solve_total += t_solve
            line = ("%5d %8d %8d %7d %7d %7d %7d %11.4e %11.4e %9.4f %7.3f %7.3f"
                    % (rnd, row["nodes"], row["elements"], counts["tet"],
                       counts["pyramid"], counts["prism"], counts["hex"],
                       row["l2"], row["h1"], row["rel_h1"], t_mesh, t_solve))
            if lin_err is not None:
                line += "  lin_err %.1e" % lin_err
            if bad_jac is not None:
                line += "  det<=0 %s" % bad_jac
            print(line, flush=True)
            # drop the views of this mesh before the next re-mesh
            del nodes, conn, types
        if mx.warnings:
            print("mixoct warnings: %s" % "; ".join(mx.warnings))

    ratio = t_mesh_total / t_solve_total if t_solve_total > 0 else float("nan")
    print("seconds: meshing (mixoct) %.3f, solving (GetFEM: mesh conversion, "
          "assembly, solve, estimate) %.3f, mesh/solve %.3f"
          % (t_mesh_total, t_solve_total, ratio))
    if args.json:
        for row in rows:
            print(json.dumps(row, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
