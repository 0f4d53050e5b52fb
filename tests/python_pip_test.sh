#!/bin/bash
# The Python way of installing (issue 30, item 1): pyproject.toml builds the
# package with meson-python, `pip install --no-build-isolation --target`
# from a copy of the source tree (git's files, or the tree without build
# directories), then a fresh process imports it from there (MIXOCT_LIB
# unset: the libmixoct.so inside the package) and meshes the demo at level
# 3. Needs python3-pip, python3-mesonpy (and meson, ninja, the compilers):
# SKIP without them unless CI is set. About a minute (it builds the
# library).
set -u
SRC=$(cd "$(dirname "$0")/.." && pwd)
PY=/usr/bin/python3
skip() {
  if [ -n "${CI:-}" ]; then echo "FAIL: $1 (CI is set)"; exit 1; fi
  echo "SKIP: $1"; exit 77
}
[ -x "$PY" ] || skip "$PY missing"
"$PY" -m pip --version >/dev/null 2>&1 || skip "pip missing (apt-get install python3-pip)"
"$PY" -c 'import mesonpy' 2>/dev/null || skip "meson-python missing (apt-get install python3-mesonpy)"
"$PY" -c 'import numpy' 2>/dev/null || skip "numpy missing (apt-get install python3-numpy)"

TMP=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_pip.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
mkdir "$TMP/src" "$TMP/target"
if git -C "$SRC" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  (cd "$SRC" && git ls-files -co --exclude-standard -z | grep -zv '^build' |
     tar --null -cf - -T -) | tar -xf - -C "$TMP/src" || exit 1
else
  (cd "$SRC" && tar --exclude='./build*' -cf - .) | tar -xf - -C "$TMP/src" || exit 1
fi
[ -f "$TMP/src/pyproject.toml" ] || { echo "FAIL: no pyproject.toml copied"; exit 1; }
if ! (cd "$TMP/src" && "$PY" -m pip install --no-build-isolation --no-deps --no-index \
        --disable-pip-version-check --root-user-action=ignore -q --target "$TMP/target" .) \
        >"$TMP/pip.log" 2>&1; then
  tail -40 "$TMP/pip.log"
  echo "FAIL: pip install"
  exit 1
fi
for f in __init__.py _capi.py _mesher.py __init__.pyi py.typed libmixoct.so; do
  [ -f "$TMP/target/mixoct/$f" ] || { echo "FAIL: mixoct/$f not installed"; ls -R "$TMP/target"; exit 1; }
done
cd "$TMP" && env -u MIXOCT_LIB PYTHONPATH="$TMP/target" "$PY" - "$TMP/target" <<'PYEOF'
import os, sys
import mixoct
root = os.path.realpath(sys.argv[1])
assert os.path.realpath(mixoct.__file__).startswith(root), mixoct.__file__
lib = os.path.realpath(mixoct.load_library()._name)
assert lib == os.path.join(root, "mixoct", "libmixoct.so"), lib
m = mixoct.Mesher(surface_level=3)
m.add_demo_surface()
m.mesh()
c = m.counts
assert sum(c.values()) == m.nelements > 0 and m.invalid == 0, c
print("ok: pip-installed mixoct %s from %s meshes the demo: %s" % (mixoct.__version__, lib, c))
PYEOF
