#!/usr/bin/env bash
# tests/test_alloc_fail.c under AddressSanitizer (LeakSanitizer) and
# UndefinedBehaviorSanitizer: the library's sources (the list meson has for
# libmixoct, read from BUILD_DIR/meson-info) and the test compiled with
# -fsanitize=address,undefined into BUILD_DIR/alloc-fail-asan/ (objects kept
# and rebuilt when a source or a header they use changed), then run: every
# allocation of the five small runs made to fail in turn, no leak, no
# invalid access, no undefined behaviour. (meson's b_sanitize would
# sanitize every target; this builds one program apart, as tools/fuzz.sh
# does for the fuzzers.)
#
#   alloc_fail_test.sh SOURCE_ROOT BUILD_DIR
#
# Environment: ALLOC_FAIL_CC (default cc), ALLOC_FAIL_JOBS (parallel
# compilations, default nproc), MX_ALLOC_FAIL_STRIDE (default 3: every
# 3rd k of the larger runs, see the test) and MX_ALLOC_FAIL_ONLY (passed to
# the test). SKIP (77) when the compiler cannot build with the
# sanitizers, a failure instead when CI is set.
set -u
root=${1:?usage: alloc_fail_test.sh SOURCE_ROOT BUILD_DIR}
builddir=${2:?usage: alloc_fail_test.sh SOURCE_ROOT BUILD_DIR}
cc=${ALLOC_FAIL_CC:-cc}
jobs=${ALLOC_FAIL_JOBS:-$(nproc 2>/dev/null || echo 2)}
out=$builddir/alloc-fail-asan
mkdir -p "$out/obj" || exit 1

missing() {
  if [ -n "${CI:-}" ]; then
    echo "alloc_fail_asan: FAIL: $1 (CI is set)"
    exit 1
  fi
  echo "alloc_fail_asan: SKIP: $1"
  exit 77
}

flags="-std=c17 -g -O1 -fno-omit-frame-pointer -fsanitize=address,undefined
  -fno-sanitize-recover=all -fopenmp -D_GNU_SOURCE -D_FILE_OFFSET_BITS=64
  -march=x86-64-v2 -I$root/src -I$root/include"

printf 'int main(void) { return 0; }\n' >"$out/probe.c"
# shellcheck disable=SC2086
$cc $flags "$out/probe.c" -o "$out/probe" >"$out/probe.log" 2>&1 ||
  { cat "$out/probe.log"; missing "$cc cannot build with -fsanitize=address,undefined"; }

# The library's sources, as meson lists them.
srcs=$(python3 - "$builddir/meson-info/intro-targets.json" <<'PY'
import json, sys
for t in json.load(open(sys.argv[1])):
    if t["name"] == "mixoct" and t["type"] in ("shared library", "static library"):
        for s in t["target_sources"]:
            for f in s.get("sources", []):
                print(f)
        break
PY
)
[ -n "$srcs" ] || { echo "alloc_fail_asan: FAIL: no library sources in $builddir/meson-info"; exit 1; }

stamp="$($cc --version 2>/dev/null | head -1) | $flags"
if [ "$(cat "$out/flags" 2>/dev/null)" != "$stamp" ]; then
  rm -f "$out"/obj/*
  printf '%s\n' "$stamp" >"$out/flags"
fi

# compile_obj, obj_path, up_to_date (shared with tools/fuzz.sh)
. "$root/tools/obj_build.sh"
OBJ_ROOT=$root OBJ_DIR=$out OBJ_CC=$cc OBJ_FLAGS=$flags
export OBJ_ROOT OBJ_DIR OBJ_CC OBJ_FLAGS

t0=$(date +%s)
printf '%s\n' $srcs | xargs -P "$jobs" -I{} bash -c 'compile_obj "$1"' _ {} ||
  { echo "alloc_fail_asan: FAIL: the library did not compile"; exit 1; }
objs=$(for s in $srcs; do obj_path "$s"; echo; done)
bin=$out/test_alloc_fail
if ! up_to_date "$bin" "$bin.d" || [ -n "$(find $objs -newer "$bin" 2>/dev/null | head -1)" ]; then
  # shellcheck disable=SC2086
  $cc $flags -MMD -MF "$bin.d" -I"$root/tests" "$root/tests/test_alloc_fail.c" $objs -lm -lz -llz4 -llzma \
    -o "$bin" || { echo "alloc_fail_asan: FAIL: the test did not link"; exit 1; }
fi
t1=$(date +%s)
echo "alloc_fail_asan: built in $((t1 - t0)) s"

# libgomp's threads sleep while they wait (as the programs set it): a
# spinning team on a shared machine makes each run seconds long.
OMP_WAIT_POLICY=passive MX_ALLOC_FAIL_STRIDE=${MX_ALLOC_FAIL_STRIDE:-3} \
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:exitcode=23 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  "$bin"
status=$?
echo "alloc_fail_asan: ran in $(($(date +%s) - t1)) s, status $status"
[ $status -eq 0 ] && echo "1 passed, 0 failed" || echo "0 passed, 1 failed"
exit $status
