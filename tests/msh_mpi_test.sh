#!/usr/bin/env bash
# The MPI-IO Gmsh writer (src/mpi/write_msh_mpi.c, issue 14): the test
# program tests/test_msh_mpi.c on 1, 2 and 3 ranks (it reads its files back
# and compares them with the serial writer's), then, when Gmsh is
# installed, `gmsh -check` on the file written on 3 ranks: it must read it
# with the node and element counts the program printed.
MPIRUN=${1:?usage: msh_mpi_test.sh MPIRUN path/to/test_msh_mpi}
PROG=${2:?usage: msh_mpi_test.sh MPIRUN path/to/test_msh_mpi}
if ! command -v "$MPIRUN" >/dev/null; then
  echo "SKIP: no mpirun"
  exit 77
fi
PROG=$(readlink -f "$PROG") # the files go to a temporary folder
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cd "$T" || exit 1
status=0
for n in 1 2 3; do
  if ! OMP_NUM_THREADS=1 "$MPIRUN" --oversubscribe --allow-run-as-root -n "$n" "$PROG" \
      >"$T/out$n.txt"; then
    echo "FAIL: $PROG on $n ranks"
    status=1
  fi
  cat "$T/out$n.txt"
done
F=msh_mpi_out/equal_np3.msh
if [ "$status" = 0 ] && command -v gmsh >/dev/null && [ -f "$F" ]; then
  line=$(grep '^equal on 3 ranks, chunk 16777216' "$T/out3.txt")
  nodes=$(sed -n 's/.*: \([0-9]*\) nodes, \([0-9]*\) cells.*/\1/p' <<<"$line")
  cells=$(sed -n 's/.*: \([0-9]*\) nodes, \([0-9]*\) cells.*/\2/p' <<<"$line")
  if ! gmsh -check "$F" >"$T/gmsh.txt" 2>&1; then
    echo "FAIL: gmsh -check $F"
    status=1
  fi
  cat "$T/gmsh.txt"
  grep -q "$nodes nodes" "$T/gmsh.txt" || { echo "FAIL: gmsh: not $nodes nodes"; status=1; }
  grep -q "$cells elements" "$T/gmsh.txt" || { echo "FAIL: gmsh: not $cells elements"; status=1; }
fi
exit $status
