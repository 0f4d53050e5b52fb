#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# The files of a run (issue 23): no output replaces an input or another
# output, whatever the spelling (./a, a symbolic or hard link), in the three
# programs (mixoct, mesher_roi, mesher2d); the restart file written may
# replace the one read. Messages: a path of thousands of characters keeps
# the reason, bytes that are not UTF-8 are escaped; readers refuse a Medit
# version that does not exist and a .vtu cut short; --stage octree is not
# reported valid.
MIXOCT=${1:?usage: files_test.sh path/to/mixoct}
MIXOCT=$(cd "$(dirname "$MIXOCT")" && pwd)/$(basename "$MIXOCT")
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"
cd "$T" || exit 1
ln -s "$MIXOCT" mesher_roi
ln -s "$MIXOCT" mesher2d

cube_off cube.off 0.5
cp cube.off in.off
sum_in=$(cksum <in.off)
nothing_new() { # what: no file but the ones listed before
  local now
  now=$(ls | sort | tr '\n' ' ')
  same "$now" "$before" "$1: nothing written"
}
touch out err
before=$(ls | sort | tr '\n' ' ')

# ---- outputs against outputs ----------------------------------------------
for ext in vtk msh; do
  expect_exit 2 "-o a.$ext --restart a.$ext" "$MIXOCT" -i cube.off -s 3 -o a.$ext --restart a.$ext
  has err "a.$ext" "the clash names the file"
  has err "same file" "the clash says why"
  nothing_new "-o a.$ext --restart a.$ext"
done
expect_exit 2 "-o a.vtu --boundary ./a.vtu" "$MIXOCT" -i cube.off -s 3 -o a.vtu --boundary ./a.vtu
has err "a.vtu and ./a.vtu" "both spellings named"
nothing_new "-o a.vtu --boundary ./a.vtu"
expect_exit 2 "-o a.msh -o ./a.msh" "$MIXOCT" -i cube.off -s 3 -o a.msh -o ./a.msh
mkdir sub
expect_exit 2 "-o sub/../a.vtk --restart a.vtk" "$MIXOCT" -i cube.off -s 3 -o sub/../a.vtk --restart a.vtk
rmdir sub
expect_exit 2 "-o p.pvtu -o p_0.vtu (the piece)" "$MIXOCT" -i cube.off -s 3 -o p.pvtu -o p_0.vtu
nothing_new "outputs that clash"

# ---- outputs against inputs -----------------------------------------------
expect_exit 2 "--restart in.off overwrites the input" "$MIXOCT" -i in.off -s 3 -o x.vtk --restart in.off
has err "in.off" "the input is named"
same "$(cksum <in.off)" "$sum_in" "the input is intact"
nothing_new "--restart in.off"
expect_exit 2 "-o in.off: the input, not just the extension" "$MIXOCT" -i in.off -s 3 -o in.off
has err "input" "-o in.off: said to be the input"
expect_exit 2 "--boundary in.off" "$MIXOCT" -i in.off -s 3 -o x.vtu --boundary in.off
has err "input" "--boundary in.off: said to be the input"
ln -s in.off link.vtk
expect_exit 2 "an output that is a symbolic link to the input" "$MIXOCT" -i in.off -s 3 -o link.vtk
rm link.vtk
ln in.off hard.vtk
expect_exit 2 "an output that is a hard link to the input" "$MIXOCT" -i in.off -s 3 -o hard.vtk
rm hard.vtk
printf 'n_regions 1\n0.2 0.2 0.2 0.6 0.6 0.6 4\n' >box.reg
cp box.reg box.copy
before=$(ls | sort | tr '\n' ' ')
expect_exit 2 "--restart over the boxes file" "$MIXOCT" -i cube.off -s 2 -b box.reg --restart box.reg
cmp -s box.reg box.copy && ok "the boxes file is intact" || bad "the boxes file was overwritten"
expect_exit 2 "-r region surface as output" "$MIXOCT" -i cube.off -s 2 -r in.off 3 --restart ./in.off
same "$(cksum <in.off)" "$sum_in" "the region surface is intact"
nothing_new "outputs over inputs"

# the re-meshing loop: the restart file written replaces the one read
expect_exit 0 "a restart file" "$MIXOCT" -i cube.off -s 2 --restart r.oct --quiet
echo 0 >list.txt
expect_exit 0 "remesh --restart over the restart file read" \
  "$MIXOCT" remesh -c r.oct -i cube.off -l list.txt --restart r.oct --quiet
expect_exit 2 "--restart over the element list" \
  "$MIXOCT" remesh -c r.oct -i cube.off -l list.txt --restart list.txt
same "$(cat list.txt)" "0" "the element list is intact"
rm -f r.oct list.txt

# the other fronts
cp in.off roi.vtk
expect_exit 2 "mesher_roi: -u roi -v over an input named roi.vtk" ./mesher_roi -o in.off -s 2 -u roi -v -r roi.vtk 3
cmp -s roi.vtk in.off && ok "mesher_roi: the input is intact" || bad "mesher_roi: input overwritten"
rm roi.vtk
printf 'OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n' >sq.off
expect_exit 2 "mesher2d: two outputs that are one file" ./mesher2d -p sq.off -a 3 -u q -v -O ./q.vtk
expect_exit 2 "mesher2d: the restart file over the domain" ./mesher2d -p sq.off -a 3 -u sq -c sq.off
rm -f sq.off
before=$(ls | sort | tr '\n' ' ')

# ---- messages ---------------------------------------------------------------
long=$(printf 'd%.0s' $(seq 1 3000))
expect_exit 4 "an output in a directory of 3000 characters that does not exist" \
  "$MIXOCT" -i cube.off -s 2 -o "$long/x.vtu"
has err "does not exist" "a long path keeps the reason"
expect_exit 2 "an input of 3000 characters that does not exist" "$MIXOCT" -i "$long.off" -s 2
python3 -c 'import sys; t=open(sys.argv[1],"rb").read().decode(); sys.exit(len(t) < 100 or len(t) > 4000)' err \
  && ok "a long path is cut in the middle, the message kept whole" || bad "long path message: $(wc -c <err) bytes"
printf '\xff\xfeOF\xc3\x28F garbage\n1 2 3\n' >garbage.off
expect_exit 2 "a garbage header" "$MIXOCT" -i garbage.off -s 2
python3 -c 'import sys; open(sys.argv[1],"rb").read().decode("utf-8")' err \
  && ok "the message is valid UTF-8" || bad "the message is not UTF-8: $(od -c err | head -3)"
has err 'xff' "the bad bytes are shown as \\xNN"
printf '\xc3\xa9OFF\n' >utf.off
expect_exit 2 "a UTF-8 header" "$MIXOCT" -i utf.off -s 2
has err $'\xc3\xa9' "valid UTF-8 is shown as it is"

# ---- readers: a version that does not exist, a file cut short ---------------
"$MIXOCT" -i cube.off -s 2 -o m.mesh -o m.vtu --quiet || bad "meshing the cube"
sed 's/^MeshVersionFormatted 2/MeshVersionFormatted 9/' m.mesh >v9.mesh
expect_exit 2 "MeshVersionFormatted 9" "$MIXOCT" check v9.mesh
has err "v9.mesh:1" "the version's line is named"
expect_exit 0 "the same file with version 2" "$MIXOCT" check m.mesh
head -c -20 m.vtu >cut.vtu
expect_exit 2 ".vtu without </VTKFile>" "$MIXOCT" check cut.vtu
has err "cut.vtu" "the cut file is named"
has err "</VTKFile>" "the missing end is said"
expect_exit 0 "the whole .vtu" "$MIXOCT" check m.vtu

# ---- --stage octree: exit 0, not called valid --------------------------------
"$MIXOCT" -i cube.off -s 3 --stage octree --json >out.json 2>err
same "$?" 0 "--stage octree exits 0"
tail -1 out.json | python3 -c 'import json,sys; d=json.load(sys.stdin); sys.exit(d["valid"] is not False)' \
  && ok "--stage octree: \"valid\": false" || bad "--stage octree reported valid"
"$MIXOCT" -i cube.off -s 3 --json >out.json 2>err
tail -1 out.json | python3 -c 'import json,sys; d=json.load(sys.stdin); sys.exit(d["valid"] is not True)' \
  && ok "the full stage: \"valid\": true" || bad "full stage not reported valid"
"$MIXOCT" --help >out 2>&1
has out "stage octree or transition, 0 means" "--help: exit 0 of an intermediate stage explained"
./mesher2d -h >out 2>&1
has out "to 27" "mesher2d -h: levels up to 27, as accepted"
expect_exit 2 "mesher2d -s 28 refused" ./mesher2d -p "$T/cube.off" -s 28
ls | grep -q 'tmp' && bad "temporary file left" || ok "no temporary left"
echo "$fails failure(s)"
[ "$fails" -eq 0 ]
