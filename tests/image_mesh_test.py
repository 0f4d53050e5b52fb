#!/usr/bin/env python3
"""Label images end to end (issue 28): synthetic images written here with
nibabel (NIfTI) and by hand (MetaImage, INR), meshed by the program as a
new user would (`mixoct -i labels.nii.gz -o out.msh`, no other option) and
through the Python binding (a numpy array with its affine), and judged by
`mixoct check` (the independent verifier: conformity, validity, labels and
their boundaries) and by the voxels:

  - exit 0, no defect, one material per label, each label's volume within
    its interface's half-voxel band of the voxel count times the voxel
    volume, the interfaces tagged in the .msh ("interface A | B");
  - --voxel: the volumes are the voxels' exactly;
  - --label-names names the materials; --merge-labels and --skip-labels
    change the materials; --min-island drops a one-voxel island;
  - the same mesh from .nii.gz, .mha and .inr of one image, and from the
    Python binding's array (same node and element counts);
  - bad images: exit 2 with the file named on stderr, and no output left.

usage: image_mesh_test.py MIXOCT BUILD_PYTHON_DIR
SKIP (77) without numpy or nibabel, unless the environment variable CI is
set (then a failure).
"""
import gzip
import json
import os
import subprocess
import sys
import tempfile

failures = 0


def check(cond, what):
    global failures
    if not cond:
        failures += 1
        print("FAIL:", what)
    else:
        print("ok:", what)


def missing(what):
    if os.environ.get("CI"):
        print("image_mesh: FAIL: %s (CI is set: install python3-numpy python3-nibabel)" % what)
        sys.exit(1)
    print("image_mesh: SKIP:", what)
    sys.exit(77)


try:
    import numpy as np
    import nibabel as nib
except ImportError as e:
    missing(str(e))

exe = sys.argv[1]
sys.path.insert(0, sys.argv[2])
tmp = tempfile.mkdtemp(prefix="mixoct-image-")


def run(*args):
    p = subprocess.run([exe] + list(args), capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def check_json(path):
    rc, out, err = run("check", path, "--json")
    return rc, json.loads(out.strip().splitlines()[-1]) if out.strip() else {}


def voxel_stats(lab):
    """voxels and interface voxel faces per label"""
    cnt, faces = {}, {}
    p = np.pad(lab, 1)
    for L in np.unique(lab):
        if L == 0:
            continue
        m = p == L
        f = 0
        for a in range(3):
            d = np.diff(m.astype(np.int8), axis=a)
            f += int(np.count_nonzero(d))
        cnt[int(L)] = int(m.sum())
        faces[int(L)] = f
    return cnt, faces


n = 28
i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
c = 13.4
r = np.sqrt((i - c) ** 2 + (j - c) ** 2 + (k - c) ** 2)
lab = np.zeros((n, n, n), np.uint8)
lab[r < 12] = 1
lab[r < 8] = 2
lab[r < 4] = 3
lab[2, 2, 2] = 4  # an island of one voxel, apart from the rest
spacing = np.array([0.8, 0.8, 1.2])
aff = np.diag([spacing[0], spacing[1], spacing[2], 1.0])
aff[:3, 3] = [-5.0, 3.0, 7.0]
vox = float(np.prod(spacing))
nii = os.path.join(tmp, "balls.nii.gz")
nib.save(nib.Nifti1Image(lab, aff), nii)
cnt, faces = voxel_stats(lab)

# the plain command, .msh out
out = os.path.join(tmp, "balls.msh")
rc, so, se = run("-i", nii, "-o", out)
check(rc == 0, "plain command: exit 0 (%d: %s)" % (rc, se.strip()[-200:]))
rc, rep = check_json(out)
check(rc == 0 and rep.get("defects", 1) in (0, None) and "OK" in json.dumps(rep.get("result", "OK")),
      "mixoct check: no defect")
mats = {int(x["label"]): x for x in rep.get("materials", {}).get("labels", [])} \
    if isinstance(rep.get("materials"), dict) else {}
print("  check json materials:", json.dumps(rep.get("materials"))[:300])
rc2, so2, _ = run("-i", nii, "-o", os.path.join(tmp, "b.vtu"), "--json")
img = json.loads(so2.strip().splitlines()[-1]).get("image", {})
labels = {x["label"]: x for x in img.get("labels", [])}
check(sorted(labels) == [1, 2, 3, 4], "one material per label (%s)" % sorted(labels))
for L in (1, 2, 3):
    got = labels.get(L, {}).get("volume", 0.0)
    want, band = cnt[L] * vox, 0.5 * faces[L] * vox
    check(abs(got - want) <= band, "label %d volume %.3f within %.3f of %.3f" % (L, got, band, want))
with open(out, "rb") as f:
    msh = f.read()
check(b"interface label 1 | label 2" in msh and b"interface label 2 | label 3" in msh,
      ".msh: the interfaces are physical surfaces")

# --voxel: exact voxel volumes
rc, so, se = run("-i", nii, "-o", os.path.join(tmp, "v.vtu"), "--voxel", "--json")
img = json.loads(so.strip().splitlines()[-1]).get("image", {}) if rc == 0 else {}
ok = rc == 0 and all(abs(x["volume"] - cnt[x["label"]] * vox) < 1e-6 * cnt[x["label"]] * vox  # float32 header
                     for x in img.get("labels", [])) and len(img.get("labels", [])) == 4
check(ok, "--voxel: each label's volume is its voxels' exactly")

# names, merges, skips, islands
names = os.path.join(tmp, "names.txt")
with open(names, "w") as f:
    f.write("# FreeSurfer-like table\n0 Unknown 0 0 0 0\n1 csf 1 2 3 0\n2 grey_matter\n3 white_matter\n")
rc, so, se = run("-i", nii, "-o", os.path.join(tmp, "n.msh"), "--label-names", names,
                 "--merge-labels", "3:2", "--skip-labels", "4", "--json")
img = json.loads(so.strip().splitlines()[-1]).get("image", {}) if rc == 0 else {}
got = {x["label"]: x["name"] for x in img.get("labels", [])}
check(got == {1: "csf", 2: "grey_matter"}, "--label-names, --merge-labels 3:2, --skip-labels 4: %s" % got)
with open(os.path.join(tmp, "n.msh"), "rb") as f:
    check(b'"grey_matter"' in f.read(), ".msh: the named physical volume")
rc, so, se = run("-i", nii, "-o", os.path.join(tmp, "i.vtu"), "--min-island", "2", "--json")
img = json.loads(so.strip().splitlines()[-1]).get("image", {}) if rc == 0 else {}
check(sorted(x["label"] for x in img.get("labels", [])) == [1, 2, 3] and img.get("islands") == 1,
      "--min-island 2 drops the one-voxel island")

# the same image as MetaImage and INR (written by hand), and from Python
lab_u8 = np.asfortranarray(lab)
mha = os.path.join(tmp, "balls.mha")
with open(mha, "wb") as f:
    f.write(("ObjectType = Image\nNDims = 3\nDimSize = %d %d %d\nElementType = MET_UCHAR\n"
             "ElementSpacing = %g %g %g\nOffset = -5 3 7\nElementDataFile = LOCAL\n"
             % (n, n, n, spacing[0], spacing[1], spacing[2])).encode())
    f.write(lab_u8.tobytes(order="F"))
inr = os.path.join(tmp, "balls.inr.gz")
head = ("#INRIMAGE-4#{\nXDIM=%d\nYDIM=%d\nZDIM=%d\nVDIM=1\nTYPE=unsigned fixed\nPIXSIZE=8 bits\n"
        "SCALE=2**0\nCPU=decm\nVX=%g\nVY=%g\nVZ=%g\nXO=-5\nYO=3\nZO=7\n" %
        (n, n, n, spacing[0], spacing[1], spacing[2]))
head = head + "\n" * (256 - len(head) - 4) + "##}\n"
with gzip.open(inr, "wb") as f:
    f.write(head.encode() + lab_u8.tobytes(order="F"))
counts = {}
for path in (nii, mha, inr):
    rc, so, se = run("-i", path, "-o", os.path.join(tmp, "x.vtu"), "--json")
    d = json.loads(so.strip().splitlines()[-1]) if rc == 0 else {}
    counts[os.path.basename(path)] = (d.get("nodes"), d.get("elements"))
try:
    import mixoct
    m = mixoct.Mesher()
    m.add_label_image(lab, affine=aff)
    m.mesh()
    counts["python"] = (m.nnodes, m.nelements)
    check(sorted(np.unique(m.material).tolist()) == [1, 2, 3, 4], "python: the materials")
except Exception as e:  # noqa: BLE001
    check(False, "python binding: %s" % e)
check(len(set(counts.values())) == 1, "same mesh from nii.gz, mha, inr.gz, python: %s" % counts)

# bad images: exit 2, the file named, no output left
bad = os.path.join(tmp, "cut.nii.gz")
raw = gzip.decompress(open(nii, "rb").read())
with gzip.open(bad, "wb") as f:
    f.write(raw[: len(raw) // 2])
junk = os.path.join(tmp, "junk.mha")
with open(junk, "w") as f:
    f.write("ObjectType = Image\nNDims = 3\nDimSize = 4 4\nElementType = MET_UCHAR\n")
empty = os.path.join(tmp, "empty.nii")
nib.save(nib.Nifti1Image(np.zeros((4, 4, 4), np.uint8), np.eye(4)), empty)
ct = os.path.join(tmp, "intensity.nii")  # an intensity image, not labels
nib.save(nib.Nifti1Image((np.arange(4096).reshape(16, 16, 16) % 1000).astype(np.int16),
                         np.eye(4)), ct)
for path in (bad, junk, empty, ct):
    o = os.path.join(tmp, "bad.vtu")
    rc, so, se = run("-i", path, "-o", o)
    check(rc == 2 and os.path.basename(path) in se and not os.path.exists(o),
          "%s: exit 2 naming the file, nothing written (%d: %s)" % (os.path.basename(path), rc,
                                                                    se.strip()[:160]))

# a size inside a label: more leaves, all of label 1's at the finest level
r1 = run("-i", nii, "-o", os.path.join(tmp, "s.vtu"), "--json")
r2 = run("-i", nii, "-o", os.path.join(tmp, "s.vtu"), "--label-size", "1:1", "--json")
l1 = json.loads(r1[1].strip().splitlines()[-1]).get("leaves", 0) if r1[0] == 0 else 0
l2 = json.loads(r2[1].strip().splitlines()[-1]).get("leaves", 0) if r2[0] == 0 else 0
check(r2[0] == 0 and l2 > l1 > 0, "--label-size 1:1: more leaves (%d against %d)" % (l2, l1))
rc, so, se = run("-i", nii, "-o", os.path.join(tmp, "s.vtu"), "--label-size", "1:0")
check(rc == 2 and "--label-size" in se, "--label-size 1:0 refused")

# a size field in the world (voxels of 0.8 x 0.8 x 1.2 mm): 0.5 mm asks
# for every voxel, 100 mm for nothing more
r3 = run("-i", nii, "-o", os.path.join(tmp, "s.vtu"), "--size", "0.5", "--json")
r4 = run("-i", nii, "-o", os.path.join(tmp, "s.vtu"), "--size", "100", "--json")
l3 = json.loads(r3[1].strip().splitlines()[-1]).get("leaves", 0) if r3[0] == 0 else 0
l4 = json.loads(r4[1].strip().splitlines()[-1]).get("leaves", 0) if r4[0] == 0 else 0
check(l3 > l1 and l4 == l1, "--size 0.5: more leaves (%d), --size 100: the same (%d = %d)"
      % (l3, l4, l1))
rc, so, se = run("-i", nii, "-o", os.path.join(tmp, "s.vtu"), "--curvature", "10")
check(rc == 2 and "curvature" in se, "--curvature with an image refused (no surface)")

# what does not apply to an image is refused, not ignored; the budget
o = os.path.join(tmp, "r.vtu")
rc, so, se = run("-i", nii, "-s", "5", "-o", o)
check(rc == 2 and "label image" in se and not os.path.exists(o), "-s with an image: exit 2")
rc, so, se = run("-i", nii, "--restart", os.path.join(tmp, "r.oct"), "-o", o)
check(rc == 2 and not os.path.exists(o), "--restart with an image: exit 2")
rc, so, se = run("-i", nii, "--max-memory", "1", "-o", o)
check(rc == 3 and "balls.nii.gz" in se and "MB" in se and not os.path.exists(o),
      "--max-memory 1: exit 3 with the estimate (%s)" % se.strip()[:120])

print("%d failure(s)" % failures)
sys.exit(1 if failures else 0)
