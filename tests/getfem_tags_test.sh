#!/bin/bash
# GetFEM loads the boundary tags of mixoct's .getfem files as regions and
# solves with them (issue 11): a Laplace patch test with Dirichlet and
# Neumann conditions on the tags of a spherical shell, of two bodies and of
# the cortex. The checks are in tests/getfem_tags_test.py. Then
# tests/getfem_msh_test.py: the .getfem file, not the .msh, is what a GetFEM
# user loads (GetFEM's Gmsh importer twists pyramids).
#
#   bash tests/getfem_tags_test.sh path/to/mixoct
#
# Needs a python3 with numpy and getfem (Debian: python3-numpy
# python3-getfem; PYTHON=path is tried first, then /usr/bin/python3, then
# python3 on PATH); without one it prints SKIP and exits 77 (meson's
# "skipped"), unless the environment variable CI is set, where that is a
# failure. MIXOCT_DATA: the shared data folder (surfaces/cortex.off),
# by default ../shared/data beside the source tree.
set -u

MIXOCT=${1:?usage: getfem_tags_test.sh path/to/mixoct}
HERE=$(cd "$(dirname "$0")" && pwd)
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}   # GetFEM and mixoct share the cores
export PYTHONDONTWRITEBYTECODE=1                    # no __pycache__ in the tree

[ -x "$MIXOCT" ] || { echo "FAIL: $MIXOCT not built"; exit 1; }

. "$HERE/lib.sh"
PY=$(find_python "numpy, getfem") || PY=""
if [ -z "$PY" ]; then
  if [ -n "${CI:-}" ]; then
    echo "FAIL: no python3 with numpy and getfem (CI is set: the GetFEM test must run)"
    exit 1
  fi
  echo "SKIP: no python3 with numpy and getfem (apt-get install --no-install-recommends python3-numpy python3-getfem)"
  exit 77
fi

TMP=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_getfem_tags.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
echo "getfem: $("$PY" -c 'import getfem, os; print(os.path.dirname(getfem.__file__))') ($PY)"
"$PY" "$HERE/getfem_tags_test.py" "$MIXOCT" "$TMP" "$DATA" || exit 1
# which file a GetFEM user loads: .getfem, not .msh (issue 30)
"$PY" "$HERE/getfem_msh_test.py" "$MIXOCT" "$TMP" 2>&1 | grep -v "^Level 2 Warning"
exit "${PIPESTATUS[0]}"
