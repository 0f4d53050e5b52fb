#!/bin/bash
# Every command of the README's Use section runs as written (issue 30): the
# ```sh blocks of the sections "## Use", "## Re-meshing" and "## 2D...",
# up to the next "## " heading, one command a
# line, run in order from a scratch copy of the layout they assume: the
# source tree's build directory as build/, the shared data as
# ../shared/data. Each must exit 0; a command may use the files an earlier
# one wrote.
#
#   bash tests/readme_use_test.sh SOURCE_ROOT BUILD_DIR
#
# MIXOCT_DATA: the shared data folder (default ../shared/data beside the
# source tree); without it the test SKIPs (exit 77), unless CI is set.
set -u
ROOT=${1:?usage: readme_use_test.sh SOURCE_ROOT BUILD_DIR}
BUILD=$(cd "${2:?usage: readme_use_test.sh SOURCE_ROOT BUILD_DIR}" && pwd)
DATA=${MIXOCT_DATA:-$ROOT/../shared/data}
if [ ! -f "$DATA/surfaces/cortex.off" ]; then
  [ -n "${CI:-}" ] && { echo "FAIL: no shared data at $DATA (CI is set)"; exit 1; }
  echo "SKIP: no shared data at $DATA"
  exit 77
fi
DATA=$(cd "$DATA" && pwd)
T=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_readme.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT
mkdir -p "$T/shared" "$T/src"
ln -s "$DATA" "$T/shared/data"
ln -s "$BUILD" "$T/src/build"
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}

awk '/^## /{use = ($0 == "## Use" || $0 == "## Re-meshing" || $0 ~ /^## 2D/)}
     use && /^```/{inblock = !inblock; next} use && inblock' \
  "$ROOT/README.md" >"$T/commands"
n=$(grep -c . "$T/commands")
if [ "$n" -lt 5 ]; then
  echo "FAIL: only $n commands found in the README's Use section"
  exit 1
fi
pass=0 fail=0
while IFS= read -r cmd; do
  [ -z "$cmd" ] && continue
  (cd "$T/src" && bash -c "$cmd") >"$T/out" 2>"$T/err" </dev/null
  st=$?
  if [ $st -eq 0 ]; then
    pass=$((pass + 1))
    echo "ok   $cmd"
  else
    fail=$((fail + 1))
    echo "FAIL $cmd (exit $st)"
    tail -5 "$T/err"
  fi
done <"$T/commands"
echo "README Use section: $pass commands ran, $fail failed"
[ "$fail" -eq 0 ]
