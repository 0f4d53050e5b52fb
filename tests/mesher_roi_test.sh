#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# End-to-end tests of the mesher_roi front (src/cli/mesher_roi.c): the
# commands of a typical job script written for the published mesher, run on
# the shared surfaces. The argument is mixoct (or the mesher_roi link); the
# script makes its own link named mesher_roi in a temporary directory and
# runs there. Data from $MIXOCT_DATA (default ../shared/data next to the source tree), never
# copied into the repository. Needs python3 (the files are parsed back).
MIXOCT=${1:?usage: mesher_roi_test.sh path/to/mixoct}
MIXOCT=$(readlink -f "$MIXOCT")
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
# meson points MIXOCT_DATA at the source tree's ../shared/data; a clone made
# elsewhere falls back to the usual place
[ -d "$DATA/surfaces" ] || DATA=$HERE/../../shared/data
S=$DATA/surfaces
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
ln -s "$MIXOCT" "$T/mesher_roi"
ROI=$T/mesher_roi
cd "$T" || exit 1
. "$HERE/lib.sh"
check_mesh() { # file, description
  if "$MIXOCT" check "$1" >"$T/check" 2>&1; then ok "$2: mixoct check clean"; else bad "$2: mixoct check"; cat "$T/check"; fi
}

# Compares NAME.getfem, NAME.m3d and NAME.mvm (when there) with NAME.vtk:
# same points (bit for bit in GetFEM, to the 9 digits of "%+1.8E" in M3D and
# MVM), same elements; M3D and MVM rows are ours (VTK's but for the prism,
# Gmsh's: REFERENCE.md, "Published output layouts"); GetFEM rows are VTK's
# in GetFEM's node order, with a positive Jacobian at each element's centre
# under GetFEM's shape functions, and a total volume that matches mixoct
# check's.
compare_formats() { # name, volume from mixoct check
  python3 - "$1" "$2" <<'EOF'
import sys
name, want_volume = sys.argv[1], float(sys.argv[2])
fails = 0
def bad(msg):
    global fails
    fails += 1
    print("FAIL", msg)

def read_vtk(path):
    tok = open(path).read().split()
    i = tok.index("POINTS"); n = int(tok[i + 1]); i += 3
    xyz = [tuple(float(t) for t in tok[i + 3 * k:i + 3 * k + 3]) for k in range(n)]
    i = tok.index("CELLS"); m = int(tok[i + 1]); i += 3
    cells = []
    for _ in range(m):
        k = int(tok[i]); cells.append([int(t) for t in tok[i + 1:i + 1 + k]]); i += 1 + k
    return xyz, cells

def read_getfem(path):
    text = open(path).read()
    body = text[text.index("BEGIN POINTS LIST"):]
    tok = body.split()
    i = 3; xyz = []
    while tok[i] != "END":
        assert tok[i] == "POINT"
        if tok[i + 1] == "COUNT": i += 3; continue
        assert int(tok[i + 1]) == len(xyz)
        xyz.append(tuple(float(t) for t in tok[i + 2:i + 5])); i += 5
    assert tok[i:i + 3] == ["END", "POINTS", "LIST"]; i += 3
    assert tok[i:i + 4] == ["BEGIN", "MESH", "STRUCTURE", "DESCRIPTION"]; i += 4
    nodes = {"'GT_PK(3,1)'": 4, "'GT_PYRAMID(1)'": 5, "'GT_PRISM(3,1)'": 6, "'GT_QK(3,1)'": 8}
    cells = []
    while tok[i] != "END":
        assert tok[i] == "CONVEX"
        if tok[i + 1] == "COUNT": i += 3; continue
        assert int(tok[i + 1]) == len(cells)
        k = nodes[tok[i + 2]]
        cells.append([int(t) for t in tok[i + 3:i + 3 + k]]); i += 3 + k
    assert tok[i:i + 4] == ["END", "MESH", "STRUCTURE", "DESCRIPTION"]; i += 4
    # then the boundary tags as regions: BEGIN REGION t, cv/f pairs, END REGION t
    while i < len(tok):
        assert tok[i:i + 2] == ["BEGIN", "REGION"]; t = tok[i + 2]; i += 3
        while tok[i] != "END":
            cv, f = tok[i].split("/"); assert 0 <= int(cv) < len(cells); i += 1
        assert tok[i:i + 3] == ["END", "REGION", t]; i += 3
    return xyz, cells

letters = {"T": 4, "P": 5, "R": 6, "H": 8}
def read_letter_cells(tok, i, m, tail):
    cells = []
    for _ in range(m):
        k = letters[tok[i]]; cells.append([int(t) for t in tok[i + 1:i + 1 + k]]); i += 1 + k
        if tail:
            assert tok[i:i + 3] == ["1000.0", "0.45", "1.0"]; i += 3
    assert i == len(tok)
    return cells

def read_m3d(path):
    tok = open(path).read().split()
    assert tok[:2] == ["[Nodes,", "ARRAY1<STRING>]"]
    n = int(tok[2]); i = 3
    assert all(tok[i + 4 * k] == "1" for k in range(n))
    xyz = [tuple(float(t) for t in tok[i + 4 * k + 1:i + 4 * k + 4]) for k in range(n)]
    i += 4 * n
    assert tok[i:i + 2] == ["[Elements,", "ARRAY1<STRING>]"]
    return xyz, read_letter_cells(tok, i + 3, int(tok[i + 2]), True)

def read_mvm(path):
    tok = open(path).read().split()
    assert tok[0] == "MIXED"
    n, m = int(tok[1]), int(tok[2]); i = 3
    xyz = [tuple(float(t) for t in tok[i + 3 * k:i + 3 * k + 3]) for k in range(n)]
    return xyz, read_letter_cells(tok, i + 3 * n, m, False)

def close(a, b):
    return len(a) == len(b) and all(abs(x - y) <= 1e-8 * abs(y) for p, q in zip(a, b) for x, y in zip(p, q))

# GetFEM shape functions (documented reference elements) and their gradients.
def shape(k, x, y, z):
    if k == 4: return [1 - x - y - z, x, y, z]
    if k == 5:
        q = x * y / (1 - z)
        return [0.25 * (1 - x - y - z + q), 0.25 * (1 + x - y - z - q),
                0.25 * (1 - x + y - z - q), 0.25 * (1 + x + y - z + q), z]
    if k == 6:
        t = [1 - x - y, x, y]; s = [1 - z, z]
        return [t[i] * s[j] for j in range(2) for i in range(3)]
    s = [[1 - x, x], [1 - y, y], [1 - z, z]]
    return [s[0][a] * s[1][b] * s[2][c] for c in range(2) for b in range(2) for a in range(2)]
centre = {4: (0.25, 0.25, 0.25), 5: (0.0, 0.0, 0.25), 6: (1 / 3, 1 / 3, 0.5), 8: (0.5, 0.5, 0.5)}
ref_volume = {4: 1 / 6, 5: 4 / 3, 6: 0.5, 8: 1.0}
def jacobian(k, p):
    h = 1e-6; r = centre[k]; J = []
    for b in range(3):
        rp = list(r); rm = list(r); rp[b] += h; rm[b] -= h
        fp = shape(k, *rp); fm = shape(k, *rm)
        J.append([sum((fp[i] - fm[i]) * p[i][a] for i in range(k)) / (2 * h) for a in range(3)])
    (a, b, c), (d, e, f), (g, hh, i) = J
    return a * (e * i - f * hh) - b * (d * i - f * g) + c * (d * hh - e * g)

vxyz, vcells = read_vtk(name + ".vtk")
# from the .vtk file's order (a VTK wedge is our prism with 1-2 and 4-5
# swapped, see src/soa/mesh.h) to GetFEM's
order = {4: [0, 1, 2, 3], 5: [0, 1, 3, 2, 4], 6: [0, 2, 1, 3, 5, 4], 8: [0, 1, 3, 2, 4, 5, 7, 6]}
gxyz, gcells = read_getfem(name + ".getfem")
if gxyz != vxyz: bad("getfem points differ from vtk")
if len(gcells) != len(vcells): bad("getfem: %d convexes, vtk %d cells" % (len(gcells), len(vcells)))
volume = 0.0; worst = float("inf")
for g, v in zip(gcells, vcells):
    if len(g) != len(v) or g != [v[j] for j in order[len(v)]]:
        bad("getfem convex %s is not vtk cell %s in GetFEM's order" % (g, v)); break
    j = jacobian(len(g), [gxyz[n] for n in g])
    worst = min(worst, j)
    volume += j * ref_volume[len(g)]
if not worst > 0: bad("getfem: an element has J <= 0 at its centre (%g)" % worst)
if abs(volume - want_volume) > 0.01 * want_volume:
    bad("getfem volume %g, mixoct check %g" % (volume, want_volume))
ours = [[v[j] for j in [0, 2, 1, 3, 5, 4]] if len(v) == 6 else v for v in vcells]
import os
for ext, reader in ((".m3d", read_m3d), (".mvm", read_mvm)):
    if ext == ".mvm" and not os.path.exists(name + ext): continue
    mxyz, mcells = reader(name + ext)
    if not close(mxyz, vxyz): bad(ext + " nodes differ from vtk")
    if mcells != ours: bad(ext + " elements differ from vtk cells")
print("%s: %d nodes, %d elements; getfem volume %.6g (check %.6g), min J %.3g" %
      (name, len(vxyz), len(vcells), volume, want_volume, worst))
sys.exit(1 if fails else 0)
EOF
}
volume_of() { "$MIXOCT" check "$1" --json 2>/dev/null | tail -1 | python3 -c 'import json,sys; print(json.load(sys.stdin)["volume"])'; }

# Help and refusals.
expect_exit 0 "-h" "$ROI" -h
has "$T/out" "-u NAME" "help lists -u"
has "$T/out" "NAME.getfem" "help names the GetFEM file"
has "$T/out" "NAME.mvm" "help names the MVM file (-i)"
expect_exit 2 "-c with a missing restart file" "$ROI" -o "$S/cortex.off" -c "$T/in.oct" -u x -v
has "$T/err" "in.oct" "-c names its file"
expect_exit 2 "-l without -c" "$ROI" -o "$S/cortex.off" -l "$T/list.txt" -s 4 -u x -v
has "$T/err" "restart file" "-l without -c says why"
absent "$T/x.vtk" "nothing written after a refusal"

# Re-meshing as a job script does it: mesh with -u NAME (NAME.oct written
# too), then -c NAME.oct -l LIST; and from the published program's c5.oct.
R=$DATA/remesh
expect_exit 0 "mesh and restart file" "$ROI" -o "$S/cortex.off" -s 4 -u c4 -v
exists "$T/c4.oct"
printf '0 5 17\n100 100\n' >"$T/l4.txt"
expect_exit 0 "re-mesh from our restart file" "$ROI" -o "$S/cortex.off" -c c4.oct -l l4.txt -u c4r -v
exists "$T/c4r.vtk"
exists "$T/c4r.oct"
check_mesh "$T/c4r.vtk" "re-meshed from c4.oct"
# the same list as numpy.savetxt writes it: the same mesh; a word: exit 2
printf '%s\n' 0.000000000000000000e+00 5.000000000000000000e+00 1.700000000000000000e+01 \
  1.000000000000000000e+02 1.000000000000000000e+02 >"$T/l4np.txt"
expect_exit 0 "re-mesh with the list in numpy.savetxt format" "$ROI" -o "$S/cortex.off" -c c4.oct -l l4np.txt -u c4np -v
if cmp -s "$T/c4r.vtk" "$T/c4np.vtk"; then ok "numpy.savetxt list: the same mesh as the integers"; else bad "numpy.savetxt list: another mesh than the integers"; fi
printf '0 5\nx17\n' >"$T/l4x.txt"
expect_exit 2 "a list with a word" "$ROI" -o "$S/cortex.off" -c c4.oct -l l4x.txt -u c4x -v
has "$T/err" 'l4x.txt:2: .*"x17" is not an element index' "the word is named with its line"
absent "$T/c4x.vtk" "nothing written after a bad list"
if [ -f "$R/c5.oct" ]; then
  expect_exit 0 "re-mesh the published c5.oct with its list" "$ROI" -o "$S/cortex.off" -c "$R/c5.oct" -l "$R/list.txt" -u p5r -v --json
  exists "$T/p5r.vtk"
  check_mesh "$T/p5r.vtk" "published c5.oct re-meshed"
  tail -1 "$T/out" | python3 -c 'import json,sys; d=json.load(sys.stdin); print("published c5.oct + list.txt: nodes", d["nodes"], "elements", d["elements"], "(published 14319 / 33254)"); sys.exit(0 if d["nodes"] > 10941 and d["invalid"] == 0 else 1)' && ok "c5.oct re-mesh grew the mesh" || bad "c5.oct re-mesh counts"
  printf '1 2 26209\n' >"$T/l_big.txt"
  expect_exit 2 "a list index out of range" "$ROI" -o "$S/cortex.off" -c "$R/c5.oct" -l "$T/l_big.txt" -u bad -v
  has "$T/err" "l_big.txt:1" "the out-of-range index is named with its line"
  expect_exit 2 "the restart file of another surface" "$ROI" -o "$S/$(ls "$S" | grep -v cortex | head -1)" -c "$R/c5.oct" -u bad -v
  has "$T/err" "c5.oct" "the wrong-surface message names the file"
  absent "$T/bad.vtk" "nothing written after a bad re-mesh"
fi
expect_exit 2 "missing input" "$ROI" -o "$T/nope.off" -s 4 -u x -v
has "$T/err" "nope.off" "missing input is named"
expect_exit 2 "missing MDL input" "$ROI" -d "$T/nope.mdl" -s 4 -u x -v
has "$T/err" "nope.mdl" "missing MDL is named"
expect_exit 2 "no input" "$ROI" -s 4 -u x -v
expect_exit 2 "format without -u" "$ROI" -o "$S/cortex.off" -s 4 -v
expect_exit 2 "-u without a format" "$ROI" -o "$S/cortex.off" -s 4 -u x
expect_exit 2 "unknown flag" "$ROI" -o "$S/cortex.off" -s 4 -q
expect_exit 2 "bad level" "$ROI" -o "$S/cortex.off" -s x -u x -v
expect_exit 2 "-s without its level" "$ROI" -o "$S/cortex.off" -s
absent "$T/x.vtk" "no output from failed runs"

# The reference job: mesher_roi -o cortex.off -s RL -u out -v
expect_exit 0 "-o cortex.off -s 4 -u out -v" "$ROI" -o "$S/cortex.off" -s 4 -u out -v
exists out.vtk
absent out.getfem "-v alone writes no GetFEM file"
check_mesh out.vtk "cortex -s 4"
if head -3 out.vtk | grep -qx ASCII; then ok "out.vtk is ASCII legacy VTK"; else bad "out.vtk is not ASCII"; fi
[ -z "$(ls "$T" | grep '\.tmp\.')" ] && ok "no temporaries left" || bad "temporaries left: $(ls "$T")"

# All four formats of one mesh from an MDL surface.
expect_exit 0 "-d femur.mdl -s 4 -u f -v -g -m -i" "$ROI" -d "$S/femur.mdl" -s 4 -u f -v -g -m -i
exists f.vtk; exists f.getfem; exists f.m3d; exists f.mvm
check_mesh f.vtk "femur -s 4"
check_mesh f.mvm "femur -s 4 (.mvm)"
if compare_formats f "$(volume_of f.vtk)"; then ok "femur: .getfem, .m3d and .mvm match .vtk"; else bad "femur: formats differ"; fi

# The same mesh as mixoct -i ... -o gives (the front only translates).
"$MIXOCT" -i "$S/femur.mdl" -s 4 -o direct.vtk --ascii --quiet
if cmp -s direct.vtk f.vtk; then ok "same bytes as mixoct -i femur.mdl -s 4 -o .vtk --ascii"; else bad "front and mixoct differ"; fi

# Formats one by one, and a path in -u.
mkdir -p sub
expect_exit 0 "-u sub/g -g" "$ROI" -o "$S/cortex.off" -s 4 -u sub/g -g
exists sub/g.getfem; absent sub/g.vtk "-g alone writes no VTK"
expect_exit 0 "-u sub/m -m" "$ROI" -o "$S/cortex.off" -s 4 -u sub/m -m
exists sub/m.m3d
expect_exit 0 "-u sub/i -i" "$ROI" -o "$S/cortex.off" -s 4 -u sub/i -i
exists sub/i.mvm; absent sub/i.m3d "-i alone writes no M3D"
expect_exit 0 "-u sub/c -v -g -m -i (cortex)" "$ROI" -o "$S/cortex.off" -s 4 -u sub/c -m -g -v -i
if compare_formats sub/c "$(volume_of sub/c.vtk)"; then ok "cortex: .getfem, .m3d and .mvm match .vtk"; else bad "cortex: formats differ"; fi
if cmp -s sub/g.getfem sub/c.getfem && cmp -s sub/m.m3d sub/c.m3d && cmp -s sub/i.mvm sub/c.mvm && cmp -s out.vtk sub/c.vtk; then
  ok "one format at a time gives the same files"; else bad "files depend on the other format flags"; fi

# Box regions with a surface level, as in the ROI jobs.
expect_exit 0 "-o cortex.off -s 3 -b cortex.reg -u roi -v" "$ROI" -o "$S/cortex.off" -s 3 -b "$S/cortex.reg" -u roi -v
check_mesh roi.vtk "cortex -s 3 -b cortex.reg"
n_s3=$("$ROI" -o "$S/cortex.off" -s 3 --json --quiet | tail -1 | python3 -c 'import json,sys; print(json.load(sys.stdin)["elements"])')
n_b=$(python3 -c 'import sys; t=open("roi.vtk").read().split(); print(t[t.index("CELLS")+1])')
[ "$n_b" -gt "$n_s3" ] && ok "-b refines beyond -s 3 ($n_b > $n_s3 elements)" || bad "-b had no effect ($n_b vs $n_s3)"
expect_exit 2 "missing .reg" "$ROI" -o "$S/cortex.off" -s 3 -b "$T/nope.reg" -u r2 -v
has "$T/err" "nope.reg" "missing .reg is named"

# A region surface, all-level refinement, threads and JSON pass through.
expect_exit 0 "-r region surface" "$ROI" -d "$S/outer_sphere.mdl" -s 2 -r "$S/in_spher.mdl" 4 -u rs -v --threads 2
check_mesh rs.vtk "sphere -r"
expect_exit 0 "-a 3 dry run" "$ROI" -o "$S/cortex.off" -a 3 --json
if tail -1 "$T/out" | python3 -c 'import json,sys; d=json.load(sys.stdin); sys.exit(0 if d["elements"] > 0 else 1)'; then
  ok "--json passes through"; else bad "--json output"; fi

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
