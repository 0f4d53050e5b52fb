#!/usr/bin/env python3
"""A real solver on two materials (issue 26 item 7): GetFEM solves a
two-conductivity diffusion problem on mixoct's --materials meshes of two
concentric spheres, and the error must fall at the rate P1 elements promise
as the level goes up.

usage: getfem_materials_test.py MIXOCT WORKDIR [--levels 3,4,5] [--subdiv N]
           [--request -a|-s] [--control] [--table] [--keep]

Geometry: tests/make_surfaces.py's hollow ball shell.off (radius R2 = 1
with radius R1 = 0.5 inside, both about make_surfaces.CENTRE, the inner
one turned inward), meshed with `mixoct -i shell.off --materials -a L`.
Material 1 (GetFEM region 1001) is the shell R1 < r < R2, material 2
(region 1002) the inner ball (numbered by nesting depth); region 1 holds
the outer boundary's faces, region 2 the interface's. The test reads these
from the comments the .getfem writer puts in the file (src/io/
write_getfem.c) and asserts them.
The spheres are make_surfaces.unit_icosphere(N) placed as shell.off's
(N = 3 gives shell.off's points); by default N is the finest level, so
that the input's triangles (chord ~1.05 R/2^N) stay finer than the
octants (~2/2^L). Why not shell.off's 1280 triangles a sphere: the
tessellation is the interface the mesh can reach at best; its faces lie
up to a^2/(6R) inside the sphere (a the chord): 0.0014 for the inner one,
which moves the solution in the ball by ~0.0014 R1/3 (1/k1 - 1/k2) = 2e-4,
the P1 error of -a 5: that floor, not the mesh, would stop the convergence
(bench/getfem_materials_bench.sh shows it). The mesh is refined uniformly
(-a L: every octant at level L, so that "h" is one number; -s L keeps
coarse octants inside, whose error does not fall with L).

Problem: -div(k grad u) = f, f = 1, k = K1 = 1 in the inner ball, K2 = 10
in the shell, u = 0 on the outer sphere. With r = |x - CENTRE| the radial
equation -(1/r^2)(r^2 k u')' = f gives k u' = -f r/3 + C/r^2; C = 0 for a
solution bounded at 0 (inside), and then continuity of the flux k u' at
R1 makes C = 0 in the shell too, so k u' = -f r/3 on both sides:
    u = f (R2^2 - r^2)/(6 K2)                          R1 < r < R2
    u = f (R2^2 - R1^2)/(6 K2) + f (R1^2 - r^2)/(6 K1)  r < R1
(continuous at R1, 0 at R2). The flux q = k grad u = -f (x - CENTRE)/3 does
not jump; the Hessian is -f/(3k) I.

Discretisation: P1 on every element type (FEM_PK(3,1), FEM_PYRAMID_
LAGRANGE(1), FEM_PK_PRISM(3,1), FEM_QK(3,1), as tests/getfem_tags_test.py
uses them); the stiffness is assembled per material region, k taken from
the region the element is in (1000 + material), never from its position:
an element of the wrong material, or an interface not where the input puts
it, costs the rate (--control shows it). u = 0 at the dofs of the boundary
region, eliminated; conjugate gradients (diagonal preconditioner) to a
relative residual of 1e-10. GetFEM 5.4's Model.solve() is not used: with
"lsolver", "superlu" it crashed (a segmentation fault, -a 4), and its
default direct solver took 10 minutes at -a 6 (152k dofs; CG: 1 s).
Errors, at the points of GetFEM's classical rules of degree 4 per element
type: the L2 error against u (a function of the point's radius; it has a
kink at R1, which costs the rule little); the H1 seminorm error
|grad u_h - q/k| and the energy error |sqrt(k) grad u_h - q/sqrt(k)|, with
k the element's material's. Between the polyhedral interface and the
sphere (a layer O(h^2) thick) q/k differs from the gradient "by radius",
which jumps there, inside elements, where no rule integrates it (measured
at -a 4: the energy error by radius changed 16% from degree 4 to 8, the
one with q/k by 1e-6 relative); the layer's share
of the H1 error is of the order of the FE error anyway (O(h) in the norm).

Checks (what theory says, not what a run gave):
  regions    the boundary and interface face regions and 1001, 1002 (whole
             convexes) exist as the comments name them, the materials hold
             every convex once; the faces' vertices lie on the spheres'
             tessellations (at most the radius from the centre).
  volumes    each material's volume (GetFEM's convex_area) within what its
             faces allow: a point p = sum l_i v_i of a face has |p - C|^2 =
             sum l_i |v_i - C|^2 - sum l_i |v_i - p|^2 >= rmin^2 - 3 d^2/8
             (d the largest face diameter, rmin the lowest vertex radius),
             so the inner ball's volume lies between the balls of radius
             R1 - depth and R1 (the shell's likewise); a convex given the
             wrong material moves it by a whole convex, more than the thin
             band allows. At the finest level both within 2% of the
             spheres' volumes.
  rates      between successive levels, log(e_coarse/e_fine)/log(octant_
             coarse/octant_fine), the octant edge halving with each level:
             P1 promises 2 in L2 and 1 in H1 (the polyhedral boundary and
             interface are O(h^2) from the spheres, which keeps both;
             Strang's lemma); the test asks L2 >= 1.5 and H1 >= 0.7, the
             margin for the pre-asymptotic -a 3 (h about R1) and the
             transition elements, whose share changes with the level.
  bounds     at the finest level, with h the largest element diameter:
             the energy error below h |u|_{2,k} (Cea's lemma: the Galerkin
             solution is the best in the energy norm, so its error is at
             most the interpolant's, C h |u|_{2,k} with |u|_{2,k}^2 = int
             k |D^2 u|^2 = int f^2/(3k), C below 1 for P1 elements of
             bounded shape and h their diameter); the L2 error below
             h^2 |u|_{2,k} / sqrt(k_min) (Aubin-Nitsche's extra h, the dual
             problem's constant taken as 1/sqrt(k_min)). Unit constants:
             these catch a wrong solution, the rates catch a wrong order.
  --control  the materials replaced by "centroid within R1 + one octant"
             (an interface one octant out): the rates must fall short.

--table prints one row per level, then the summary line, then one JSON
object (the bench). Exits 1 on any failed check.
"""
import json
import math
import os
import re
import subprocess
import sys
import time

import numpy as np
import scipy.sparse
import getfem as gf

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import make_surfaces  # noqa: E402  (unit_icosphere, CENTRE: shell.off's shapes)

R1, R2 = 0.5, 1.0
K1, K2 = 1.0, 10.0
F = 1.0
C = np.array(make_surfaces.CENTRE, dtype=float)
FEM = {"GT_PK(3,1)": "FEM_PK(3,1)", "GT_PYRAMID(1)": "FEM_PYRAMID_LAGRANGE(1)",
       "GT_PRISM(3,1)": "FEM_PK_PRISM(3,1)", "GT_QK(3,1)": "FEM_QK(3,1)"}
STIFF_DEGREE = 4    # the stiffness (trilinear hexahedra, rational pyramids)
ERROR_DEGREE = 4    # the errors against the exact solution (exact on tetrahedra)
MIN_RATE_L2, MIN_RATE_H1 = 1.5, 0.7
VOLUME_TOL = 0.02
CG_TOL = 1e-10      # relative residual: far below the discretisation error

fails = 0


def ok(msg):
    print("ok   " + msg, flush=True)


def bad(msg):
    global fails
    fails += 1
    print("FAIL " + msg, flush=True)


def check(cond, msg):
    (ok if cond else bad)(msg)
    return cond


# ---- the exact solution -----------------------------------------------------------

def exact_u(r):
    r = np.asarray(r, dtype=float)
    out = F * (R2 ** 2 - r ** 2) / (6 * K2)
    inner = F * (R2 ** 2 - R1 ** 2) / (6 * K2) + F * (R1 ** 2 - r ** 2) / (6 * K1)
    return np.where(r < R1, inner, out)


def exact_expressions():
    """u in GetFEM's assembly language, as a function of X (the point)
    through s = |X - c|^2 (H = 1 inside the inner sphere), and the flux
    k grad u = -f (X - c)/3, which is the same on both sides."""
    s = "Norm_sqr(X-c)"
    H = "Heaviside(%r-%s)" % (R1 ** 2, s)
    u_in = "(%r+(%r-%s)/%r)" % (F * (R2 ** 2 - R1 ** 2) / (6 * K2), R1 ** 2, s, 6 * K1 / F)
    u_out = "((%r-%s)/%r)" % (R2 ** 2, s, 6 * K2 / F)
    u = "(%s*%s+(1-%s)*%s)" % (H, u_in, H, u_out)
    flux = "((-%r/3)*(X-c))" % F
    return u, flux


def exact_norms():
    """|u|_L2 and |u|_H1 over the exact ball (4 pi int r^2 ...: Gauss-Legendre
    on each material's radii, exact for these polynomials in r)."""
    x, w = np.polynomial.legendre.leggauss(8)
    l2 = 0.0
    for lo, hi in ((0.0, R1), (R1, R2)):
        r = 0.5 * (hi - lo) * x + 0.5 * (hi + lo)
        l2 += 0.5 * (hi - lo) * np.sum(w * exact_u(r) ** 2 * r ** 2)
    # |grad u|^2 = f^2 r^2/(9 k^2)
    h1 = F ** 2 / 45.0 * (R1 ** 5 / K1 ** 2 + (R2 ** 5 - R1 ** 5) / K2 ** 2)
    return math.sqrt(4 * math.pi * l2), math.sqrt(4 * math.pi * h1)


def h2_seminorm_k():
    """|u|_{2,k} = sqrt(int k |D^2 u|^2): D^2 u = -f/(3k) I, so k |D^2 u|^2
    = f^2/(3k); over the two exact regions."""
    v1 = 4.0 / 3.0 * math.pi * R1 ** 3
    v2 = 4.0 / 3.0 * math.pi * (R2 ** 3 - R1 ** 3)
    return math.sqrt(F ** 2 / 3.0 * (v1 / K1 + v2 / K2))


# ---- input and mesh ----------------------------------------------------------------

def write_shell(path, subdiv):
    """shell.off's hollow ball (outer sphere outward, inner inward) at the
    given icosphere subdivision."""
    u, f = make_surfaces.unit_icosphere(subdiv)
    pts = [C + R2 * np.array(p) for p in u] + [C + R1 * np.array(p) for p in u]
    n = len(u)
    tris = [tuple(t) for t in f] + [(a + n, c + n, b + n) for a, b, c in f]
    with open(path, "w") as o:
        o.write("OFF\n%d %d 0\n" % (len(pts), len(tris)))
        for p in pts:
            o.write("%.17g %.17g %.17g\n" % tuple(p))
        for t in tris:
            o.write("3 %d %d %d\n" % t)
    return len(f)


def run_mixoct(mixoct, shell, request, level, out):
    cmd = [mixoct, "-i", shell, "--materials", request, str(level), "-o", out, "--json"]
    t0 = time.time()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        bad("%s: exit %d\n%s" % (" ".join(cmd), p.returncode, p.stderr[-2000:]))
        return None
    j = json.loads(p.stdout.strip().splitlines()[-1])
    j["_seconds"] = time.time() - t0
    return j


def region_names(path):
    """The writer's comments: {region: name} for face regions and
    {region: material number} for the convex regions."""
    faces, mats = {}, {}
    with open(path) as f:
        for line in f:
            if not line.startswith("%"):
                break
            m = re.match(r'% region (\d+): faces "(.*)"', line)
            if m:
                faces[int(m.group(1))] = m.group(2)
            m = re.match(r'% region (\d+): convexes of material (\d+)', line)
            if m:
                mats[int(m.group(1))] = int(m.group(2))
    return faces, mats


def vertex_sets(m, cvs, local):
    """For convexes cvs and, per row, a list of local vertex numbers
    (local(row) -> list), yield (rows, V): V the points, 3 x k x n, of k
    rows of n vertices each, in blocks."""
    pids, idx = m.pid_from_cvid(cvs)
    groups = {}
    for row in range(len(cvs)):
        loc = local(row)
        g = groups.setdefault(len(loc), ([], []))
        g[0].append(row)
        g[1].append([idx[row] + j for j in loc])
    P = m.pts()
    for rows, at in groups.values():
        rows, at = np.array(rows, dtype=np.int64), np.array(at, dtype=np.int64)
        for b in range(0, len(rows), 100000):
            yield rows[b:b + 100000], P[:, pids[at[b:b + 100000]]]


def centroids(m):
    """The mean of each convex's vertices, 3 x nbcvs."""
    cvs = np.arange(m.nbcvs(), dtype=np.int64)
    counts = np.diff(m.pid_from_cvid(cvs)[1])
    out = np.zeros((3, m.nbcvs()))
    for rows, V in vertex_sets(m, cvs, lambda row: range(counts[row])):
        out[:, rows] = V.mean(axis=2)
    return out


def diameter(V):
    """3 x k x n points: the largest distance within each of the k sets."""
    d = V[:, :, :, None] - V[:, :, None, :]
    return np.sqrt((d ** 2).sum(axis=0)).max(axis=(1, 2))


def diameters(m):
    """The largest element diameter (the largest distance between two
    vertices of a convex)."""
    cvs = np.arange(m.nbcvs(), dtype=np.int64)
    counts = np.diff(m.pid_from_cvid(cvs)[1])
    return max(float(diameter(V).max()) for _, V in vertex_sets(m, cvs, lambda row: range(counts[row])))


def octant_edge(m):
    """The octants' edge at the level asked: the median of the hexahedra's
    edge 0-1 (all octants are at that level with -a; only some hexahedra
    near the surfaces are moved)."""
    gts, cv2gt = m.geotrans()
    hexes = [i for i, g in enumerate(gts) if g.char() == "GT_QK(3,1)"]
    sel = np.flatnonzero(np.isin(cv2gt, hexes))
    if sel.size == 0:
        return float("nan")
    _, V = next(vertex_sets(m, sel[:100000], lambda row: (0, 1)))
    return float(np.median(np.linalg.norm(V[:, :, 1] - V[:, :, 0], axis=0)))


def face_bounds(m, region):
    """The faces of a face region: the largest face diameter and the
    smallest and largest distance of their vertices from C."""
    faces = m.region(region)
    structs, cv2s = m.cvstruct()
    cvs, fs = faces[0].astype(np.int64), faces[1].astype(np.int64)
    facepts = {}    # (structure, face): the face's local vertex numbers
    for key in set(zip(cv2s[cvs].tolist(), fs.tolist())):
        facepts[key] = list(np.asarray(structs[key[0]].facepts(key[1]), dtype=np.int64))
    d, rmin, rmax = 0.0, np.inf, 0.0
    for _, V in vertex_sets(m, cvs, lambda row: facepts[(cv2s[cvs[row]], fs[row])]):
        d = max(d, float(diameter(V).max()))
        r = np.linalg.norm(V - C[:, None, None], axis=0)
        rmin, rmax = min(rmin, float(r.min())), max(rmax, float(r.max()))
    return d, rmin, rmax


def depth_bound(radius, d, rmin):
    """How far inside the sphere of the given radius a face can reach whose
    vertices lie at rmin..radius from C and within d of each other: a point
    p = sum l_i v_i of a face (a triangle, or a bilinear quadrilateral,
    which lies in its vertices' convex hull) has |p - C|^2 = sum l_i |v_i -
    C|^2 - sum l_i |v_i - p|^2, and the last sum, (1/2) sum_ij l_i l_j |v_i
    - v_j|^2, is at most d^2 (1 - 1/n)/2 <= 3 d^2/8 (n <= 4 vertices); so
    |p - C| >= sqrt(rmin^2 - 3 d^2/8)."""
    return radius - math.sqrt(max(rmin ** 2 - 3.0 * d * d / 8.0, 0.0))


def check_regions(tag, path, m, j):
    """Regions and volumes; returns (boundary region, inner region, shell
    region) or None."""
    faces, mats = region_names(path)
    regions = sorted(int(r) for r in m.regions())
    by_mat = {v: k for k, v in mats.items()}
    boundary = [r for r, n in faces.items() if n == "boundary"]
    interface = [r for r, n in faces.items() if n.startswith("interface")]
    if not check(m.nbpts() == j["nodes"] and m.nbcvs() == j["elements"],
                 "%s: GetFEM read %d points, %d convexes (mixoct: %d nodes, %d elements)"
                 % (tag, m.nbpts(), m.nbcvs(), j["nodes"], j["elements"])):
        return None
    want = (len(boundary) == 1 and len(interface) == 1 and sorted(by_mat) == [1, 2]
            and by_mat[1] == 1001 and by_mat[2] == 1002
            and set(boundary + interface + [1001, 1002]) <= set(regions))
    if not check(want, "%s: regions %s; comments: faces %s, materials %s (wanted the boundary, "
                 "one interface, materials 1 and 2 as regions 1001, 1002)"
                 % (tag, regions, faces, mats)):
        return None
    shell, inner = m.region(1001), m.region(1002)
    whole = bool(np.all(shell[1] == 65535)) and bool(np.all(inner[1] == 65535))
    cvs = np.sort(np.concatenate([shell[0], inner[0]]))
    every = cvs.size == m.nbcvs() and bool(np.array_equal(cvs, np.arange(m.nbcvs())))
    check(whole and every, "%s: regions 1001 (%d convexes) and 1002 (%d): whole convexes, "
          "every convex once" % (tag, shell.shape[1], inner.shape[1]))
    check(m.region(boundary[0]).shape[1] > 0 and m.region(interface[0]).shape[1] > 0,
          "%s: region %d (boundary) %d faces, region %d (interface) %d faces"
          % (tag, boundary[0], m.region(boundary[0]).shape[1], interface[0],
             m.region(interface[0]).shape[1]))
    # the volumes against the band the faces of the boundary and the
    # interface lie in: every face between the sphere (its vertices are on
    # the input, inside the sphere) and depth_bound below it, so the inner
    # material holds the ball of radius R1 - d1 and lies in the one of
    # radius R1, and the whole mesh likewise for R2 - d2, R2
    vol = lambda r: 4.0 / 3.0 * math.pi * r ** 3
    band = {}
    for name, rg, radius in (("interface", interface[0], R1), ("boundary", boundary[0], R2)):
        d, rmin, rmax = face_bounds(m, rg)
        band[name] = depth_bound(radius, d, rmin)
        check(rmax <= radius * (1 + 1e-12) and rmin > 0.5 * radius,
              "%s: %s faces: vertices at %.5f..%.5f from the centre (the sphere: %g), largest face "
              "%.4f across: the faces lie less than %.2e inside the sphere"
              % (tag, name, rmin, rmax, radius, d, band[name]))
    v_in = float(np.sum(m.convex_area(inner[0])))
    v_sh = float(np.sum(m.convex_area(shell[0])))
    e_in, e_sh = vol(R1), vol(R2) - vol(R1)
    lo_in, hi_in = vol(R1 - band["interface"]), vol(R1)
    lo_sh, hi_sh = vol(R2 - band["boundary"]) - vol(R1), vol(R2) - vol(R1 - band["interface"])
    eps = 1e-9
    check(lo_in * (1 - eps) <= v_in <= hi_in * (1 + eps),
          "%s: material 2 (inner ball): volume %.5f, %+.2f%% of 4/3 pi R1^3, within what the "
          "interface allows (%.5f..%.5f)" % (tag, v_in, 100 * (v_in / e_in - 1), lo_in, hi_in))
    check(lo_sh * (1 - eps) <= v_sh <= hi_sh * (1 + eps),
          "%s: material 1 (shell): volume %.5f, %+.2f%% of 4/3 pi (R2^3 - R1^3), within what "
          "the boundary and the interface allow (%.5f..%.5f)"
          % (tag, v_sh, 100 * (v_sh / e_sh - 1), lo_sh, hi_sh))
    return boundary[0], 1002, 1001, v_in / e_in - 1, v_sh / e_sh - 1


# ---- solve -------------------------------------------------------------------------

def spmat_to_scipy(S):
    ind = S.csc_ind()
    return scipy.sparse.csc_matrix((S.csc_val(), ind[1], ind[0]), shape=tuple(S.size()))


def pcg(A, b, tol):
    """Conjugate gradients with the diagonal as preconditioner (A symmetric
    positive definite): x with |b - A x| <= tol |b|, and the iterations."""
    d = 1.0 / A.diagonal()
    x = np.zeros_like(b)
    r = b.copy()
    z = d * r
    p = z.copy()
    rz = r @ z
    stop = tol * np.linalg.norm(b)
    for it in range(1, 20 * b.size + 1):
        q = A @ p
        alpha = rz / (p @ q)
        x += alpha * p
        r -= alpha * q
        if np.linalg.norm(r) <= stop:
            return x, it
        z = d * r
        rz, rz_old = r @ z, rz
        p = z + (rz / rz_old) * p
    return x, -1


def solve(tag, m, boundary, inner, shell):
    """The P1 solution and its errors: dict."""
    t0 = time.time()
    gts, cv2gt = m.geotrans()
    mf = gf.MeshFem(m, 1)
    for i, g in enumerate(gts):
        mf.set_fem(gf.Fem(FEM[g.char()]), np.flatnonzero(cv2gt == i))
    mim = gf.MeshIm(m, STIFF_DEGREE)
    md = gf.Model("real")
    md.add_fem_variable("u", mf)
    md.add_initialized_data("c", C)
    # the stiffness per material region, k of the region; u = 0 on the
    # boundary region's dofs, eliminated (the system stays symmetric)
    K = (spmat_to_scipy(gf.asm_generic(mim, 2, "%r*Grad_u.Grad_Test_u" % K1, inner, md))
         + spmat_to_scipy(gf.asm_generic(mim, 2, "%r*Grad_u.Grad_Test_u" % K2, shell, md))).tocsr()
    b = np.asarray(gf.asm_generic(mim, 1, "%r*Test_u" % F, -1, md), dtype=float)
    nbdof = mf.nbdof()
    fixed = np.zeros(nbdof, bool)
    fixed[mf.basic_dof_on_region(boundary)] = True
    free = np.flatnonzero(~fixed)
    t_asm = time.time() - t0
    t0 = time.time()
    x, its = pcg(K[free][:, free], b[free], CG_TOL)
    if its < 0:
        bad("%s: conjugate gradients did not converge" % tag)
    u = np.zeros(nbdof)
    u[free] = x
    md.set_variable("u", u)
    t_solve = time.time() - t0
    # errors at the points of the rules of degree ERROR_DEGREE; the H1 and
    # energy errors from the same two integrals, one per material
    t0 = time.time()
    mime = gf.MeshIm(m, ERROR_DEGREE)
    u_ex, flux = exact_expressions()
    a = lambda expr, rg=-1: float(gf.asm_generic(mime, 0, expr, rg, md))
    l2 = math.sqrt(a("sqr(u-%s)" % u_ex))
    g_in, g_sh = (a("Norm_sqr(Grad_u-%s/%r)" % (flux, k), rg)
                  for rg, k in ((inner, K1), (shell, K2)))
    # the solution at the mesh points against u there (a pointwise view)
    cvs = np.arange(m.nbcvs())
    dofs, _ = mf.basic_dof_from_cvid(cvs)
    pids, _ = m.pid_from_cvid(cvs)
    at_pts = np.full(m.nbpts(), np.nan)
    at_pts[pids] = u[dofs]
    r = np.linalg.norm(m.pts().T - C, axis=1)
    max_nodal = float(np.nanmax(np.abs(at_pts - exact_u(r))))
    l2_ex, h1_ex = exact_norms()
    return {"dofs": nbdof, "fixed": int(fixed.sum()), "cg_iterations": its,
            "l2": l2, "h1": math.sqrt(g_in + g_sh), "energy": math.sqrt(K1 * g_in + K2 * g_sh),
            "l2_rel": l2 / l2_ex, "h1_rel": math.sqrt(g_in + g_sh) / h1_ex,
            "max_nodal": max_nodal, "assembly_s": t_asm, "solve_s": t_solve,
            "error_s": time.time() - t0}


# ---- the study ---------------------------------------------------------------------

def misplaced_materials(m, shift):
    """The control: materials as a mesher that put the interface one
    octant too far out would give them (k1 where the convex's centroid
    lies within R1 + shift of the centre): two new regions."""
    inside = np.linalg.norm(centroids(m) - C[:, None], axis=0) < R1 + shift
    cvs = np.arange(m.nbcvs())
    m.set_region(3002, cvs[inside].reshape(1, -1))
    m.set_region(3001, cvs[~inside].reshape(1, -1))
    return 3002, 3001


def parse_args(args):
    opts = {"levels": [3, 4, 5], "subdiv": None, "request": "-a", "table": False,
            "keep": False, "control": False}
    i = 0
    while i < len(args):
        if args[i] == "--levels" and i + 1 < len(args):
            opts["levels"] = [int(x) for x in args[i + 1].split(",")]
            i += 2
        elif args[i] == "--subdiv" and i + 1 < len(args):
            opts["subdiv"] = int(args[i + 1])
            i += 2
        elif args[i] == "--request" and i + 1 < len(args) and args[i + 1] in ("-a", "-s"):
            opts["request"] = args[i + 1]
            i += 2
        elif args[i] in ("--table", "--keep", "--control"):
            opts[args[i][2:]] = True
            i += 1
        else:
            return None
    if opts["subdiv"] is None:
        opts["subdiv"] = max(opts["levels"])
    return opts


def print_table(rows):
    print("\n%5s %8s %8s %9s %9s %11s %11s %11s %6s %6s %6s %8s %8s"
          % ("level", "octant", "h_max", "elements", "dofs", "L2", "H1", "energy", "rL2", "rH1", "rE",
             "dV_in%", "dV_sh%"))
    rate = lambda r, k: "%.2f" % r[k] if k in r else "-"
    for r in rows:
        print("%5d %8.4f %8.4f %9d %9d %11.4e %11.4e %11.4e %6s %6s %6s %8.3f %8.3f"
              % (r["level"], r["octant"], r["h"], r["elements"], r["dofs"], r["l2"], r["h1"], r["energy"],
                 rate(r, "rate_l2"), rate(r, "rate_h1"), rate(r, "rate_energy"),
                 100 * r["volume_inner"], 100 * r["volume_shell"]))


def check_rates(rows, opts):
    """The rates between successive levels, against the octants' edge (with
    -a, halved from one level to the next; the largest diameter, which one
    element decides, is in the table). The control's must fall short."""
    for a, b in zip(rows, rows[1:]):
        lh = math.log(a["octant"] / b["octant"])
        for k in ("l2", "h1", "energy"):
            b["rate_" + k] = math.log(a[k] / b[k]) / lh
        good = b["rate_l2"] >= MIN_RATE_L2 and b["rate_h1"] >= MIN_RATE_H1
        check(good != opts["control"],
              "%srates from %s %d to %d (octant edge %.4f -> %.4f): L2 %.2f (at least %g), "
              "H1 %.2f (at least %g), energy %.2f"
              % ("control, the interface one octant out: the rates must fall short; "
                 if opts["control"] else "", opts["request"], a["level"], b["level"],
                 a["octant"], b["octant"], b["rate_l2"], MIN_RATE_L2, b["rate_h1"],
                 MIN_RATE_H1, b["rate_energy"]))


def check_finest(last):
    """The errors and the volumes at the finest level against bounds."""
    h2k = h2_seminorm_k()
    check(last["energy"] < last["h"] * h2k,
          "level %d: energy error %.3e below h |u|_{2,k} = %.4f * %.4f = %.3e"
          % (last["level"], last["energy"], last["h"], h2k, last["h"] * h2k))
    l2_bound = last["h"] ** 2 * h2k / math.sqrt(min(K1, K2))
    check(last["l2"] < l2_bound,
          "level %d: L2 error %.3e below h^2 |u|_{2,k} / sqrt(k_min) = %.3e"
          % (last["level"], last["l2"], l2_bound))
    check(abs(last["volume_inner"]) < VOLUME_TOL and abs(last["volume_shell"]) < VOLUME_TOL,
          "level %d: the materials' volumes within %g%% of the spheres' (%+.2f%%, %+.2f%%)"
          % (last["level"], 100 * VOLUME_TOL, 100 * last["volume_inner"],
             100 * last["volume_shell"]))


def main():
    opts = parse_args(sys.argv[3:]) if len(sys.argv) >= 3 else None
    if opts is None:
        print(__doc__)
        return 2
    mixoct, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    gf.util_trace_level(0)
    gf.util_warning_level(0)
    shell = os.path.join(work, "shell_%d.off" % opts["subdiv"])
    ntri = write_shell(shell, opts["subdiv"])
    print("input: two icospheres of %d triangles (subdivision %d), radii %g and %g about %s; "
          "k = %g inside, %g in the shell, f = %g"
          % (ntri, opts["subdiv"], R2, R1, tuple(C), K1, K2, F), flush=True)
    rows = []
    for L in opts["levels"]:
        tag = "%s %d" % (opts["request"], L)
        out = os.path.join(work, "mesh%d.getfem" % L)
        j = run_mixoct(mixoct, shell, opts["request"], L, out)
        if j is None:
            return 1
        t0 = time.time()
        try:
            m = gf.Mesh("load", out)
        except RuntimeError as e:   # e.g. "Two points ... with the same coords"
            bad("%s: GetFEM cannot load %s: %s" % (tag, out, str(e).strip()[-300:]))
            return 1
        t_load = time.time() - t0
        regs = check_regions(tag, out, m, j)
        if regs is None:
            return 1
        boundary, inner, shell_rg, dv_in, dv_sh = regs
        if opts["control"]:
            inner, shell_rg = misplaced_materials(m, octant_edge(m))
        res = solve(tag, m, boundary, inner, shell_rg)
        res.update({"level": L, "h": diameters(m), "octant": octant_edge(m), "nodes": j["nodes"],
                    "elements": j["elements"], "by_type": j["by_type"],
                    "volume_inner": dv_in, "volume_shell": dv_sh,
                    "mesh_s": j["_seconds"], "load_s": t_load})
        rows.append(res)
        print("%s: %d elements (%s), %d dofs, h %.4f: L2 %.3e (%.2e of |u|), H1 %.3e (%.2e of "
              "|u|_1), energy %.3e, max nodal %.2e (mesh %.1f s, load %.1f s, assembly %.1f s, "
              "CG %d iterations %.1f s, errors %.1f s)"
              % (tag, j["elements"], ", ".join("%s %d" % kv for kv in j["by_type"].items()),
                 res["dofs"], res["h"], res["l2"], res["l2_rel"], res["h1"], res["h1_rel"],
                 res["energy"], res["max_nodal"], res["mesh_s"], t_load, res["assembly_s"],
                 res["cg_iterations"], res["solve_s"], res["error_s"]), flush=True)
        if not opts["keep"]:
            os.remove(out)
    check_rates(rows, opts)
    if not opts["control"]:
        check_finest(rows[-1])
    if opts["table"]:
        print_table(rows)
    print("getfem materials: %s" % ("all checks passed" if not fails else
                                     "%d check(s) failed" % fails))
    if opts["table"]:
        print(json.dumps({"bench": "getfem_materials", "request": opts["request"],
                          "subdiv": opts["subdiv"], "input_triangles": 2 * ntri,
                          "control": opts["control"], "k1": K1, "k2": K2, "rows": rows,
                          "failed_checks": fails}))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
