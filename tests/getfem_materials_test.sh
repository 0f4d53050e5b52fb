#!/bin/bash
# A real solver on two materials (issue 26 item 7): GetFEM solves
# -div(k grad u) = 1 on mixoct's --materials meshes of two concentric
# spheres (k = 1 inside, 10 in the shell, u = 0 outside) at -a 3, 4, 5,
# k taken from each element's material region, and the error against the
# radial solution must fall as P1 elements promise (L2 rate >= 1.5, H1 >=
# 0.7), below bounds from h at the finest level, with each material's
# volume within what its faces allow. The checks are in
# tests/getfem_materials_test.py; bench/getfem_materials_bench.sh is the
# long version.
#
#   bash tests/getfem_materials_test.sh path/to/mixoct
#
# Needs a python3 with numpy, scipy and getfem (Debian: python3-getfem,
# which brings python3-numpy and python3-scipy; PYTHON=path is tried
# first, then /usr/bin/python3, then python3 on PATH); without one it
# prints SKIP and exits 77 (meson's "skipped"), unless the environment
# variable CI is set, where that is a failure.
set -u

MIXOCT=${1:?usage: getfem_materials_test.sh path/to/mixoct}
HERE=$(cd "$(dirname "$0")" && pwd)
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}   # GetFEM and mixoct share the cores
export PYTHONDONTWRITEBYTECODE=1                    # no __pycache__ in the tree

[ -x "$MIXOCT" ] || { echo "FAIL: $MIXOCT not built"; exit 1; }

. "$HERE/lib.sh"
PY=$(find_python "numpy, scipy.sparse, getfem") || PY=""
if [ -z "$PY" ]; then
  if [ -n "${CI:-}" ]; then
    echo "FAIL: no python3 with numpy, scipy and getfem (CI is set: the GetFEM test must run)"
    exit 1
  fi
  echo "SKIP: no python3 with numpy, scipy and getfem (apt-get install --no-install-recommends python3-getfem)"
  exit 77
fi

TMP=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_getfem_materials.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
"$PY" "$HERE/getfem_materials_test.py" "$MIXOCT" "$TMP"
