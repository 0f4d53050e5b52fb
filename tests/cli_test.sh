#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# End-to-end tests of the mixoct program: exit codes, messages that name the
# file and line, no partial output, JSON summary, determinism across threads,
# requests through the command line on box surfaces (counts reasoned in
# test_octree.c).
MIXOCT=${1:?usage: cli_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"


expect_exit 0 "--help" "$MIXOCT" --help
has "$T/out" "--surface-level" "help lists the options"
expect_exit 0 "--version" "$MIXOCT" --version
expect_exit 2 "no input" "$MIXOCT" -s 3
expect_exit 2 "unknown option" "$MIXOCT" --demo --frobnicate
expect_exit 2 "bad level" "$MIXOCT" --demo -s x
expect_exit 2 "missing file" "$MIXOCT" -i "$T/nope.off" -s 2
has "$T/err" "nope.off" "missing file is named"

cube_off "$T/cube.off" 0.5
sed 's/^3 3 7 5$/3 3 7 99/' "$T/cube.off" >"$T/badidx.off"
expect_exit 2 "index out of range" "$MIXOCT" -i "$T/badidx.off" -s 2
has "$T/err" "badidx.off:22" "bad index names file and line"
printf 'OFF\n8 12 0\n0 0 0\n' >"$T/trunc.off"
expect_exit 2 "truncated file" "$MIXOCT" -i "$T/trunc.off" -s 2
has "$T/err" "trunc.off" "truncated file is named"
sed 's/^0.5 0.5 0.5$/nan 0.5 0.5/' "$T/cube.off" >"$T/nan.off"
expect_exit 2 "NaN coordinate" "$MIXOCT" -i "$T/nan.off" -s 2
has "$T/err" "nan.off:" "NaN names the file and line"

# Requests on the unit cube (see test_octree.c for the reasoning).
leaves() { "$MIXOCT" "$@" --json --quiet | tail -1 | python3 -c 'import json,sys; print(json.load(sys.stdin)["leaves"])'; }
[ "$(leaves -i "$T/cube.off" -s 3)" = 456 ] && ok "-s 3 on the cube: 456 leaves" || bad "-s 3 on the cube"
[ "$(leaves -i "$T/cube.off" -a 2)" = 64 ] && ok "-a 2 on the cube: 64 leaves" || bad "-a 2 on the cube"
printf 'n_regions 1\n0.01 0.01 0.01\n0.02 0.02 0.02\n3\n' >"$T/roi.reg"
[ "$(leaves -i "$T/cube.off" -b "$T/roi.reg")" = 64 ] && ok "-b box level 3: 64 leaves" || bad "-b box"
cube_off "$T/inner.off" 0.15
# Inward orientation does not matter for parity; the inner shell is a hole.
[ "$(leaves -i "$T/cube.off" -i "$T/inner.off" -s 3)" = 504 ] && ok "two shells make a hole: 504 leaves" || bad "two shells"
cube_off "$T/region.off" 0.2
[ "$(leaves -i "$T/cube.off" -r "$T/region.off" 3)" = 120 ] && ok "-r region level 3: 120 leaves" || bad "-r region"

# JSON summary keys, output written, nothing temporary left.
"$MIXOCT" --demo -s 4 --stage octree -o "$T/demo.vtu" --json >"$T/json" 2>"$T/err"
[ $? -eq 0 ] && ok "demo meshes" || bad "demo"
tail -1 "$T/json" | python3 -c '
import json, sys
d = json.load(sys.stdin)
for k in ["nodes", "elements", "by_type", "leaves", "phases", "total_s", "peak_rss_mb", "threads", "jens_min", "invalid"]:
    assert k in d, k
for k in ["read", "grid", "refine", "balance", "write"]:
    assert k in d["phases"], k
assert d["leaves"] > 0 and d["elements"] == d["leaves"] and d["nodes"] > d["leaves"]
' && ok "JSON summary has the keys" || bad "JSON summary"
[ -s "$T/demo.vtu" ] && ok "VTU written" || bad "VTU missing"
ls "$T" | grep -q tmp && bad "temporary file left" || ok "no temporary left"
expect_exit 4 "unwritable output" "$MIXOCT" --demo -s 3 --stage octree -o "$T/no/such/dir/x.vtu"
[ ! -e "$T/no" ] && ok "no partial output" || bad "partial output"

# Determinism: byte-identical output for 1 and 2 threads, both balances.
"$MIXOCT" --demo -s 5 --stage octree -o "$T/t1.vtk" --threads 1 --quiet
"$MIXOCT" --demo -s 5 --stage octree -o "$T/t2.vtk" --threads 2 --quiet
"$MIXOCT" --demo -s 5 --stage octree -o "$T/r2.vtk" --threads 2 --quiet --balance recursive
cmp -s "$T/t1.vtk" "$T/t2.vtk" && ok "1 and 2 threads: identical bytes" || bad "threads differ"
cmp -s "$T/t1.vtk" "$T/r2.vtk" && ok "edges and recursive: identical bytes" || bad "balances differ"
# ... and the same mixed meshes: the transition after the recursive balance
# reads edge infos built for the balanced tree (it once had none: hexahedra
# with hanging nodes, exit 0)
for s in transition full; do
  "$MIXOCT" --demo -s 5 --stage $s -o "$T/e_$s.vtk" --quiet
  "$MIXOCT" --demo -s 5 --stage $s -o "$T/r_$s.vtk" --quiet --balance recursive
  cmp -s "$T/e_$s.vtk" "$T/r_$s.vtk" && ok "--stage $s: edges and recursive, identical bytes" \
    || bad "--stage $s: the balances give different meshes"
done

# Memory budget and output names are checked before any meshing.
expect_exit 3 "a run that cannot fit is refused" "$MIXOCT" --demo -s 15
has "$T/err" "needs about" "the refusal says how much it needs"
expect_exit 3 "--max-memory is a limit" "$MIXOCT" --demo -s 7 --max-memory 10
expect_exit 2 "an unknown output format is refused first" "$MIXOCT" --demo -s 3 -o "$T/x.obj"
has "$T/err" "x.obj" "the refusal names the output"

# Transition stage: a conforming mesh that the independent
# checker accepts, the same bytes for 1 and 2 threads, and the pattern table.
"$MIXOCT" -i "$T/cube.off" -s 3 -o "$T/cube3.vtu" --quiet --stage transition
expect_exit 0 "check accepts the cube's transition mesh" "$MIXOCT" check "$T/cube3.vtu" --json
tail -1 "$T/out" | python3 -c '
import json, sys
d = json.load(sys.stdin)
assert d["defects"] == 0 and d["invalid"] == 0, d
assert abs(d["volume"] - 1.01**3) < 1e-9, d["volume"]
' && ok "cube mesh: 0 defects, the root cube's volume" || bad "cube mesh check"
"$MIXOCT" --demo -s 5 -o "$T/m1.vtu" --threads 1 --quiet --stage transition
"$MIXOCT" --demo -s 5 -o "$T/m2.vtu" --threads 2 --quiet --stage transition
cmp -s "$T/m1.vtu" "$T/m2.vtu" && ok "transition mesh: identical bytes for 1 and 2 threads" || bad "transition threads differ"
expect_exit 0 "check accepts the demo's transition mesh" "$MIXOCT" check "$T/m1.vtu"
printf 'not a mesh\n' >"$T/junk.vtu"
expect_exit 2 "check refuses a broken file" "$MIXOCT" check "$T/junk.vtu"
has "$T/err" "junk.vtu" "check names the broken file"
"$MIXOCT" patterns --json >"$T/pat" && tail -1 "$T/pat" | python3 -c '
import json, sys
d = json.load(sys.stdin)
assert d["configurations"] == 6210 and d["classes"] == 325, d
assert d["centre_classes"] <= 65 and d["worst_jens"] >= 0.172, d
assert set(d["by_type"]) == {"tet", "pyramid", "prism", "hex"}
' && ok "patterns --json: 325 classes, centre and quality targets" || bad "patterns --json"

# --help groups, --version contents, and no progress line when stderr is not
# a terminal (job scripts and these tests): a clean run prints nothing there.
"$MIXOCT" --help >"$T/help"
for g in "Input" "Refinement requests" "Output:" "Execution:" "Subcommands:" "Examples:"; do
  has "$T/help" "$g" "help has the group '$g'"
done
"$MIXOCT" --version >"$T/version"
for k in "mixoct [0-9]" "build " "compiler " "OpenMP max threads" "topology "; do
  has "$T/version" "$k" "version shows '$k'"
done
"$MIXOCT" --demo -s 5 >"$T/out" 2>"$T/err"
[ ! -s "$T/err" ] && ok "no progress on stderr when it is not a terminal" || bad "stderr not empty: $(cat "$T/err")"
has "$T/out" "J_ENS" "the summary has the J_ENS table"
has "$T/out" "peak memory" "the summary has the peak memory"

# Full disk and denied permission: exit 2, a message naming the file, and no
# partial or temporary file left in the directory.
only_has() { # dir, expected listing (space separated, sorted), description
  local got; got=$(ls -A "$1" | sort | tr '\n' ' ' | sed 's/ $//')
  [ "$got" = "$2" ] && ok "$3" || bad "$3: '$got' left in $1"
}
expect_exit 4 "output under /dev/full (not a directory)" "$MIXOCT" --demo -s 3 -o /dev/full/x.vtu
has "$T/err" "/dev/full/x.vtu" "the message names /dev/full/x.vtu"
# A full disk: /dev/full behind a .vtu name is written in place (a device).
mkdir "$T/full" && ln -s /dev/full "$T/full/out.vtu"
expect_exit 4 "full disk (/dev/full)" "$MIXOCT" --demo -s 3 -o "$T/full/out.vtu"
has "$T/err" "full/out.vtu" "the full-disk message names the file"
has "$T/err" "No space left" "the full-disk message says why"
only_has "$T/full" "out.vtu" "full disk: nothing but the link left"
[ "$(readlink "$T/full/out.vtu")" = /dev/full ] && ok "full disk: the device link is untouched" || bad "the /dev/full link was replaced"
# A disk filling up half-way through a regular file: a file-size limit
# (SIGXFSZ ignored, so writes fail with EFBIG as they would with ENOSPC).
mkdir "$T/fsize"
(ulimit -f 16 && trap '' XFSZ && exec "$MIXOCT" --demo -s 5 -o "$T/fsize/x.vtu") >"$T/out" 2>"$T/err"
got=$?
[ "$got" -eq 4 ] && ok "output cut short by a full disk (exit 4)" || bad "output cut short: exit $got, wanted 4"
has "$T/err" "fsize/x.vtu" "the cut-short message names the file"
only_has "$T/fsize" "" "cut short: no partial or temporary file left"
# A read-only directory. Root ignores permissions: then run as nobody
# (setpriv), or, if that cannot run mixoct, skip this one case (the next two
# cover a directory that cannot be written whoever runs the test).
mkdir "$T/ro" && chmod 555 "$T/ro"
as_user=()
if [ "$(id -u)" -eq 0 ]; then
  chmod 711 "$T"
  if command -v setpriv >/dev/null &&
     setpriv --reuid=65534 --regid=65534 --clear-groups "$MIXOCT" --version >/dev/null 2>&1 &&
     ! setpriv --reuid=65534 --regid=65534 --clear-groups touch "$T/ro/probe" 2>/dev/null; then
    as_user=(setpriv --reuid=65534 --regid=65534 --clear-groups)
  else
    as_user=(skip)
  fi
fi
if [ "${as_user[0]:-}" = skip ]; then
  ok "read-only directory: skipped (root, and setpriv cannot run mixoct as nobody)"
else
  expect_exit 4 "read-only directory" "${as_user[@]}" "$MIXOCT" --demo -s 3 -o "$T/ro/x.vtu"
  has "$T/err" "ro/x.vtu" "the read-only message names the file"
  has "$T/err" "Permission denied" "the read-only message says why"
  only_has "$T/ro" "" "read-only directory: nothing left"
fi
chmod 700 "$T/ro"
printf 'x\n' >"$T/plain"
expect_exit 4 "output under a regular file" "$MIXOCT" --demo -s 3 -o "$T/plain/x.vtu"
has "$T/err" "plain/x.vtu" "the message names the file under a regular file"
if [ -d /sys/kernel ]; then
  expect_exit 4 "output in /sys (denied even to root)" "$MIXOCT" --demo -s 3 -o /sys/mixoct-test.vtu
  has "$T/err" "/sys/mixoct-test.vtu" "the /sys message names the file"
  [ ! -e /sys/mixoct-test.vtu ] && ok "nothing written in /sys" || bad "a file appeared in /sys"
fi

# Two inputs that overlap (the same cube twice) bound no domain: refused,
# naming both files.
cube_off "$T/twin.off" 0.5
expect_exit 2 "overlapping inputs are refused" "$MIXOCT" -i "$T/cube.off" -i "$T/twin.off" -s 2
has "$T/err" "twin.off" "the refusal names the second input"
has "$T/err" "cube.off" "the refusal names the first input"

# ---- the contract of exit 0 and what a new user tries (issue 10) ----------
json_ok() { # file, python expression on d, description
  if python3 -c "import json,sys; d=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1]); sys.exit(0 if ($2) else 1)" "$1" 2>/dev/null; then
    ok "$3"; else bad "$3: $(tail -c 400 "$1")"; fi
}
expect_exit 2 "no refinement request" "$MIXOCT" -i "$T/cube.off" -o "$T/none.vtu"
has "$T/err" "no refinement request" "no request: said so"
[ ! -e "$T/none.vtu" ] && ok "no request: no file" || bad "no request wrote a file"
expect_exit 2 "an empty result" "$MIXOCT" -i "$T/cube.off" -s 0 -o "$T/empty.vtu"
has "$T/err" "the mesh is empty" "empty result: said so"
[ ! -e "$T/empty.vtu" ] && ok "empty result: no file" || bad "an empty mesh was written"
expect_exit 2 "--json on a refused run" "$MIXOCT" -i "$T/cube.off" --json
json_ok "$T/out" "d['valid'] is False and d['exit_code'] == 2 and 'refinement' in d['error']" "--json of a refused run: valid false, the error"
expect_exit 0 "attached values: -s3 --output=" "$MIXOCT" -i "$T/cube.off" -s3 "--output=$T/att.vtu" --quiet
[ -s "$T/att.vtu" ] && ok "--output=FILE written" || bad "--output=FILE not written"
expect_exit 0 "several -o" "$MIXOCT" -i "$T/cube.off" -s 3 -o "$T/m1.vtu" -o "$T/m2.msh" -o "$T/m3.mesh"
for f in m1.vtu m2.msh m3.mesh; do
  [ -s "$T/$f" ] && ok "several -o: $f written" || bad "several -o: $f missing"
  has "$T/out" "written      $T/$f" "several -o: a line for $f"
done
expect_exit 0 "a dry run" "$MIXOCT" -i "$T/cube.off" -s 3
has "$T/out" "dry run" "a run without -o says it is a dry run"
expect_exit 0 "--json with outputs" "$MIXOCT" -i "$T/cube.off" -s 3 -o "$T/j.vtu" --json
json_ok "$T/out" "d['valid'] is True and d['exit_code'] == 0 and d['outputs'][0]['bytes'] > 0 and d['warnings'] == []" "--json: valid, outputs with sizes"
# --smooth: 0 is off (the default), 3 rounds never lower the mesh's worst
# element and say so in the summary and the JSON
expect_exit 0 "--smooth 0" "$MIXOCT" --demo -s 4 --smooth 0 --json
json_ok "$T/out" "d['boundary']['smoothing']['rounds'] == 0 and d['boundary']['smoothing']['moved'] == 0 and d['invalid'] == 0" "--smooth 0: no smoothing"
cp "$T/out" "$T/smooth0.json"
expect_exit 0 "--smooth 3" "$MIXOCT" --demo -s 4 --smooth 3 --json
json_ok "$T/out" "d['boundary']['smoothing']['rounds'] >= 1 and d['boundary']['smoothing']['moved'] > 0 and d['boundary']['smoothing']['jens_min_after'] >= d['boundary']['smoothing']['jens_min_before'] and d['invalid'] == 0" "--smooth 3: nodes moved, the worst J_ENS not lowered"
expect_exit 0 "--smooth 3 summary" "$MIXOCT" --demo -s 4 --smooth 3
has "$T/out" "smoothing " "--smooth 3: a summary line"
expect_exit 2 "--smooth -1" "$MIXOCT" --demo -s 4 --smooth -1
has "$T/err" "--smooth" "a bad --smooth is named"
start=$(date +%s%N)
expect_exit 4 "an output directory that does not exist, before meshing" "$MIXOCT" --demo -s 6 -o "$T/nodir/x.vtu" -o "$T/ok.vtu"
elapsed=$(( ($(date +%s%N) - start) / 1000000 ))
has "$T/err" "nodir/x.vtu" "the missing directory is named"
[ ! -e "$T/ok.vtu" ] && ok "nothing meshed nor written when one output cannot be ($elapsed ms)" || bad "the other output was written"
expect_exit 2 "an unknown second output format" "$MIXOCT" -i "$T/cube.off" -s 3 -o "$T/a.vtu" -o "$T/b.xyz"
printf '\xef\xbb\xbf' >"$T/bom.off"; cat "$T/cube.off" >>"$T/bom.off"
expect_exit 0 "a UTF-8 byte-order mark is skipped" "$MIXOCT" -i "$T/bom.off" -s 3 --quiet
ln -s /dev/zero "$T/zero.off"
expect_exit 2 "a device is refused" "$MIXOCT" -i "$T/zero.off" -s 3
has "$T/err" "device" "the device refusal says why"
printf 'OFF\n\033[2J 3 0\n' >"$T/ctl.off"
expect_exit 2 "control characters in the input" "$MIXOCT" -i "$T/ctl.off" -s 3
if grep -q $'\033' "$T/err"; then bad "a control character reached the terminal"; else ok "control characters escaped in the message"; fi
has "$T/err" '\\x1b' "the escape shows as \\x1b"
printf 'n_regions 1\n0 0 0 1 1 1 99999\n' >"$T/lvl.reg"
expect_exit 2 "a .reg level out of range" "$MIXOCT" -i "$T/cube.off" -b "$T/lvl.reg"
has "$T/err" "lvl.reg:2" "the .reg level error names file and line"
mkdir -p "$T/real"; : >"$T/real/target.vtu"; ln -s real/target.vtu "$T/link.vtu"
expect_exit 0 "a symbolic link as -o" "$MIXOCT" -i "$T/cube.off" -s 3 -o "$T/link.vtu" --quiet
[ -L "$T/link.vtu" ] && [ -s "$T/real/target.vtu" ] && ok "written through the link, the link kept" || bad "the symbolic link was replaced"
box_off() { # file, sx, sy, sz
  python3 - "$@" <<'PY'
import sys
f, sx, sy, sz = sys.argv[1], *map(float, sys.argv[2:])
v = [(0,0,0),(sx,0,0),(sx,sy,0),(0,sy,0),(0,0,sz),(sx,0,sz),(sx,sy,sz),(0,sy,sz)]
t = [(0,2,1),(0,3,2),(4,5,6),(4,6,7),(0,1,5),(0,5,4),(1,2,6),(1,6,5),(2,3,7),(2,7,6),(3,0,4),(3,4,7)]
open(f, "w").write("OFF\n8 12 0\n" + "".join("%r %r %r\n" % p for p in v) + "".join("3 %d %d %d\n" % x for x in t))
PY
}
box_off "$T/beam.off" 100 1 1
expect_exit 0 "an elongated beam (100 x 1 x 1) is meshed" "$MIXOCT" -i "$T/beam.off" -s 5 -o "$T/beam.vtu" --quiet
expect_exit 0 "the beam's mesh checks" "$MIXOCT" check "$T/beam.vtu" --surface "$T/beam.off"
box_off "$T/plate.off" 1 1 1e-10
expect_exit 2 "a plate thinner than the finest octant is refused" timeout 20 "$MIXOCT" -i "$T/plate.off" -s 3
has "$T/err" "plate.off" "the thin-plate refusal names the file"
box_off "$T/long.off" 3e9 1 1
expect_exit 2 "a 3e9 x 1 x 1 box is refused, not hung" timeout 20 "$MIXOCT" -i "$T/long.off" -s 3
box_off "$T/tiny.off" 1e-110 1e-110 1e-110
expect_exit 2 "coordinates of size 1e-110 are refused" timeout 20 "$MIXOCT" -i "$T/tiny.off" -s 3
has "$T/err" "out of range" "tiny coordinates: said why"
box_off "$T/huge.off" 1e160 1e160 1e160
expect_exit 2 "coordinates of size 1e160 are refused" timeout 20 "$MIXOCT" -i "$T/huge.off" -s 3
# --boundary: the tagged boundary faces in a .vtu of their own, asked before meshing
expect_exit 0 "--boundary writes the boundary faces" "$MIXOCT" --demo -s 3 -o "$T/bd.msh" --boundary "$T/bd_faces.vtu" --quiet
if [ -s "$T/bd_faces.vtu" ] && grep -q 'Name="surface_tag"' "$T/bd_faces.vtu" &&
   grep -q 'NumberOfCells="[1-9]' "$T/bd_faces.vtu"; then
  ok "the boundary file has faces and a surface_tag field"
else
  bad "the boundary file: $(head -c 300 "$T/bd_faces.vtu" 2>&1)"
fi
if grep -aq '^2 1 "demo"' "$T/bd.msh"; then ok "the .msh names the boundary tag after the input"; else bad "no physical group \"demo\" in the .msh"; fi
expect_exit 2 "--boundary wants .vtu, .stl, .off or .ply" "$MIXOCT" --demo -s 3 --boundary "$T/bd.msh"
# the same faces as plain surfaces: counts against the .vtu's, the OFF and
# PLY closed and outward (meshed again; the mesh's boundary lies on them with
# the volume of the mesh, up to the non-planar quadrilaterals the surface
# splits in two: 2e-7 at -s 3), the STL's triangles 1 per triangle + 2 per quad
for e in stl off ply; do
  expect_exit 0 "--boundary .$e" "$MIXOCT" --demo -s 3 -o "$T/bd.vtu" --boundary "$T/bd_faces.$e" --quiet
done
counts=$(python3 - "$T" <<'PY'
import re, struct, sys
t = sys.argv[1]
vtu = open(t + "/bd_faces.vtu").read()
types = re.search(r'Name="types"[^>]*>([^<]*)<', vtu).group(1).split()
ntri, nquad = types.count("5"), types.count("9")
npts = int(re.search(r'NumberOfPoints="(\d+)"', vtu).group(1))
stl = open(t + "/bd_faces.stl", "rb").read()
nstl = struct.unpack("<I", stl[80:84])[0]
off = open(t + "/bd_faces.off").read().split("\n")
nv, nf = map(int, off[1].split()[:2])
sizes = sorted(int(l.split()[0]) for l in off[2 + nv:2 + nv + nf])
ply = open(t + "/bd_faces.ply", "rb").read()
head = ply[:ply.index(b"end_header")].decode()
pv = int(re.search(r"element vertex (\d+)", head).group(1))
pf = int(re.search(r"element face (\d+)", head).group(1))
print("ok" if (nstl == ntri + 2 * nquad and len(stl) == 84 + 50 * nstl and nv == npts
               and sizes.count(3) == ntri and sizes.count(4) == nquad and pv == npts
               and pf == ntri + nquad and ntri + nquad > 0)
      else "bad vtu %d+%d/%d stl %d off %d/%d ply %d/%d" % (ntri, nquad, npts, nstl, nv, nf, pv, pf))
PY
)
[ "$counts" = ok ] && ok "--boundary .stl/.off/.ply: the .vtu's faces and nodes" || bad "--boundary counts: $counts"
for e in off ply; do
  expect_exit 0 "the .$e boundary meshes again (closed, outward)" "$MIXOCT" -i "$T/bd_faces.$e" -s 3 --quiet
  "$MIXOCT" check "$T/bd.vtu" --surface "$T/bd_faces.$e" --json --quiet >"$T/bdc.json" 2>"$T/err"
  python3 -c 'import json,sys; c=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1]); sys.exit(not (c["boundary_max_dist"] < 1e-12 and abs(c["volume_error"]) < 1e-5))' "$T/bdc.json" &&
    ok "the mesh's boundary lies on its .$e boundary, same volume" || bad "check against the .$e boundary: $(tail -c 400 "$T/bdc.json")"
done
expect_exit 2 "--boundary needs the full stage" "$MIXOCT" --demo -s 3 --stage transition --boundary "$T/bd2.vtu"
[ -e "$T/bd2.vtu" ] && bad "a refused --boundary wrote a file" || ok "a refused --boundary writes nothing"
expect_exit 4 "--boundary into a missing directory fails before meshing" "$MIXOCT" --demo -s 3 --boundary "$T/no/dir/b.vtu"
# --fields: the element data written. The same mesh (the checker's hash)
# whatever is chosen; .msh keeps its $ElementData for the fields asked only
# (the tags are its physical groups), .vtu keeps the tags as fields.
for f in all quality none; do
  expect_exit 0 "--fields $f" "$MIXOCT" --demo -s 3 -o "$T/fd_$f.msh" -o "$T/fd_$f.vtu" --fields "$f" --quiet
  for e in msh vtu; do
    "$MIXOCT" check "$T/fd_$f.$e" --json --quiet 2>/dev/null | tail -1 |
      python3 -c 'import json,sys; c=json.load(sys.stdin); print(c["mesh_hash"] if c["defects"] == 0 else "defects")' >"$T/fd_$f.$e.hash"
  done
done
if [ "$(cat "$T"/fd_*.hash | sort -u | wc -l)" = 1 ] && ! grep -q defects "$T"/fd_all.msh.hash; then
  ok "--fields: one mesh in every file, no defect"
else
  bad "--fields changed the mesh: $(cat "$T"/fd_*.hash | tr '\n' ' ')"
fi
fields_of() { grep -a -A2 '^\$ElementData' "$1" | grep -a '^"' | tr -d '"' | tr '\n' ' '; }
[ "$(fields_of "$T/fd_all.msh")" = "type level jens body " ] && ok "--fields all: .msh type level jens body" || bad "--fields all .msh: $(fields_of "$T/fd_all.msh")"
[ "$(fields_of "$T/fd_quality.msh")" = "jens " ] && ok "--fields quality: .msh jens only" || bad "--fields quality .msh: $(fields_of "$T/fd_quality.msh")"
[ -z "$(fields_of "$T/fd_none.msh")" ] && ok "--fields none: .msh without \$ElementData" || bad "--fields none .msh: $(fields_of "$T/fd_none.msh")"
names=$(grep -ao 'Name="[a-z_]*"' "$T/fd_none.vtu" | sort -u | tr '\n' ' ')
case "$names" in
  *jens*|*level*) bad "--fields none .vtu: $names" ;;
  *body*surface_tag*) ok "--fields none: .vtu keeps body and surface_tag only" ;;
  *) bad "--fields none .vtu lost the tags: $names" ;;
esac
expect_exit 2 "--fields with another word" "$MIXOCT" --demo -s 3 --fields jens
# -l LIST: one rule for every word (src/io/element_list.h). The demo at
# level 3 and its restart file; a list written by numpy.savetxt, with whole
# reals, CR LF, commas or comments must refine what the same integers do;
# any other word is exit 2 naming the file, the line and the word.
"$MIXOCT" --demo -s 3 --restart "$T/d3.oct" --json --quiet >"$T/d3.json"
nel=$(tail -1 "$T/d3.json" | python3 -c 'import json,sys; print(json.load(sys.stdin)["elements"])')
list_run() { # list file, then more arguments: "exit leaves refined_listed" of the re-mesh
  "$MIXOCT" remesh -c "$T/d3.oct" --demo -l "$@" --json 2>"$T/err" | tail -1 | python3 -c '
import json,sys; d=json.load(sys.stdin); print(d["exit_code"], d["leaves"], d.get("refined_listed"))'
}
printf '1\n5\n7\n' >"$T/l_int.txt"
want=$(list_run "$T/l_int.txt")
case $want in "0 "*" 0" | "0 "*" None" | "") bad "-l 1 5 7 refined nothing: $want" ;; *) ok "-l 1 5 7: exit, leaves, listed leaves $want" ;; esac
printf '1.000000000000000000e+00\n5.000000000000000000e+00\n7.000000000000000000e+00\n' >"$T/l_np.txt"
printf '1.000000000000000000e+00,5.000000000000000000e+00,7.000000000000000000e+00\n' >"$T/l_npc.txt"
printf '1.0\n5.\n0.7e+01\n' >"$T/l_real.txt"
printf '# elements to refine\r\n1\r\n5 # five\r\n7\r\n' >"$T/l_crlf.txt"
for f in l_np l_npc l_real l_crlf; do
  same "$(list_run "$T/$f.txt")" "$want" "-l $f.txt refines as the integers 1 5 7 do"
done
same "$("$MIXOCT" -c "$T/d3.oct" --demo -l "$T/l_np.txt" --json 2>/dev/null | tail -1 | python3 -c '
import json,sys; d=json.load(sys.stdin); print(d["exit_code"], d["leaves"], d.get("refined_listed"))')" "$want" \
  "mixoct -c -l (no subcommand): the same list, the same leaves"
printf '12.0\n1.2e+01\n' >"$T/l_12a.txt"
printf '12\n' >"$T/l_12b.txt"
same "$(list_run "$T/l_12a.txt")" "$(list_run "$T/l_12b.txt")" "12.0 and 1.2e+01 are element 12"
list_refused() { # description, list text, line, word, text of the message
  printf -- "$2" >"$T/l_bad.txt"
  expect_exit 2 "-l: $1" "$MIXOCT" remesh -c "$T/d3.oct" --demo -l "$T/l_bad.txt"
  has "$T/err" "l_bad.txt:$3: .*\"$4\" $5" "-l: $1: file, line $3, word $4"
}
list_refused "a word" '1\n5\nabc\n' 3 abc "is not an element index"
list_refused "12.5" '1\r\n12.5\r\n' 2 12.5 "is not a whole number"
list_refused "a negative index" '-1\n' 1 -1 "is negative"
list_refused "out of range" "1\n$nel\n" 2 "$nel" "is out of range: $nel elements"
list_refused "NaN" '# x\n\nnan\n' 3 nan "is not a finite number"
list_refused "semicolons" '1;5;7\n' 1 '1;5;7' "is not an element index"
absent "$T/l_out.vtk" "nothing written after a refused list"
: >"$T/l_empty.txt"
expect_exit 0 "-l: an empty list is read" "$MIXOCT" remesh -c "$T/d3.oct" --demo -l "$T/l_empty.txt"
has "$T/err" "l_empty.txt: .*no element index in the list" "-l: an empty list is a warning"
# SIGTERM while writing: no temporary left
"$MIXOCT" --demo -s 7 -o "$T/sig.vtk" --ascii --quiet 2>/dev/null &
pid=$!
seen=no
for _ in $(seq 1 1000); do
  if ls "$T"/sig.vtk.tmp.* >/dev/null 2>&1; then seen=yes; break; fi
  sleep 0.005
done
kill -TERM "$pid" 2>/dev/null; wait "$pid"; code=$?
if ls "$T"/sig.vtk.tmp.* >/dev/null 2>&1; then bad "SIGTERM left a temporary file"; else ok "SIGTERM during the write (temporary seen: $seen): none left (exit $code)"; fi
[ "$code" -eq 143 ] && ok "SIGTERM: exit 143" || ok "SIGTERM came after the end (exit $code)"

# Threads that sleep at barriers (issue 24): without a policy from the user
# the program sets the passive one (and starts itself again); the user's
# choice is kept; the mesh does not depend on it.
wp() { tail -1 "$1" | python3 -c 'import json,sys; print(json.load(sys.stdin)["wait_policy"])'; }
env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "$MIXOCT" --demo -s 4 -o "$T/wp1.vtu" --json >"$T/wp.json" 2>/dev/null
same "$(wp "$T/wp.json")" "passive (set by mixoct)" "no policy chosen: passive, set by the program"
OMP_WAIT_POLICY=active "$MIXOCT" --demo -s 4 -o "$T/wp2.vtu" --json >"$T/wp.json" 2>/dev/null
same "$(wp "$T/wp.json")" "active" "the user's OMP_WAIT_POLICY is kept"
cmp -s "$T/wp1.vtu" "$T/wp2.vtu" && ok "the same mesh with either policy" || bad "the mesh depends on the wait policy"

# Every phase in the summary (issue 24): the restart file's writing is one,
# reported in the table and in --json when --restart is given.
"$MIXOCT" --demo -s 4 -o "$T/ph.vtu" --restart "$T/ph.oct" >"$T/ph.txt" 2>&1
has "$T/ph.txt" " restart [0-9]" "the summary shows the restart phase"
"$MIXOCT" --demo -s 4 -o "$T/ph2.vtu" --restart "$T/ph2.oct" --json >"$T/ph.json" 2>/dev/null
json_ok "$T/ph.json" "d['phases']['restart'] > 0 and d['phases']['write'] > 0" "--json: restart and write phases"

# Several materials, first part (issue 26): each element carries its
# material (the demo surface is one shell: material 1; at the transition
# stage 0 for the elements outside it), written as a VTU field and as Gmsh
# physical volumes, and the files pass the checker; --p4est takes them but
# not with a restart file (exit 2); restart
# files keep them.
expect_exit 0 "--materials at the full stage" "$MIXOCT" --demo -s 3 --materials -o "$T/matf.msh" --quiet
has "$T/matf.msh" '3 1 "demo"' "the full stage's .msh names material 1 after its input"
expect_exit 0 "check of the full stage's materials" "$MIXOCT" check "$T/matf.msh"
expect_exit 2 "--materials with --p4est and --restart" "$MIXOCT" --demo -s 3 --materials --p4est --restart "$T/matp.oct"
expect_exit 0 "--materials with --restart" "$MIXOCT" --demo -s 3 --materials -o "$T/matr.vtu" --restart "$T/matr.oct" --quiet
expect_exit 0 "--materials re-meshing a restart file" "$MIXOCT" --demo --materials -c "$T/matr.oct" -o "$T/matr2.msh" --quiet
has "$T/matr2.msh" '3 1 "demo"' "the re-mesh from a restart file keeps the material"
expect_exit 0 "--materials --stage transition" "$MIXOCT" --demo -s 3 --materials --stage transition \
  -o "$T/mat.vtu" -o "$T/mat.msh" --quiet
has "$T/mat.vtu" 'Name="material"' "the VTU has the material field"
has "$T/mat.msh" '3 1 "demo"' "the .msh names material 1 after its input"
has "$T/mat.msh" '"outside the inputs"' "the .msh names the elements outside the input"
expect_exit 0 "check of the materials' .msh" "$MIXOCT" check "$T/mat.msh"
expect_exit 0 "check of the materials' .vtu" "$MIXOCT" check "$T/mat.vtu"

# Two materials in one file (tests/make_surfaces.py's shell.off: a sphere of
# radius 1 with one of radius 0.5 inside, given inward): the file has
# shells at two depths, so the materials keep their numbers as names; the
# interface is a physical surface; mixoct check reads the labels back, takes
# the tagged interface faces for interfaces (no defect) and finds the inner
# ball's volume within the staircase's error (10% at -s 4) of 4/3 pi 0.5^3.
python3 "$HERE/make_surfaces.py" "$T" >/dev/null 2>&1
expect_exit 0 "--materials on a hollow ball" "$MIXOCT" -i "$T/shell.off" -s 4 --materials -o "$T/sh.msh" --quiet
# the volume check against the outermost shell's volume (not the hollow
# ball's: at -s 5 its tolerance no longer hides the inner ball's 14%)
expect_exit 0 "--materials on a hollow ball at -s 5" "$MIXOCT" -i "$T/shell.off" -s 5 --materials --quiet
has "$T/sh.msh" '3 2 "material 2"' "the inner ball is material 2"
has "$T/sh.msh" '"interface material 1 | material 2"' "the interface is a physical surface"
"$MIXOCT" check "$T/sh.msh" --json >"$T/sh.json" 2>/dev/null
json_ok "$T/sh.json" "d['defects'] == 0 and [m['label'] for m in d['materials']] == [1, 2] and d['interface_faces'] == d['tagged_interface'] > 0 and abs(d['materials'][1]['volume'] - 4.1887902 / 8) < 0.1 * 4.1887902 / 8" "check: two materials, the interface tagged, the inner volume"
# with the surface: each material against the region of shell.off its
# elements lie in (1: between the spheres, 2: the inner ball), within the
# volume tolerance; a tolerance of 1e-6 makes both volumes defects
"$MIXOCT" check "$T/sh.msh" --surface "$T/shell.off" --json >"$T/shs.json" 2>/dev/null
json_ok "$T/shs.json" "d['defects'] == 0 and [m['region'] for m in d['materials']] == [1, 2] and d['materials_volume_off'] == 0 and abs(d['volume_error']) < 0.05" "check --surface: each material in its region, volumes within the tolerance"
"$MIXOCT" check "$T/sh.msh" --surface "$T/shell.off" --volume-tol 1e-6 --json >"$T/shs.json" 2>/dev/null
json_ok "$T/shs.json" "d['materials_volume_off'] == 2" "check --surface --volume-tol 1e-6: both material volumes off"

# Materials numbered and named by the user (--material ID[:NAME] after
# -i): make_surfaces.py's sphere numbered 5 and named grey, as the Gmsh
# physical volume and the VTU field, which mixoct check reads back; a file
# whose shells nest at two depths (shell.off) and bad specs are refused
# (exit 2).
"$MIXOCT" -i "$T/shell.off" --material 5:grey -s 4 --materials -o "$T/num.msh" -o "$T/num.mesh" -o "$T/num.vtu" --quiet 2>/dev/null
[ $? -eq 2 ] && ok "--material on a file with shells at two depths: exit 2" || bad "--material on nested shells of one file"
"$MIXOCT" -i "$T/sphere.off" --material 5:grey -s 4 --materials -o "$T/num.msh" -o "$T/num.mesh" -o "$T/num.vtu" --quiet
has "$T/num.msh" '3 5 "grey"' "the .msh's physical volume 5 named grey"
"$MIXOCT" check "$T/num.vtu" --json >"$T/num.json" 2>/dev/null
json_ok "$T/num.json" "[m['label'] for m in d['materials']] == [5] or d.get('materials') is None" "check of the .vtu: label 5 (or one label: none listed)"
grep -aq 'Name="material"' "$T/num.vtu" && ok "the VTU carries the material field" || bad "no material field"
expect_exit 2 "--material without --materials" "$MIXOCT" -i "$T/sphere.off" --material 5 -s 3
expect_exit 2 "--material before any -i" "$MIXOCT" --material 5 -i "$T/sphere.off" -s 3 --materials
expect_exit 2 "--material 0" "$MIXOCT" -i "$T/sphere.off" --material 0 -s 3 --materials

# A level per input (--level / --inside-level after -i): the sphere at -s 3
# with its surface at level 5 has more leaves than at -s 3 alone and its
# deepest level is 5; misplaced or bad levels are refused (exit 2).
"$MIXOCT" -i "$T/sphere.off" -s 3 --json --quiet >"$T/lv3.json" 2>/dev/null
"$MIXOCT" -i "$T/sphere.off" --level 5 -s 3 --json --quiet >"$T/lv5.json" 2>/dev/null
python3 - "$T/lv3.json" "$T/lv5.json" <<'EOF2' && ok "--level 5 after -i refines that input's surface" || bad "--level after -i"
import json, sys
a, b = (json.loads(open(p).read().strip().splitlines()[-1]) for p in sys.argv[1:])
sys.exit(0 if b['leaves'] > 2 * a['leaves'] and b['max_level'] == 5 and a['max_level'] == 3 else 1)
EOF2
expect_exit 2 "--level before any -i" "$MIXOCT" --level 5 -i "$T/sphere.off" -s 3
expect_exit 2 "--inside-level with a bad level" "$MIXOCT" -i "$T/sphere.off" --inside-level x -s 3

# Size fields (issue 27): a size map file (--size FILE: text x y z h), the
# surface sources (--curvature, --thickness) with a valid --json; bad maps
# and bad values refused (exit 2) naming the file and line.
printf '# a size map\n0.3 0.2 0.1 0.05\n-0.4 0 0 0.4\n' >"$T/map.txt"
"$MIXOCT" -i "$T/sphere.off" -s 2 --size "$T/map.txt" --curvature 20 --thickness 2 --json --quiet \
  >"$T/sz.json" 2>/dev/null
json_ok "$T/sz.json" "d['valid'] and d['size_field']['sources']['map'] == 2 and d['size_field']['sources']['curvature'] > 0 and d['size_field']['sources']['thickness'] > 0" "--size FILE, --curvature, --thickness: valid JSON with the sources"
printf '0.3 0.2 0.1 0.05\n0 0 0 nan\n' >"$T/map_nan.txt"
"$MIXOCT" -i "$T/sphere.off" -s 2 --size "$T/map_nan.txt" >"$T/out" 2>"$T/err"
[ $? -eq 2 ] && has "$T/err" "map_nan.txt:2" "a NaN size in a size map: exit 2 naming the line" || bad "NaN size map"
printf '30 0 0 0.1\n' >"$T/map_far.txt"
expect_exit 2 "a size map's point outside the domain" "$MIXOCT" -i "$T/sphere.off" -s 2 --size "$T/map_far.txt"
expect_exit 2 "--thickness 0.5" "$MIXOCT" -i "$T/sphere.off" -s 2 --thickness 0.5
expect_exit 2 "--curvature 180" "$MIXOCT" -i "$T/sphere.off" -s 2 --curvature 180
expect_exit 2 "--gradation 1" "$MIXOCT" -i "$T/sphere.off" -s 2 --thickness 2 --gradation 1
expect_exit 0 "--thickness alone is a request" "$MIXOCT" -i "$T/sphere.off" --thickness 2 --quiet

# sharp features found and reported (issue 29; kept: features_test.sh): a box of 12
# triangles has 12 ridges and 8 corners; none without the search
printf 'OFF\n8 12 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n3 0 2 1\n3 0 3 2\n3 4 5 6\n3 4 6 7\n3 0 1 5\n3 0 5 4\n3 1 2 6\n3 1 6 5\n3 2 3 7\n3 2 7 6\n3 3 0 4\n3 3 4 7\n' >"$T/box12.off"
"$MIXOCT" -i "$T/box12.off" -s 2 -o "$T/box12.vtu" --json --quiet >"$T/ft.json" 2>/dev/null
json_ok "$T/ft.json" "d['features']['ridges'] == 12 and d['features']['corners'] == 8 and abs(d['features']['length'] - 12) < 1e-9" "features: a box's 12 ridges and 8 corners"
"$MIXOCT" -i "$T/box12.off" -s 2 -o "$T/box12.vtu" --no-features --json --quiet >"$T/ft0.json" 2>/dev/null
json_ok "$T/ft0.json" "'features' not in d" "--no-features: no feature search"
expect_exit 2 "--feature-angle 180" "$MIXOCT" -i "$T/box12.off" -s 2 --feature-angle 180

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
