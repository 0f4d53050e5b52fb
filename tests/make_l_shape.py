"""The L of the tests: the unit cube less [1/2, 1] x [0, 1] x [1/2, 1], as OFF
(argv[1]). Its inner faces lie in the root's middle planes, lattice planes at
every level: inside nodes lie exactly on them, and octants outside touch
them by a face only (tests/tag_faces_test.sh, tests/restart_lattice_test.sh)."""
import sys
# the L profile in (x, z), counter-clockwise seen from -y, extruded along y
prof = [(0, 0), (1, 0), (1, 0.5), (0.5, 0.5), (0.5, 1), (0, 1)]
n = len(prof)
verts = [(x, 0.0, z) for x, z in prof] + [(x, 1.0, z) for x, z in prof]
tris = []
r = 3  # the reflex corner sees every other one: a fan from it
for i in range(n):
    a, b = (r + 1 + i) % n, (r + 2 + i) % n
    if r in (a, b):
        continue
    tris.append((r, a, b))            # y = 0
    tris.append((n + r, n + b, n + a))  # y = 1
for i in range(n):
    a, b = i, (i + 1) % n
    tris.append((a, n + a, n + b))
    tris.append((a, n + b, b))
def vol(t):
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = (verts[k] for k in t)
    return (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6
if sum(vol(t) for t in tris) < 0:
    tris = [t[::-1] for t in tris]
assert abs(abs(sum(vol(t) for t in tris)) - 0.75) < 1e-12
with open(sys.argv[1], "w") as f:
    f.write("OFF\n%d %d 0\n" % (len(verts), len(tris)))
    f.writelines("%.17g %.17g %.17g\n" % p for p in verts)
    f.writelines("3 %d %d %d\n" % t for t in tris)
