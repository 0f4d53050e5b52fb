#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# `mixoct check` against the surface as several files, one per input of the
# run (issue 26, touching inputs; src/verify/check_pieces.c): the mesher's
# own materials on boxes glued on faces, checked with --surface repeated.
# The boxes (python3 writes them): A = [0, 1]^3, B = [1, 2] x [0, 1]^2,
# C = [0, 1] x [1, 2] x [0, 1], each side a 3 x 3 grid of squares cut in two
# triangles along the same diagonal, so that the faces two boxes share are
# the same 18 triangles in both files.
# Derived, not recorded: A and B share 18 triangles each way (36 lie on
# another file's); the union's volume 2 (L of three: 3); each material in
# its own region: regions by (depth 0, file), numbered 1, 2, 3 in the order
# the files are given, so the material of A is region 1 with A given first
# and region 2 with B first; every region holds 1.
MIXOCT=${1:?usage: check_touching_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"
json_ok() { # file, python expression on d, description
  if python3 -c "import json,sys; d=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1]); sys.exit(0 if ($2) else 1)" "$1" 2>/dev/null; then
    ok "$3"; else bad "$3: $(tail -c 400 "$1")"; fi
}

python3 - "$T" <<'EOF'
import sys

def box(lo, hi, n=3):
    """Each side an n x n grid of squares, 2 triangles each (the diagonal
    from the square's smallest corner), outward."""
    index, verts, tris = {}, [], []
    def vertex(p):
        if p not in index:
            index[p] = len(verts)
            verts.append(p)
        return index[p]
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        for side in (0, 1):
            for i in range(n):
                for j in range(n):
                    q = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0.0, 0.0, 0.0]
                        p[a] = hi[a] if side else lo[a]
                        p[b] = lo[b] + (hi[b] - lo[b]) * (i + di) / n
                        p[c] = lo[c] + (hi[c] - lo[c]) * (j + dj) / n
                        q.append(vertex(tuple(p)))
                    t1, t2 = (q[0], q[1], q[2]), (q[0], q[2], q[3])
                    if side == 0:
                        t1, t2 = t1[::-1], t2[::-1]
                    tris += [t1, t2]
    return verts, tris

def write(path, v, t):
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(v), len(t)))
        f.writelines("%.17g %.17g %.17g\n" % p for p in v)
        f.writelines("3 %d %d %d\n" % x for x in t)

d = sys.argv[1]
write(d + "/a.off", *box((0, 0, 0), (1, 1, 1)))
write(d + "/b.off", *box((1, 0, 0), (2, 1, 1)))
write(d + "/c.off", *box((0, 1, 0), (1, 2, 1)))
EOF

expect_exit 0 "two boxes glued on a face, --materials" "$MIXOCT" -i "$T/a.off" -i "$T/b.off" \
  --materials -s 4 -o "$T/ab.msh" -o "$T/ab.vtu" --quiet
for f in ab.msh ab.vtu; do
  expect_exit 0 "check $f --surface a.off --surface b.off" "$MIXOCT" check "$T/$f" \
    --surface "$T/a.off" --surface "$T/b.off" --json
  cp "$T/out" "$T/ab.json"
  json_ok "$T/ab.json" "d['defects'] == 0 and d['surface_files'] == 2 and d['surface_pieces'] == 2 and d['shared_triangles'] == 36 and abs(d['surface_volume'] - 2) < 1e-12" "$f: 2 files, 2 pieces, 36 triangles on another file's, the union's volume 2"
  json_ok "$T/ab.json" "[m['region'] for m in d['materials']] == [1, 2] and all(abs(m['region_volume'] - 1) < 1e-12 for m in d['materials']) and d['materials_volume_off'] == 0 and d['across_interface']['elements'] == 0 and d['off_label_region']['elements'] == 0 and d['interface_off_surface'] == 0" "$f: each material in its own region of volume 1, none across, none off"
done
expect_exit 0 "the text report" "$MIXOCT" check "$T/ab.msh" --surface="$T/a.off" --surface="$T/b.off"
has "$T/out" "surfaces  *$T/a.off" "the report names the first file"
has "$T/out" "^  *$T/b.off" "and the second"
has "$T/out" "2 closed shells in 2 files; 36 triangles" "the pieces and the shared triangles"
has "$T/out" "OK, no defect" "no defect"
expect_exit 0 "the files in the other order" "$MIXOCT" check "$T/ab.msh" --surface "$T/b.off" \
  --surface "$T/a.off" --json
json_ok "$T/out" "d['defects'] == 0 and [m['region'] for m in d['materials']] == [2, 1]" "B given first: its material is region 1, A's region 2"
# one of the two files: the mesh is twice its volume (a defect), and half
# of the mesh lies outside it
expect_exit 5 "check against a.off alone" "$MIXOCT" check "$T/ab.msh" --surface "$T/a.off" --json
json_ok "$T/out" "d['volume_off'] == 1 and 'surface_files' not in d" "a.off alone: volume off, the one-file report"

expect_exit 0 "an L of three boxes, --materials" "$MIXOCT" -i "$T/a.off" -i "$T/b.off" -i "$T/c.off" \
  --materials -s 4 -o "$T/abc.msh" --quiet
expect_exit 0 "check the L against its three files" "$MIXOCT" check "$T/abc.msh" \
  --surface "$T/a.off" --surface "$T/b.off" --surface "$T/c.off" --json
json_ok "$T/out" "d['defects'] == 0 and d['surface_files'] == 3 and d['shared_triangles'] == 72 and abs(d['surface_volume'] - 3) < 1e-12 and [m['region'] for m in d['materials']] == [1, 2, 3]" "the L: 3 files, 72 triangles shared, volume 3, a region each"

expect_exit 2 "--poly with --surface twice" "$MIXOCT" check "$T/ab.msh" --surface "$T/a.off" \
  --surface "$T/b.off" --poly "$T/a.off"
expect_exit 2 "a missing second surface" "$MIXOCT" check "$T/ab.msh" --surface "$T/a.off" \
  --surface "$T/nope.off"
has "$T/err" "nope.off" "the missing file is named"

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
