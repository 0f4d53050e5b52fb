#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# `mixoct check` on 2D meshes (io/read_mesh.h: mx_read_mesh_dim,
# src/mesher/check_file.c): the shared polylines a, box and pie meshed by mesher2d at two levels into VTU,
# legacy VTK (ASCII and binary), MSH 4.1 (ASCII and binary) and OFF; each
# file checked with and without its domain (exit 0, the node, cell and type
# counts of mesher2d's --json, the same edge count and Euler number in every
# format); then meshes broken on purpose, each defect counted exactly where
# the breakage allows it to be derived here (python3 edits an ASCII VTK and
# computes the expected counts from the cells it changed):
#   a cell turned clockwise       inverted 1, bad edges = its shared edges
#   an inner cell removed         a hole: euler - 1, boundary edges + its
#                                 sides; exit 0 alone, with the domain its
#                                 nodes off the polylines and topology off
#   a quad split with a new node  hanging 1 (a T-junction on its neighbour)
#     on a shared edge
#   a boundary node moved inward  off_boundary 1 with the domain, exit 0
#                                 without
#   the wrong domain              off_boundary > 0, area off
# 2D and 3D cells mixed: a 3D mesh whose triangle is a tagged face (exit 5,
# it is not on the boundary); and input errors (exit 2, file and line): a
# 3D surface with a 2D mesh,
# polylines with a 3D mesh, z != 0, pentagons,
# truncated files. The argument is the mixoct program.
BIN=${1:?usage: check2d_test.sh path/to/mixoct}
BIN=$(readlink -f "$BIN")
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
[ -d "$DATA/polylines" ] || DATA=$HERE/../../shared/data
PL=$DATA/polylines
command -v python3 >/dev/null || { echo "SKIP: python3 not found"; exit 77; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
ln -s "$BIN" "$T/mesher2d"
M2=$T/mesher2d
cd "$T" || exit 1
. "$HERE/lib.sh"

cat >"$T/tool.py" <<'EOF'
import sys

def read_vtk(path):
    """mesher2d's ASCII legacy VTK: points, cells (node lists), the lines."""
    lines = open(path).read().split('\n')
    i = next(k for k, l in enumerate(lines) if l.startswith('POINTS'))
    n = int(lines[i].split()[1])
    pts = [list(map(float, lines[i + 1 + k].split())) for k in range(n)]
    c = next(k for k, l in enumerate(lines) if l.startswith('CELLS'))
    m = int(lines[c].split()[1])
    cells = [list(map(int, lines[c + 1 + k].split()))[1:] for k in range(m)]
    return lines, i + 1, pts, c + 1, cells

def write_vtk(path, pts, cells):
    with open(path, 'w') as f:
        f.write('# vtk DataFile Version 3.0\nedited\nASCII\nDATASET UNSTRUCTURED_GRID\n')
        f.write('POINTS %d double\n' % len(pts))
        for p in pts: f.write('%.17g %.17g %.17g\n' % tuple(p))
        f.write('CELLS %d %d\n' % (len(cells), sum(len(c) + 1 for c in cells)))
        for c in cells: f.write('%d %s\n' % (len(c), ' '.join(map(str, c))))
        f.write('CELL_TYPES %d\n' % len(cells))
        for c in cells: f.write('%d\n' % (9 if len(c) == 4 else 5))

def edge_use(cells):
    use = {}
    for c in cells:
        for j in range(len(c)):
            e = tuple(sorted((c[j], c[(j + 1) % len(c)])))
            use[e] = use.get(e, 0) + 1
    return use

def sides(c):
    return [tuple(sorted((c[j], c[(j + 1) % len(c)]))) for j in range(len(c))]

cmd = sys.argv[1]
src, dst = sys.argv[2], sys.argv[3]
lines, p0, pts, c0, cells = read_vtk(src)
use = edge_use(cells)
bnode = {v for e, u in use.items() if u == 1 for v in e}
if cmd == 'flip':  # reverse one cell in place (the file is kept otherwise)
    k = len(cells) // 2
    c = cells[k]
    lines[c0 + k] = '%d %s' % (len(c), ' '.join(map(str, c[::-1])))
    open(dst, 'w').write('\n'.join(lines))
    print(sum(use[e] == 2 for e in sides(c)))  # expected bad edges
elif cmd == 'delete':  # remove a cell none of whose nodes is on the boundary
    k = next(k for k, c in enumerate(cells) if not bnode & set(c))
    n = len(cells[k])
    del cells[k]
    write_vtk(dst, pts, cells)
    print(n)
elif cmd == 'hang':  # a quad a b c d with (b, c) shared -> a b m, a m c, a c d
    for k, c in enumerate(cells):
        if len(c) != 4: continue
        r = next((r for r in range(4) if use[sides(c)[(r + 1) % 4]] == 2), None)
        if r is not None: break
    else: sys.exit('no quad with a shared side')
    a, b, cc, d = (c[(r + j) % 4] for j in range(4))
    m = len(pts)
    pts.append([(pts[b][i] + pts[cc][i]) / 2 for i in range(3)])
    cells[k:k + 1] = [[a, b, m], [a, m, cc], [a, cc, d]]
    write_vtk(dst, pts, cells)
    print(1)
elif cmd == 'move':  # a boundary node between two collinear boundary edges, moved inward
    nxt = {}
    for c in cells:
        for j in range(len(c)):
            a, b = c[j], c[(j + 1) % len(c)]
            if use[tuple(sorted((a, b)))] == 1: nxt[a] = b  # domain on the left of a -> b
    prv = {b: a for a, b in nxt.items()}
    for v in sorted(nxt):
        a, b = pts[prv[v]], pts[nxt[v]]
        u = (pts[v][0] - a[0], pts[v][1] - a[1]); w = (b[0] - pts[v][0], b[1] - pts[v][1])
        lu, lw = (u[0] ** 2 + u[1] ** 2) ** .5, (w[0] ** 2 + w[1] ** 2) ** .5
        if abs(u[0] * w[1] - u[1] * w[0]) < 1e-9 * lu * lw and u[0] * w[0] + u[1] * w[1] > 0: break
    else: sys.exit('no boundary node between collinear edges')
    s = 0.01 * min(lu, lw)
    pts[v][0] -= s * w[1] / lw
    pts[v][1] += s * w[0] / lw
    lines[p0 + v] = '%.17g %.17g 0' % (pts[v][0], pts[v][1])
    open(dst, 'w').write('\n'.join(lines))
    print(v)
EOF
# J FILE KEY...: the values of the keys in the JSON object on FILE's last
# line, blank-separated (the first occurrence of each key: by_type.tri is
# "tri"; python3 starts too slowly for the many look-ups here)
J() {
  local L out=() k re last=""
  mapfile -t L <"$1"; shift
  [ "${#L[@]}" -gt 0 ] && last=${L[${#L[@]} - 1]}
  for k; do
    re="\"${k##*.}\": ?([^,}]*)"
    if [[ $last =~ $re ]]; then out+=("${BASH_REMATCH[1]}"); else out+=("?"); fi
  done
  echo "${out[*]}"
}
TOOL() { python3 "$T/tool.py" "$@"; }

# ---- a hand-made mesh: counts by hand ---------------------------------------
# two unit squares side by side: 6 nodes, 2 quads, 7 edges (6 on the
# boundary), V - E + F = 6 - 7 + 2 = 1, area 2
printf 'OFF\n6 2 0\n0 0 0\n1 0 0\n2 0 0\n0 1 0\n1 1 0\n2 1 0\n4 0 1 4 3\n4 1 2 5 4\n' >two.off
printf '4 2 0 0\n0 0 0\n1 2 0\n2 2 1\n3 0 1\n4 0\n0 0 1\n1 1 2\n2 2 3\n3 3 0\n0\n' >two.poly
expect_exit 0 "two squares (OFF)" "$BIN" check two.off --json
same "$(J out dimension nodes elements by_type.quad edges boundary_edges euler area)" \
  "2 6 2 2 7 6 1 2" "two squares: counts"
expect_exit 0 "two squares against their polygon" "$BIN" check two.off --poly two.poly --json
same "$(J out domain_area area_error domain_euler off_boundary missing_features defects)" \
  "2 0 1 0 0 0" "two squares: domain counts"
# the same in VTK 5.1 (OFFSETS + CONNECTIVITY), the right square as 2 triangles
printf '# vtk DataFile Version 5.1\nv5\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 6 double\n0 0 0 1 0 0 2 0 0\n0 1 0 1 1 0 2 1 0\nCELLS 4 10\nOFFSETS vtktypeint64\n0 4 7 10\nCONNECTIVITY vtktypeint64\n0 1 4 3\n1 2 5\n1 5 4\nCELL_TYPES 3\n9\n5\n5\n' >v5.vtk
expect_exit 0 "VTK 5.1 2D mesh" "$BIN" check v5.vtk --poly two.poly --json
same "$(J out elements by_type.tri by_type.quad edges euler area)" "3 2 1 8 1 2" "VTK 5.1: counts"
# text report
expect_exit 0 "text report" "$BIN" check two.off --surface two.poly
has out "2D mesh" "report says 2D"
has out "conforming  *yes" "report says conforming"

# ---- mesher2d's meshes in every format -----------------------------------------
runs="a:-s:6 a:-s:7 box:-a:3 box:-s:5 pie:-s:6 pie:-s:7"
for run in $runs; do
  IFS=: read -r dom flag lev <<<"$run"
  base=${dom}_${flag#-}$lev
  if ! "$M2" -p "$PL/$dom.poly" "$flag" "$lev" -O "$base.vtu" -O "$base.vtk" -O "$base.msh" \
       -O "$base.off" --json >"$base.json" 2>"$T/err" ||
     ! "$M2" -p "$PL/$dom.poly" "$flag" "$lev" --binary -O "${base}_b.vtk" -O "${base}_b.msh" \
       >/dev/null 2>>"$T/err"; then
    bad "mesher2d $dom $flag $lev failed"; cat "$T/err"; continue
  fi
  want=$(J "$base.json" nodes elements by_type.tri by_type.quad)
  ref=""
  for f in "$base.vtu" "$base.vtk" "${base}_b.vtk" "$base.msh" "${base}_b.msh" "$base.off"; do
    "$BIN" check "$f" --json >"$T/out" 2>"$T/err"; e1=$?
    "$BIN" check "$f" --poly "$PL/$dom.poly" --json >"$T/outp" 2>>"$T/err"; e2=$?
    got=$(J out nodes elements by_type.tri by_type.quad)
    topo=$(J out edges boundary_edges euler)
    vd=$(J outp valid defects off_boundary missing_features topology_off area_off)
    if [ "$e1" -eq 0 ] && [ "$e2" -eq 0 ] && [ "$got" == "$want" ] &&
       [ "$vd" == "true 0 0 0 0 0" ] && { [ -z "$ref" ] || [ "$topo" == "$ref" ]; }; then
      ok "$f: exit 0 alone and with $dom.poly, counts $got as mesher2d's"
    else
      bad "$f: exits $e1 $e2, counts '$got' (mesher2d '$want'), edges/euler '$topo' (first '$ref'), domain '$vd'"
      cat "$T/err"
    fi
    [ -n "$ref" ] || ref=$topo
  done
done

# ---- broken meshes --------------------------------------------------------------
B=box_a3
P=$PL/box.poly
exp=$(TOOL flip "$B.vtk" flip.vtk)
expect_exit 5 "a cell turned clockwise" "$BIN" check flip.vtk --json
same "$(J out inverted bad_edges hanging conforming valid)" "1 $exp 0 false false" \
  "clockwise cell: inverted 1, $exp bad edges"

read -r e0 b0 <<<"$("$BIN" check "$B.vtk" --json | tail -1 >ref.json; J ref.json euler boundary_edges)"
nv=$(TOOL delete "$B.vtk" hole.vtk)
expect_exit 0 "an inner cell removed: still a valid mesh alone" "$BIN" check hole.vtk --json
same "$(J out euler boundary_edges)" "$((e0 - 1)) $((b0 + nv))" "hole: euler - 1, boundary + $nv"
expect_exit 5 "an inner cell removed, against the domain" "$BIN" check hole.vtk --poly "$P" --json
same "$(J out off_boundary topology_off inverted hanging bad_edges)" "$nv 1 0 0 0" \
  "hole: its $nv nodes off the polylines, topology off"

TOOL hang "$B.vtk" hang.vtk >/dev/null
expect_exit 5 "a T-junction" "$BIN" check hang.vtk --json
same "$(J out hanging bad_edges inverted conforming)" "1 0 0 false" "T-junction: 1 hanging node"

TOOL move "${B}.vtk" move.vtk >/dev/null
expect_exit 0 "a boundary node moved inward: valid alone" "$BIN" check move.vtk --json
expect_exit 5 "a boundary node moved inward, against the domain" "$BIN" check move.vtk --poly "$P" --json
same "$(J out off_boundary missing_features inverted topology_off area_off)" "1 0 0 0 0" \
  "moved node: off_boundary 1"

expect_exit 5 "the wrong domain" "$BIN" check a_s6.vtu --poly "$P" --json
read -r ob ao <<<"$(J out off_boundary area_off)"
if [ "$ob" -gt 0 ] && [ "$ao" -eq 1 ]; then ok "wrong domain: $ob off, area off"; else bad "wrong domain: off $ob area_off $ao"; fi
expect_exit 5 "the wrong domain (text)" "$BIN" check pie_s6.msh --poly "$PL/a.poly"
has out "not valid" "report says not valid"

# ---- input errors ----------------------------------------------------------------
printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n' >tet.off
expect_exit 2 "3D surface with a 2D mesh" "$BIN" check two.off --surface tet.off
has err "tet.off:6" "3D surface: names file and line"
has err "2D mesh" "3D surface: says the mesh is 2D"
expect_exit 2 "3D surface (.stl) with a 2D mesh" "$BIN" check two.off --surface x.stl
has err "3D surface" "3D .stl: says so"
expect_exit 2 "a 3D OFF surface as the mesh" "$BIN" check tet.off
has err "tet.off:6" "3D OFF mesh: names file and line"
printf 'OFF\n5 1 0\n0 0 0\n1 0 0\n1 1 0\n0.5 1.5 0\n0 1 0\n5 0 1 2 3 4\n' >pent.off
expect_exit 2 "a pentagon" "$BIN" check pent.off
has err "pent.off:8" "pentagon: names file and line"
printf '# vtk DataFile Version 3.0\nm\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 0\nCELLS 2 9\n4 0 1 2 3\n3 1 4 2\nCELL_TYPES 2\n10\n5\n' >mixed.vtk
# volume cells with 2D cells: a 3D mesh, its triangles tagged faces (as
# Gmsh's .vtk files have them); this one is not a face of the tetrahedron
expect_exit 5 "2D and 3D cells mixed: a 3D mesh with a tagged face" "$BIN" check mixed.vtk
has out "tagged not boundary      1" "mixed: the triangle is a tagged face off the boundary"
printf '# vtk DataFile Version 3.0\nz\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 double\n0 0 0\n1 0 0\n0 1 0.5\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n' >zoff.vtk
expect_exit 2 "a triangle off the plane" "$BIN" check zoff.vtk
has err "zoff.vtk:8" "z != 0: names file and line"
head -n 40 box_a3.vtk >trunc.vtk
expect_exit 2 "truncated VTK" "$BIN" check trunc.vtk
has err "trunc.vtk:" "truncated VTK: named"
head -c 2000 box_a3_b.msh >trunc.msh
expect_exit 2 "truncated binary MSH" "$BIN" check trunc.msh
has err "trunc.msh" "truncated MSH: named"
expect_exit 2 "--poly and --surface together" "$BIN" check two.off --poly two.poly --surface two.poly
if "$BIN" --demo -s 2 -o d3.vtu >/dev/null 2>&1; then
  expect_exit 0 "a 3D mesh still checked as before" "$BIN" check d3.vtu --json
  same "$(J out defects)" "0" "3D mesh: no defect"
  if grep -q dimension out; then bad "3D JSON unchanged"; else ok "3D JSON unchanged"; fi
  expect_exit 2 "polylines with a 3D mesh" "$BIN" check d3.vtu --poly two.poly
  has err "3D mesh" "polylines with 3D: says so"
  expect_exit 2 "a .poly as --surface of a 3D mesh" "$BIN" check d3.vtu --surface two.poly
else
  bad "mixoct --demo failed"
fi

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
