#!/usr/bin/python3
"""Synthetic segmented 3D label images (issue 28): 0 background, 1.. materials.

usage: make_label_image.py OUT.nii.gz [--shape SHAPE] [--n N] [--voxel H]
                           [--inr OUT.inr] [--no-json]

Writes OUT.nii.gz (uint8, NIfTI-1 through nibabel, affine diag(H, H, H) with
no offset: voxel (i, j, k) has its centre at (i H, j H, k H) mm), with --inr
also an uncompressed INRIA image of the same voxels (what CGAL::Image_3
reads; it too puts voxel (i, j, k) at (i VX, j VY, k VZ)), and a JSON
sidecar OUT.json (OUT less .nii.gz / .nii): the shape's parameters and, for
each label, its voxel count, the voxel count times the voxel volume and the
analytic volume where known. Needs numpy and nibabel (/usr/bin/python3 on
Debian 12).

Shapes (--shape; every voxel labelled by its centre):
  brain    the bench's target (default N 256, H 1): a head of concentric
           deformed shells about the centre C = ((N-1)/2 + (0.31, -0.23,
           0.17)) H. Each shell's outer surface is |x - C| = r_k(u), u the
           direction (x - C) / |x - C|:
             r1 = R1 E(u) (1 + B(u) + F(u))    1 white matter, folded
             r2 = r1 + Tg (1 + 0.3 sin(9 u.a5))  2 grey matter: a layer of
                                               2-5 voxels that follows r1's
                                               folds
             r3 = R3 E(u) (1 + B(u))           3 CSF (fills the sulci; at
                                               least Tc thick)
             r4 = r3 + Ts                      4 skull
             r5 = r4 + Tk                      5 scalp, max r5 < N/2 - 3 voxels
           E(u) = 1 / |(ux / 0.9, uy, uz / 0.85)| (an ellipsoid's radial
           function), B(u) = 0.03 (1.5 uz^2 - 0.5) + 0.02 ux uy (low order
           bumps), F(u) = 0.08 sin(7 u.a1) sin(5 u.a2) + 0.05 sin(13 u.a3 +
           0.3) sin(11 u.a4 + 1.1) + 0.035 sin(23 u.a2 + 0.7) sin(19 u.a5 -
           0.2) (the folds, the last of about 20 voxels' wavelength at N 256:
           the products of sines of the
           sin(7 theta) sin(5 phi) kind, written in u's Cartesian components
           so that they are smooth at the poles too; a1..a5 fixed unit
           vectors). Tg, Tc, Ts, Tk = 4, 1.5, 6, 5 voxels at N 256, scaled
           with N (floors 2, 1, 2, 2); R1 is the largest that keeps r5 <=
           N/2 - 4 voxels; R3 the smallest that keeps r3 - r2 >= Tc. Plus a
           "ventricle" of label 3 inside label 1: the ellipsoid of centre
           C + (0, 0.12, 0.08) R1 and half axes (0.22, 0.10, 0.12) R1.
           Interfaces: (1,2) r1, (2,3) r2, (3,4) r3, (4,5) r4, (0,5) r5,
           (1,3) the ventricle. Analytic volumes: integral over the sphere
           of r^3 / 3 (Gauss-Legendre in cos(theta) x uniform in phi, with
           the difference of two resolutions as its error estimate) and
           4/3 pi abc for the ventricle.
  balls2   two concentric balls (N default 32): label 1 radius 0.2 N,
           label 2 up to 0.4 N, centre (N-1)/2 + (0.31, -0.23, 0.17) voxels.
  balls3   three: radii 0.15, 0.28, 0.4 N, labels 1, 2, 3.
  boxes    two touching boxes: label 1 x in [N/4, N/2), label 2 x in
           [N/2, 3N/4), y and z in [N/4, 3N/4) (voxel indices: exact).
  plate    a plate of label 1 one voxel thick (k = N/2), i, j in
           [3N/8, 5N/8), inside the box [N/4, 3N/4)^3 of label 2.
  checker  [2, N-2)^3 cut into 4 x 4 x 4 blocks, labels 1 + (bi+bj+bk) % 2.

As a module: Shape.from_json(path or dict) rebuilds the shape of a sidecar;
shape.interface_distance(points, a, b) (or the module function
interface_distance(points, a, b, params)) gives, for points (m x 3, world
mm) meant to lie on the interface of labels a and b, their distance to the
exact interface. Definition: the interface is the zero set of an implicit
function f (brain: f = |x - C| - r_k(u); ventricle: |M (x - Cv)| - 1 with
M = diag(1/axes); balls: |x - C| - R; boxes: x - x0); each point is
projected by Newton steps along the gradient, x <- x - f grad f / |grad f|^2
(central differences of step 1e-4 H, 8 steps, or fewer once |f| / |grad f|
< 1e-9 H), and the distance is |x0 - x_final|: a point on the surface, so
an upper bound of the true (closest point) distance, equal to it to first
order. shape.radial_distance(points, a, b) gives the cheaper
| |x - C| - r_k(u) | for the radial surfaces. A pair of labels that has no
interface in the shape (e.g. 2 and 4 where a mesher lost the thin CSF) is
measured against the nearest of the surfaces of the shape bounding a or b.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

OFFSET = np.array([0.31, -0.23, 0.17])
SHAPES = ("brain", "balls2", "balls3", "boxes", "plate", "checker")


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


# the fold directions of the brain (fixed, not axis-aligned)
A1, A2, A3, A4, A5 = (_unit(v) for v in ((1, 0.2, 0.1), (0.1, 1, -0.3), (0.3, -0.5, 1),
                                           (-0.6, 0.4, 0.7), (0.5, 0.5, -0.7)))


def _sphere_quadrature(nt, nphi):
    """(directions m x 3, weights m): Gauss-Legendre in cos(theta), uniform
    in phi; sum of the weights 4 pi"""
    x, w = np.polynomial.legendre.leggauss(nt)
    phi = (np.arange(nphi) + 0.5) * (2 * math.pi / nphi)
    ct = np.repeat(x, nphi)
    st = np.sqrt(1 - ct * ct)
    ph = np.tile(phi, nt)
    u = np.stack([st * np.cos(ph), st * np.sin(ph), ct], axis=1)
    return u, np.repeat(w, nphi) * (2 * math.pi / nphi)


class Shape:
    """One synthetic label image: its parameters, its labels at points and
    its interfaces"""

    def __init__(self, shape, n, h):
        self.shape, self.n, self.h = shape, int(n), float(h)
        self.centre = ((self.n - 1) / 2 + OFFSET) * self.h
        self.params = {"shape": shape, "n": self.n, "voxel": self.h,
                       "centre": self.centre.tolist(),
                       "voxel_centre": "voxel (i, j, k) at (i, j, k) * voxel"}
        getattr(self, "_setup_" + shape)()

    # ---- brain ---------------------------------------------------------------

    def _setup_brain(self):
        n, h = self.n, self.h
        s = n / 256.0
        self.tg = max(2.0, 4.0 * s) * h
        self.tc = max(1.0, 1.5 * s) * h
        self.ts = max(2.0, 6.0 * s) * h
        self.tk = max(2.0, 5.0 * s) * h
        u, _ = _sphere_quadrature(160, 320)
        target = (n / 2 - 4) * h
        lo, hi = 0.05 * n * h, 0.5 * n * h
        for _ in range(50):  # the largest R1 with max r5 <= target
            self.r1s = 0.5 * (lo + hi)
            self.r3s = 1.0
            self.r3s = self._r3_scale(u)
            if np.max(self.radius(u, 5)) <= target:
                lo = self.r1s
            else:
                hi = self.r1s
        self.r1s = lo
        self.r3s = self._r3_scale(u)
        r1 = self.r1s
        self.vcentre = self.centre + np.array([0.0, 0.12, 0.08]) * r1
        self.vaxes = np.array([0.22, 0.10, 0.12]) * r1
        self.params.update({
            "R1": self.r1s, "R3": self.r3s, "grey_thickness": self.tg, "csf_min": self.tc,
            "skull": self.ts, "scalp": self.tk, "ventricle_centre": self.vcentre.tolist(),
            "ventricle_axes": self.vaxes.tolist(),
            "folds": "F(u) = 0.08 sin(7 u.a1) sin(5 u.a2) + 0.05 sin(13 u.a3 + 0.3) "
                     "sin(11 u.a4 + 1.1) + 0.035 sin(23 u.a2 + 0.7) sin(19 u.a5 - 0.2)",
            "a": [a.tolist() for a in (A1, A2, A3, A4, A5)],
            "labels": {"1": "white matter", "2": "grey matter", "3": "CSF (and ventricle)",
                       "4": "skull", "5": "scalp"},
            "interfaces": {"1-2": "r1", "2-3": "r2", "3-4": "r3", "4-5": "r4", "0-5": "r5",
                           "1-3": "ventricle"}})

    @staticmethod
    def _ellipsoid(u):
        return 1.0 / np.sqrt((u[:, 0] / 0.9) ** 2 + u[:, 1] ** 2 + (u[:, 2] / 0.85) ** 2)

    @staticmethod
    def _bumps(u):
        return 0.03 * (1.5 * u[:, 2] ** 2 - 0.5) + 0.02 * u[:, 0] * u[:, 1]

    @staticmethod
    def _folds(u):
        return (0.08 * np.sin(7 * (u @ A1)) * np.sin(5 * (u @ A2))
                + 0.05 * np.sin(13 * (u @ A3) + 0.3) * np.sin(11 * (u @ A4) + 1.1)
                + 0.035 * np.sin(23 * (u @ A2) + 0.7) * np.sin(19 * (u @ A5) - 0.2))

    def _r3_scale(self, u):
        r2 = self.radius(u, 2)
        return float(np.max((r2 + self.tc) / (self._ellipsoid(u) * (1 + self._bumps(u)))))

    def radius(self, u, k):
        """r_k(u) for unit directions u (m x 3)"""
        e = self._ellipsoid(u)
        if k <= 2:
            r = self.r1s * e * (1 + self._bumps(u) + self._folds(u))
            if k == 2:
                r = r + self.tg * (1 + 0.3 * np.sin(9 * (u @ A5)))
            return r
        r = self.r3s * e * (1 + self._bumps(u))
        if k >= 4:
            r = r + self.ts
        if k >= 5:
            r = r + self.tk
        return r

    def _ventricle_f(self, x):
        return np.linalg.norm((x - self.vcentre) / self.vaxes, axis=1) - 1.0

    # ---- the small shapes ----------------------------------------------------

    def _setup_balls2(self):
        self.radii = [0.2 * self.n * self.h, 0.4 * self.n * self.h]
        self.params["radii"] = self.radii

    def _setup_balls3(self):
        self.radii = [0.15 * self.n * self.h, 0.28 * self.n * self.h, 0.4 * self.n * self.h]
        self.params["radii"] = self.radii

    def _setup_boxes(self):
        n = self.n
        self.params["boxes_voxels"] = {"1": [[n // 4, n // 2], [n // 4, 3 * n // 4],
                                             [n // 4, 3 * n // 4]],
                                       "2": [[n // 2, 3 * n // 4], [n // 4, 3 * n // 4],
                                             [n // 4, 3 * n // 4]]}

    def _setup_plate(self):
        n = self.n
        self.params["box_voxels"] = [n // 4, 3 * n // 4]
        self.params["plate_voxels"] = {"i": [3 * n // 8, 5 * n // 8],
                                       "j": [3 * n // 8, 5 * n // 8], "k": n // 2}

    def _setup_checker(self):
        self.params["region_voxels"] = [2, self.n - 2]
        self.params["blocks"] = 4

    # ---- labels --------------------------------------------------------------

    def labels_at(self, x):
        """the label at world points x (m x 3)"""
        lab = np.zeros(len(x), dtype=np.uint8)
        if self.shape == "brain":
            d = x - self.centre
            rho = np.linalg.norm(d, axis=1)
            u = d / np.maximum(rho, 1e-300)[:, None]
            for k in (5, 4, 3, 2, 1):
                lab[rho < self.radius(u, k)] = k
            lab[self._ventricle_f(x) < 0] = 3
        elif self.shape in ("balls2", "balls3"):
            rho = np.linalg.norm(x - self.centre, axis=1)
            for k in range(len(self.radii), 0, -1):
                lab[rho < self.radii[k - 1]] = k
        else:
            ijk = np.rint(x / self.h).astype(np.int64)
            i, j, k = ijk[:, 0], ijk[:, 1], ijk[:, 2]
            n = self.n
            if self.shape == "boxes":
                for name, b in self.params["boxes_voxels"].items():
                    m = ((i >= b[0][0]) & (i < b[0][1]) & (j >= b[1][0]) & (j < b[1][1])
                         & (k >= b[2][0]) & (k < b[2][1]))
                    lab[m] = int(name)
            elif self.shape == "plate":
                a, b = n // 4, 3 * n // 4
                lab[(i >= a) & (i < b) & (j >= a) & (j < b) & (k >= a) & (k < b)] = 2
                p, q = 3 * n // 8, 5 * n // 8
                lab[(i >= p) & (i < q) & (j >= p) & (j < q) & (k == n // 2)] = 1
            elif self.shape == "checker":
                lo, hi = 2, n - 2
                inside = (i >= lo) & (i < hi) & (j >= lo) & (j < hi) & (k >= lo) & (k < hi)
                bs = (hi - lo) / 4.0
                bi = np.floor((i - lo) / bs).astype(np.int64)
                bj = np.floor((j - lo) / bs).astype(np.int64)
                bk = np.floor((k - lo) / bs).astype(np.int64)
                lab[inside] = (1 + (bi + bj + bk) % 2)[inside].astype(np.uint8)
        return lab

    def image(self):
        """the label image, shape (n, n, n), index [i, j, k]"""
        n, h = self.n, self.h
        out = np.empty((n, n, n), dtype=np.uint8)
        g = np.arange(n, dtype=float) * h
        ii, jj = np.meshgrid(g, g, indexing="ij")
        for k in range(n):  # slab by slab: bounded memory at N 256
            x = np.stack([ii.ravel(), jj.ravel(), np.full(n * n, k * h)], axis=1)
            out[:, :, k] = self.labels_at(x).reshape(n, n)
        return out

    # ---- volumes -------------------------------------------------------------

    def analytic_volumes(self):
        """({label: volume}, estimated quadrature error) where known"""
        if self.shape == "brain":
            def shells(nt):
                u, w = _sphere_quadrature(nt, 2 * nt)
                return [float(np.sum(w * self.radius(u, k) ** 3) / 3) for k in (1, 2, 3, 4, 5)]
            v, v2 = shells(400), shells(300)
            err = max(abs(a - b) for a, b in zip(v, v2))
            vent = 4 / 3 * math.pi * float(np.prod(self.vaxes))
            vol = {1: v[0] - vent, 2: v[1] - v[0], 3: v[2] - v[1] + vent, 4: v[3] - v[2],
                   5: v[4] - v[3]}
            return vol, err
        if self.shape in ("balls2", "balls3"):
            b = [4 / 3 * math.pi * r ** 3 for r in self.radii]
            return {k + 1: b[k] - (b[k - 1] if k else 0.0) for k in range(len(b))}, 0.0
        return None, None  # voxel-aligned: the voxel count is exact

    # ---- interfaces ----------------------------------------------------------

    def _surfaces(self):
        """{name: f(x)} and {(a, b): name} of the shape's interfaces"""
        c = self.centre
        if self.shape == "brain":
            def radial(k):
                def f(x):
                    d = x - c
                    rho = np.linalg.norm(d, axis=1)
                    return rho - self.radius(d / np.maximum(rho, 1e-300)[:, None], k)
                return f
            surf = {"r%d" % k: radial(k) for k in range(1, 6)}
            surf["ventricle"] = self._ventricle_f
            pairs = {(1, 2): "r1", (2, 3): "r2", (3, 4): "r3", (4, 5): "r4", (0, 5): "r5",
                     (1, 3): "ventricle"}
            return surf, pairs
        if self.shape in ("balls2", "balls3"):
            surf = {"R%d" % (k + 1): (lambda r: lambda x: np.linalg.norm(x - c, axis=1) - r)(r)
                    for k, r in enumerate(self.radii)}
            m = len(self.radii)
            pairs = {(k, k + 1): "R%d" % k for k in range(1, m)}
            pairs[(0, m)] = "R%d" % m
            return surf, pairs
        if self.shape == "boxes":
            x0 = (self.n // 2 - 0.5) * self.h
            return {"x0": lambda x: x[:, 0] - x0}, {(1, 2): "x0"}
        return {}, {}

    def interface_names(self):
        return {"%d-%d" % p: s for p, s in self._surfaces()[1].items()}

    def _candidates(self, a, b):
        surf, pairs = self._surfaces()
        key = (min(a, b), max(a, b))
        if key in pairs:
            return surf, [pairs[key]]
        names = sorted({s for p, s in pairs.items() if a in p or b in p})
        return surf, names

    def interface_distance(self, points, a, b, steps=8):
        """distance of points (m x 3) to the exact interface of labels a, b:
        Newton projection along the gradient (see the module's doc); None
        when the shape has no analytic interface for them"""
        x0 = np.asarray(points, dtype=float).reshape(-1, 3)
        surf, names = self._candidates(a, b)
        if not names:
            return None
        best = None
        eps = 1e-4 * self.h
        for name in names:
            f = surf[name]
            x = x0.copy()
            for _ in range(steps):
                fx = f(x)
                g = np.empty_like(x)
                for d in range(3):
                    e = np.zeros(3)
                    e[d] = eps
                    g[:, d] = (f(x + e) - f(x - e)) / (2 * eps)
                g2 = np.maximum(np.sum(g * g, axis=1), 1e-300)
                step = (fx / g2)[:, None] * g
                x -= step
                if np.max(np.abs(fx) / np.sqrt(g2)) < 1e-9 * self.h:
                    break
            dist = np.linalg.norm(x - x0, axis=1)
            best = dist if best is None else np.minimum(best, dist)
        return best

    def radial_distance(self, points, a, b):
        """| |x - C| - r_k(u) | (brain, balls) for the pair's surface(s)"""
        x = np.asarray(points, dtype=float).reshape(-1, 3)
        surf, names = self._candidates(a, b)
        names = [s for s in names if s != "ventricle"]
        if not names or self.shape not in ("brain", "balls2", "balls3"):
            return None
        return np.min([np.abs(surf[s](x)) for s in names], axis=0)

    @classmethod
    def from_json(cls, params):
        if isinstance(params, str):
            with open(params) as fp:
                params = json.load(fp)
        p = params.get("params", params)
        return cls(p["shape"], p["n"], p["voxel"])


def interface_distance(points, label_a, label_b, params=None):
    """module-level form: params a sidecar (path or dict), default the
    brain at N 256, voxel 1"""
    shape = Shape("brain", 256, 1.0) if params is None else Shape.from_json(params)
    return shape.interface_distance(points, label_a, label_b)


def write_inr(path, img, h):
    """uncompressed INRIA image: 256-byte header, then the voxels x fastest"""
    nx, ny, nz = img.shape
    head = ("#INRIMAGE-4#{\nXDIM=%d\nYDIM=%d\nZDIM=%d\nVDIM=1\nTYPE=unsigned fixed\n"
            "PIXSIZE=8 bits\nSCALE=2**0\nCPU=decm\nVX=%g\nVY=%g\nVZ=%g\n" % (nx, ny, nz, h, h, h))
    end = "##}\n"
    pad = 256 - len(head) - len(end)
    if pad < 0:
        raise ValueError("INR header too long")
    with open(path, "wb") as fp:
        fp.write((head + "\n" * pad + end).encode("ascii"))
        fp.write(np.asarray(img, dtype=np.uint8).tobytes(order="F"))


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="OUT.nii.gz (or .nii)")
    ap.add_argument("--shape", choices=SHAPES, default="brain")
    ap.add_argument("--n", type=int, default=None, help="voxels per side (brain 256, others 32)")
    ap.add_argument("--voxel", type=float, default=1.0, help="voxel size, mm")
    ap.add_argument("--inr", default=None, help="also write this .inr")
    ap.add_argument("--no-json", action="store_true")
    a = ap.parse_args(argv)
    import nibabel as nib

    n = a.n or (256 if a.shape == "brain" else 32)
    if n < 8:
        ap.error("--n must be at least 8")
    shape = Shape(a.shape, n, a.voxel)
    img = shape.image()
    affine = np.diag([a.voxel, a.voxel, a.voxel, 1.0])
    ni = nib.Nifti1Image(img, affine)
    ni.header.set_xyzt_units("mm")
    nib.save(ni, a.out)
    if a.inr:
        write_inr(a.inr, img, a.voxel)
    counts = np.bincount(img.ravel(), minlength=int(img.max()) + 1)
    vvox = a.voxel ** 3
    exact, qerr = shape.analytic_volumes()
    labels = {}
    for lab in range(1, len(counts)):
        e = {"voxels": int(counts[lab]), "voxel_volume": float(counts[lab]) * vvox}
        if exact is not None and lab in exact:
            e["analytic_volume"] = exact[lab]
        labels[str(lab)] = e
    side = {"params": shape.params, "files": {"nifti": a.out, "inr": a.inr},
            "voxel_volume": vvox, "background_voxels": int(counts[0]), "labels": labels,
            "interfaces": shape.interface_names(),
            "analytic_volume_quadrature_error": qerr}
    if not a.no_json:
        base = a.out
        for ext in (".nii.gz", ".nii"):
            if base.endswith(ext):
                base = base[:-len(ext)]
                break
        with open(base + ".json", "w") as fp:
            json.dump(side, fp, indent=1)
    print(json.dumps({k: side[k] for k in ("labels", "interfaces")}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
