#!/usr/bin/env bash
# The readers under libFuzzer for a few seconds each (tools/fuzz.sh; run it
# longer by hand). $1: the source root. SKIP (77) when clang cannot build a
# fuzzer (Debian: clang libclang-rt-14-dev libomp-dev), a failure instead
# when the environment variable CI is set.
root=${1:?usage: fuzz_test.sh SOURCE_ROOT}
cc=${FUZZ_CC:-clang}

missing() {
  if [ -n "${CI:-}" ]; then
    echo "fuzz: FAIL: $1 (CI is set: install clang, libclang-rt-14-dev and libomp-dev)"
    exit 1
  fi
  echo "fuzz: SKIP: $1"
  exit 77
}

command -v "$cc" >/dev/null 2>&1 || missing "$cc not found"
probe=$(mktemp -d) || exit 1
trap 'rm -rf "$probe"' EXIT
cat >"$probe/p.c" <<'C'
#include <omp.h>
#include <stddef.h>
#include <stdint.h>
int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);
int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) {
  (void)d;
  return (int)n * 0 + omp_get_max_threads() * 0;
}
C
"$cc" -fsanitize=fuzzer,address,undefined -fopenmp "$probe/p.c" \
  -o "$probe/p" >"$probe/log" 2>&1 ||
  { cat "$probe/log"; missing "$cc cannot build a libFuzzer target with -fopenmp"; }

# A fresh corpus (the seeds only) each time; crash inputs are kept.
work=$(mktemp -d "${TMPDIR:-/tmp}/mixoct-fuzz-test.XXXXXX") || exit 1
FUZZ_WORK_DIR=$work bash "$root/tools/fuzz.sh" "${FUZZ_TEST_SECONDS:-3}"
status=$?
if [ $status -eq 0 ]; then
  rm -rf "$work"
  exit 0
fi
echo "fuzz: FAIL (status $status): crash inputs and logs in $work"
exit 1
