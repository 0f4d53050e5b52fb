#!/usr/bin/env python3
"""The label image readers against nibabel (issue 28): images written with
nibabel (.nii and .nii.gz, NIfTI-1 and NIfTI-2, int16, uint8, int32 big-endian,
float32 with values that are not integers, scl_slope/scl_inter, an oblique
sform, a qform alone) are read by tests/image_dump (mx_read_label_image) and
what it prints is compared with nibabel's own reading: the dims, the affine
(the voxel-to-world transform of the voxels' centres), the count of values
that are not integers, the sums of the labels (plain and weighted by the
voxel's index, i fastest) and a few voxels.

    image_readers_test.py path/to/image_dump

Needs python3-numpy and python3-nibabel (Debian); without them it prints SKIP
and exits 77, unless the environment variable CI is set (then a failure)."""
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
    import nibabel as nib
except ImportError as e:
    if os.environ.get("CI"):
        print(f"FAIL: {e} (CI is set: python3-numpy and python3-nibabel must be there)")
        sys.exit(1)
    print(f"SKIP: {e} (apt-get install python3-nibabel)")
    sys.exit(77)

DUMP = sys.argv[1]
failures = 0


def fail(msg):
    global failures
    failures += 1
    print("FAIL:", msg)


def dump(path, voxels):
    args = [DUMP, path] + [f"{i},{j},{k}" for i, j, k in voxels]
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"{path}: image_dump exit {r.returncode}: {r.stderr.strip()}")
        return None
    out = {"at": {}}
    for line in r.stdout.splitlines():
        w = line.split()
        if w[0] == "at":
            out["at"][tuple(map(int, w[1:4]))] = int(w[4])
        elif w[0] == "format":
            out["format"] = w[1]
        else:
            out[w[0]] = [float(x) for x in w[1:]]
    return out


def round_half_away(x):
    return np.sign(x) * np.floor(np.abs(x) + 0.5)


def check(path, fmt, oblique):
    img = nib.load(path)
    data = np.asarray(img.get_fdata(dtype=np.float64))
    labels = round_half_away(data).astype(np.int64)
    rounded = int(np.count_nonzero(labels != data))
    shape = data.shape
    rng = np.random.default_rng(len(path))
    voxels = [tuple(int(rng.integers(0, n)) for n in shape) for _ in range(6)]
    got = dump(path, voxels)
    if got is None:
        return
    name = os.path.basename(path)
    if got["format"] != fmt:
        fail(f"{name}: format {got['format']}, expected {fmt}")
    if tuple(int(x) for x in got["dims"]) != shape:
        fail(f"{name}: dims {got['dims']}, expected {shape}")
        return
    A = np.array(got["A"]).reshape(3, 4)
    if not np.allclose(A, img.affine[:3, :], rtol=1e-6, atol=1e-6):
        fail(f"{name}: A\n{A}\nexpected\n{img.affine[:3, :]}")
    if int(got["oblique"][0]) != oblique:
        fail(f"{name}: oblique {got['oblique']}, expected {oblique}")
    if int(got["rounded"][0]) != rounded:
        fail(f"{name}: rounded {got['rounded']}, expected {rounded}")
    flat = labels.flatten(order="F")  # i fastest
    w = 1 + np.arange(flat.size) % 1000
    if int(got["sum"][0]) != int(flat.sum()):
        fail(f"{name}: sum {got['sum']}, expected {flat.sum()}")
    if int(got["wsum"][0]) != int((flat * w).sum()):
        fail(f"{name}: wsum {got['wsum']}, expected {(flat * w).sum()}")
    for v in voxels:
        if got["at"].get(v) != int(labels[v]):
            fail(f"{name}: voxel {v}: {got['at'].get(v)}, expected {labels[v]}")
    print(f"ok {name}: {shape}, {rounded} rounded")


def rotation(axis, deg):
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    R = np.eye(3)
    a, b = [(1, 2), (0, 2), (0, 1)][axis]
    R[a, a], R[a, b], R[b, a], R[b, b] = c, -s, s, c
    return R


def main():
    rng = np.random.default_rng(28)
    tmp = tempfile.mkdtemp(prefix="mixoct_nibabel_")
    shape = (7, 6, 5)
    lab = rng.integers(0, 9, size=shape)
    diag = np.diag([0.5, 0.75, 1.25, 1.0])
    diag[:3, 3] = [10, -20, 30]

    # int16, plain .nii and .nii.gz
    for ext in ("nii", "nii.gz"):
        p = os.path.join(tmp, f"int16.{ext}")
        nib.save(nib.Nifti1Image(lab.astype(np.int16), diag), p)
        check(p, "NIfTI-1", 0)

    # NIfTI-2, uint8
    p = os.path.join(tmp, "uint8_v2.nii")
    nib.save(nib.Nifti2Image(lab.astype(np.uint8), diag), p)
    check(p, "NIfTI-2", 0)

    # big-endian int32 with negative labels
    p = os.path.join(tmp, "int32_be.nii.gz")
    hdr = nib.Nifti1Header(endianness=">")
    nib.save(nib.Nifti1Image((lab - 4).astype(">i4"), diag, hdr), p)
    check(p, "NIfTI-1", 0)

    # float32 with values that are not integers
    p = os.path.join(tmp, "float32.nii.gz")
    f = lab.astype(np.float32)
    f[::2, 1, :] += np.float32(0.3)
    f[1, ::2, ::3] -= np.float32(0.4)
    nib.save(nib.Nifti1Image(f, diag), p)
    check(p, "NIfTI-1", 0)

    # scl_slope 2, scl_inter -3 on uint8 voxels
    p = os.path.join(tmp, "scaled.nii")
    im = nib.Nifti1Image(lab.astype(np.uint8), diag)
    im.header.set_slope_inter(2.0, -3.0)
    nib.save(im, p)
    check(p, "NIfTI-1", 0)

    # an oblique sform: rotations about x and z, anisotropic voxels
    p = os.path.join(tmp, "oblique.nii.gz")
    aff = np.eye(4)
    aff[:3, :3] = rotation(2, 30) @ rotation(0, 20) @ np.diag([0.8, 1.1, 2.0])
    aff[:3, 3] = [1.5, 2.5, -3.5]
    im = nib.Nifti1Image(lab.astype(np.int16), aff)
    nib.save(im, p)
    check(p, "NIfTI-1", 1)

    # a qform alone (sform_code 0), with a flip (qfac -1)
    p = os.path.join(tmp, "qform.nii")
    aff = np.eye(4)
    aff[:3, :3] = rotation(1, 25) @ np.diag([1.0, 1.5, -2.0])
    aff[:3, 3] = [-4, 5, 6]
    im = nib.Nifti1Image(lab.astype(np.int16), None)
    im.header.set_qform(aff, code=1)
    im.header.set_sform(None, code=0)
    nib.save(im, p)
    check(p, "NIfTI-1", 1)

    # an axis permutation and flip in the sform: not oblique
    p = os.path.join(tmp, "perm.nii")
    aff = np.array([[0, 0, -1.5, 3], [0.5, 0, 0, 4], [0, 2.0, 0, 5], [0, 0, 0, 1]])
    nib.save(nib.Nifti1Image(lab.astype(np.int16), aff), p)
    check(p, "NIfTI-1", 0)

    subprocess.run(["rm", "-rf", tmp])
    if failures:
        print(f"{failures} failure(s)")
        sys.exit(1)


main()
