#!/bin/bash
# The installed pkg-config file (issue 30, item 4): a program written
# against include/mixoct.h builds with `pkg-config --static --cflags --libs
# mixoct` (the build tree's copy of the .pc, with -L to the build tree),
# once against the shared library and once against libmixoct.a, and runs.
# hwloc's own .pc named -ludev, which Debian's libhwloc-dev does not bring.
#   bash tests/pkgconfig_test.sh BUILD_DIR SOURCE_DIR
BUILD=${1:?usage: pkgconfig_test.sh BUILD_DIR SOURCE_DIR}
SRC=${2:?usage: pkgconfig_test.sh BUILD_DIR SOURCE_DIR}
pass=0
fail=0
ok() { pass=$((pass + 1)); echo "ok: $*"; }
ko() { fail=$((fail + 1)); echo "FAIL: $*"; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
if ! command -v pkg-config >/dev/null || ! command -v cc >/dev/null; then
  if [ -n "$CI" ]; then echo "FAIL: pkg-config or cc missing"; echo "0 passed, 1 failed"; exit 1; fi
  echo "SKIP: pkg-config or cc missing"; echo "0 passed, 0 failed"; exit 0
fi
export PKG_CONFIG_PATH="$BUILD/meson-private"
flags=$(pkg-config --static --cflags --libs mixoct) && ok "pkg-config --static: $flags" ||
  ko "pkg-config --static --libs mixoct failed"
cat >"$T/p.c" <<'C'
#include <mixoct.h>
int main(void) {
  mx_params p;
  mx_params_default(&p);
  return p.repair_rounds == 10 && p.surface_level == -1 ? 0 : 1;
}
C
# the shared library
if cc "$T/p.c" -I"$SRC/include" -L"$BUILD" $flags -o "$T/shared" 2>"$T/err" &&
  LD_LIBRARY_PATH="$BUILD" "$T/shared"; then
  ok "built and ran against libmixoct.so"
else
  ko "shared: $(cat "$T/err")"
fi
# the static library, system libraries shared
if cc "$T/p.c" -I"$SRC/include" "$BUILD/libmixoct.a" ${flags//-lmixoct/} -o "$T/static" 2>"$T/err" &&
  "$T/static" && ! ldd "$T/static" | grep -q mixoct; then
  ok "built and ran against libmixoct.a"
else
  ko "static: $(cat "$T/err")"
fi
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
