#!/bin/bash
# Byte-identity check for refactors (issue 25): writes the outputs of a fixed
# set of runs, at 1 and 2 threads, so two builds can be compared file by file.
#   tools/byte_identity.sh run BUILD_DIR OUT_DIR   writes OUT_DIR/t1, OUT_DIR/t2
#   tools/byte_identity.sh cmp DIR_A DIR_B         cmp every file; lists differences
# The set: every 3D format of the cortex at -s 7 (and --stage octree and
# transition), every shared surface at a small level, the restart files (.oct,
# .octb), a re-mesh of the published program's restart file (ours and
# mesher_roi), every 2D polyline in every 2D format, the 2D restart file.
# Data: MIXOCT_DATA or ../shared/data next to the source tree.
set -u
HERE=$(cd "$(dirname "$0")" && pwd)
D=$(cd "${MIXOCT_DATA:-$HERE/../../shared/data}" && pwd)
case "${1:-}" in
run)
  B=$(cd "$2" && pwd); O=$3; fail=0
  for t in 1 2; do
    W=$O/t$t; rm -rf "$W"; mkdir -p "$W"; cd "$W" || exit 1
    export OMP_NUM_THREADS=$t
    # the status of a failed run, its command with the build and data
    # directories named BIN and DATA (two builds compare equal)
    st() { echo "exit $1 : ${*:2}" | sed "s|$B|BIN|g; s|$D|DATA|g" >> status.txt; }
    r() { "$@" --quiet > /dev/null 2>> log.txt || st $? "$@"; }
    S=$D/surfaces
    r $B/mixoct -i $S/cortex.off -s 7 -o c7.vtu -o c7.vtk -o c7.msh -o c7.mesh \
      -o c7.meshb -o c7.getfem -o c7.m3d -o c7.mvm --restart c7.oct --boundary c7b.vtu
    r $B/mixoct -i $S/cortex.off -s 7 --ascii -o c7a.vtk -o c7a.msh --restart c7.octb
    r $B/mixoct -i $S/cortex.off -s 6 --stage octree -o c6o.vtu
    r $B/mixoct -i $S/cortex.off -s 6 --stage transition -o c6t.vtu --restart c6t.oct
    r $B/mixoct -i $S/cortex.off -s 5 -b $S/cortex.reg -o creg.vtu --restart creg.oct
    r $B/mixoct --demo -s 5 -o demo.vtu -o demo.msh
    for f in cyl50.off femur.mdl fertilityRotated.mdl hex.off hollow-coarse.off \
             in_spher.mdl outer_sphere.mdl sein.mdl suture.off; do
      r $B/mixoct -i $S/$f -s 5 -o ${f%.*}.vtu -o ${f%.*}.msh --restart ${f%.*}.oct
    done
    r $B/mixoct -i $S/outer_sphere.mdl -i $S/in_spher.mdl -s 4 -o hollow2.vtu
    r $B/mixoct -i $S/cyl50.off -s 4 -r $S/hex.off 6 -o cylr.vtu
    r $B/mixoct -i $S/femur.mdl -a 3 -s 5 -o fema.m3d --restart fema.oct
    r $B/mixoct remesh -c $D/remesh/c5.oct -i $S/cortex.off -l $D/remesh/list.txt \
      -o rem.vtu -o rem.msh --restart rem.oct
    r $B/mixoct remesh -c c7.oct -i $S/cortex.off -l $D/remesh/list.txt -s 7 \
      -o rem7.vtu --restart rem7.oct
    mkdir -p roi && (cd roi && $B/mesher_roi -o $S/cortex.off -c $D/remesh/c5.oct \
      -l $D/remesh/list.txt -u r -v -g -m > /dev/null 2>&1 || echo "exit $? : roi" >> ../status.txt)
    for p in $D/polylines/*.poly $D/polylines/*.off; do
      n=$(basename ${p%.*})
      "$B/mesher2d" -p "$p" -s 6 -u q_$n -v -x -o -g -m -O q_$n.vtu --quiet > /dev/null 2>> log.txt \
        || echo "exit $? : 2d $n" >> status.txt
    done
    "$B/mesher2d" -p $D/polylines/a.poly -s 6 -a 3 --binary -u qb -v -x --quiet > /dev/null 2>> log.txt \
      || echo "exit $? : 2d binary" >> status.txt
    printf '3\n17\n40\n' > list2.txt
    "$B/mesher2d" -p $D/polylines/a.poly -c qb.oct -l list2.txt -u qr -v -x --quiet > /dev/null 2>> log.txt \
      || echo "exit $? : 2d remesh" >> status.txt
    cd - > /dev/null
  done ;;
cmp)
  A=$2; Bd=$3; n=0; bad=0
  while IFS= read -r f; do
    n=$((n + 1))
    if [ ! -f "$Bd/$f" ]; then echo "missing in $Bd: $f"; bad=$((bad + 1));
    elif ! cmp -s "$A/$f" "$Bd/$f"; then echo "differs: $f"; bad=$((bad + 1)); fi
  done < <(cd "$A" && find . -type f ! -name log.txt | sort)
  m=$(cd "$Bd" && find . -type f ! -name log.txt | wc -l)
  [ "$m" -ne "$n" ] && { echo "file count: $n in $A, $m in $Bd"; bad=$((bad + 1)); }
  echo "$n files compared, $bad differ"
  [ $bad -eq 0 ] ;;
*) echo "usage: $0 run BUILD_DIR OUT_DIR | cmp DIR_A DIR_B" >&2; exit 2 ;;
esac
