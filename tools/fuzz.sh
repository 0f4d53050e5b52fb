#!/usr/bin/env bash
# Builds and runs the libFuzzer targets of the input readers.
#
#   tools/fuzz.sh [SECONDS_PER_TARGET] [TARGET ...]
#
# Targets (all by default): off mdl stl obj ply reg poly polylines
# (tools/fuzz_readers.c; poly: the 2D readers .poly/.off/.mdl and the domain
# check; polylines: the feature polylines reader and the feature distances),
# mesh_vtk mesh_vtu mesh_msh mesh_mesh mesh_meshb mesh_getfem mesh_m3d
# mesh_mvm (mx_read_mesh of `mixoct check`, the input written under that
# extension; tools/fuzz_readers.c), sizemap_txt sizemap_vtk sizemap_vtu
# sizemap_pos (mx_sizemap_read, the format named by that extension;
# tools/fuzz_readers.c), image_nii image_niigz image_mha image_inr
# image_inrgz (mx_read_label_image_mem on the bytes named .nii, .nii.gz,
# .mha, .inr, .inr.gz; tools/fuzz_readers.c),
# restart (tools/fuzz_restart.c) and list (the element index lists of -l,
# tools/fuzz_list.c). Each runs SECONDS_PER_TARGET seconds
# (default 60) from its seeds tools/fuzz_seeds/TARGET plus a corpus kept
# outside the tree, up to FUZZ_JOBS targets at a time (default: nproc). One
# line per target: executions, time, crashes, and the path of each crash
# input.
# Exit status 0 when no target crashed, leaked, ran out of memory or timed
# out (10 s per input), 1 otherwise, 2 when the build failed.
#
# Environment:
#   FUZZ_CC          the compiler (default clang; needs -fsanitize=fuzzer)
#   FUZZ_BUILD_DIR   objects and fuzzers (default build-fuzz/ in the tree)
#   FUZZ_WORK_DIR    corpora, crash inputs and logs
#                    (default ${TMPDIR:-/tmp}/mixoct-fuzz)
#   FUZZ_JOBS        targets run at once (default nproc)
#   FUZZ_FORK=1      keep fuzzing after a crash (libFuzzer -fork=1
#                    -ignore_crashes=1 ...), to collect several crash inputs
#   FUZZ_ARGS        more libFuzzer arguments, for every target
#
# Reproduce a crash: FUZZ_BUILD_DIR/fuzz_TARGET CRASH_FILE
set -u
export LC_ALL=C

root=$(cd "$(dirname "$0")/.." && pwd)
all_targets="off mdl stl obj ply reg poly polylines mesh_vtk mesh_vtu mesh_msh mesh_mesh mesh_meshb mesh_getfem mesh_m3d mesh_mvm sizemap_txt sizemap_vtk sizemap_vtu sizemap_pos image_nii image_niigz image_mha image_inr image_inrgz restart list"

secs=60
case ${1:-} in
  '' | *[!0-9]*) ;;
  *) secs=$1; shift ;;
esac
targets=${*:-$all_targets}
for t in $targets; do
  case " $all_targets " in
    *" $t "*) ;;
    *) echo "usage: tools/fuzz.sh [SECONDS_PER_TARGET] [TARGET ...]" >&2
       echo "fuzz.sh: unknown target '$t' (known: $all_targets)" >&2
       exit 2 ;;
  esac
done

cc=${FUZZ_CC:-clang}
build=${FUZZ_BUILD_DIR:-$root/build-fuzz}
work=${FUZZ_WORK_DIR:-${TMPDIR:-/tmp}/mixoct-fuzz}
njobs=${FUZZ_JOBS:-$(nproc 2>/dev/null || echo 2)}
mkdir -p "$build/obj" "$work" || exit 2

flags="-std=c17 -g -O1 -fno-omit-frame-pointer -fno-sanitize-recover=all -fopenmp -D_GNU_SOURCE -I$root/src -I$root/include"
obj_flags="$flags -fsanitize=fuzzer-no-link,address,undefined"
bin_flags="$flags -fsanitize=fuzzer,address,undefined"

# ---- build -----------------------------------------------------------------

# Objects built with other flags or another compiler are thrown away.
stamp="$($cc --version 2>/dev/null | head -1) | $obj_flags"
if [ "$(cat "$build/flags" 2>/dev/null)" != "$stamp" ]; then
  rm -f "$build"/obj/* "$build"/fuzz_* "$build"/libmixoct_fuzz.a
  printf '%s\n' "$stamp" >"$build/flags"
fi

# compile_obj, obj_path, up_to_date (shared with tests/alloc_fail_test.sh)
. "$root/tools/obj_build.sh"
OBJ_ROOT=$root OBJ_DIR=$build OBJ_CC=$cc OBJ_FLAGS=$obj_flags
export OBJ_ROOT OBJ_DIR OBJ_CC OBJ_FLAGS
export build cc obj_flags root

# build_lib SOURCES: compiles them and archives the objects in $lib (an
# archive, so each fuzzer links only what it uses). A source that does not
# compile is left out with a warning: the fuzzers that need it fail to link.
lib=$build/libmixoct_fuzz.a
build_lib() {
  printf '%s\n' $1 | xargs -P "$njobs" -I{} bash -c 'compile_obj "$1"' _ {}
  local objs s o rebuild=0 ar=ar
  objs=$(for s in $1; do
    o=$(obj_path "$s")
    if [ -f "$o.err" ]; then
      echo "fuzz.sh: warning: $s did not compile (above): left out" >&2
      rm -f "$o"
    else
      printf '%s\n' "$o"
    fi
  done)
  [ -f "$lib" ] || rebuild=1
  [ "$(cat "$build/objects" 2>/dev/null)" = "$objs" ] || rebuild=1
  for o in $objs; do [ "$o" -nt "$lib" ] && rebuild=1; done
  [ $rebuild = 1 ] || return 0
  command -v ar >/dev/null || ar=llvm-ar
  # shellcheck disable=SC2086
  rm -f "$lib.tmp" && $ar rcs "$lib.tmp" $objs && mv "$lib.tmp" "$lib" || exit 2
  printf '%s\n' "$objs" >"$build/objects"
}

# link_target TARGET: its fuzzer, $build/fuzz_TARGET; errors in $build/fuzz_TARGET.err
# (and on stderr unless link_quiet=1).
link_target() {
  local t=$1 bin=$build/fuzz_$1 src=tools/fuzz_readers.c def
  case $t in
    restart) src=tools/fuzz_restart.c; def= ;;
    list) src=tools/fuzz_list.c; def= ;;
    mesh_*) def="-DFUZZ_FORMAT=mesh -DFUZZ_EXT=${t#mesh_}" ;;
    sizemap_*) def="-DFUZZ_FORMAT=sizemap -DFUZZ_EXT=${t#sizemap_}" ;;
    image_niigz) def="-DFUZZ_FORMAT=image -DFUZZ_EXT=nii.gz" ;;
    image_inrgz) def="-DFUZZ_FORMAT=image -DFUZZ_EXT=inr.gz" ;;
    image_*) def="-DFUZZ_FORMAT=image -DFUZZ_EXT=${t#image_}" ;;
    *) def="-DFUZZ_FORMAT=$t" ;;
  esac
  if up_to_date "$bin" "$bin.d" && [ ! "$lib" -nt "$bin" ]; then return 0; fi
  # shellcheck disable=SC2086
  if $cc $bin_flags $def -MMD -MF "$bin.d.tmp" "$root/$src" "$lib" -lm -lz -llz4 -llzma -o "$bin.tmp" 2>"$bin.err"; then
    mv "$bin.tmp" "$bin" && mv "$bin.d.tmp" "$bin.d" && rm -f "$bin.err"
  else
    [ "${link_quiet:-0}" = 1 ] || cat "$bin.err" >&2
    rm -f "$bin.tmp" "$bin.d.tmp"
    return 1
  fi
}
export -f link_target
export lib bin_flags
link_all() {
  printf '%s\n' $targets | link_quiet=$1 xargs -P "$njobs" -I{} bash -c 'link_target "$1"' _ {}
}

# First the sources of the readers and of their checks; every source but
# the command line (src/cli) when a fuzzer needs more (remembered).
core_srcs=$(cd "$root" && ls src/base/*.c src/soa/*.c src/io/*.c src/geom/*.c \
              src/verify/check.c src/quad/poly.c 2>/dev/null)
all_srcs=$(cd "$root" && ls src/*/*.c | grep -v '^src/cli/')
if [ "$(cat "$build/libset" 2>/dev/null)" != all ]; then
  build_lib "$core_srcs"
  if ! link_all 1; then
    errs=$(for t in $targets; do cat "$build/fuzz_$t.err" 2>/dev/null; done)
    if printf '%s\n' "$errs" | grep -q 'undefined reference'; then
      echo all >"$build/libset"
    else
      printf '%s\n' "$errs" >&2
      echo "fuzz.sh: a fuzzer did not build (see above)" >&2
      exit 2
    fi
  fi
fi
if [ "$(cat "$build/libset" 2>/dev/null)" = all ]; then
  build_lib "$all_srcs"
  if ! link_all 0; then
    echo "fuzz.sh: a fuzzer did not build (see above)" >&2
    exit 2
  fi
fi

# ---- run -------------------------------------------------------------------

# run_target TARGET: fuzzes it, then writes its result line to
# $work/result/TARGET and its status (0 clean, 1 finding) to .status.
run_target() {
  local t=$1 bin=$build/fuzz_$1 corpus=$work/corpus/$1 crashes=$work/crashes/$1
  local log=$work/logs/$1.log rundir=$work/run/$1 extra=""
  mkdir -p "$corpus" "$crashes" "$work/logs" "$work/result" "$rundir"
  case $t in
    restart) extra="-close_fd_mask=2" ;; # its messages; reports still go out
  esac
  if [ "${FUZZ_FORK:-0}" = 1 ]; then
    extra="$extra -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1"
  fi
  local mark=$rundir/start t0 t1 rc tmp
  touch "$mark"
  # the files the fuzzers write each input to (tmpfs when there is one)
  tmp=$(mktemp -d /dev/shm/mixoct-fuzz.XXXXXX 2>/dev/null) ||
    tmp=$(mktemp -d "$rundir/tmp.XXXXXX") || return 1
  t0=$(date +%s)
  # shellcheck disable=SC2086
  (cd "$rundir" && TMPDIR=$tmp timeout -k 30 $((secs + 600)) "$bin" -max_total_time="$secs" \
     -timeout=10 -max_len=8192 -rss_limit_mb=2048 -print_final_stats=1 \
     -artifact_prefix="$crashes/" $extra ${FUZZ_ARGS:-} \
     "$corpus" "$root/tools/fuzz_seeds/$t") >"$log" 2>&1
  rc=$?
  t1=$(date +%s)
  rm -rf "$tmp"
  local runs found n=0 paths="" kind
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  if [ -z "$runs" ]; then
    runs=$(grep -oE '^#[0-9]+' "$log" | tr -d '#' | sort -n | tail -1)
  fi
  found=$(find "$crashes" -maxdepth 1 -type f \
            \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) \
            -newer "$mark" | sort)
  for f in $found; do n=$((n + 1)); paths="$paths $f"; done
  kind=$(grep -m1 -E '^SUMMARY: |^==[0-9]+== ?ERROR: libFuzzer' "$log" | cut -c1-100)
  local status=0 line
  line=$(printf '%-10s runs %10s  time %4s s  crashes %d' "$t" "${runs:-0}" $((t1 - t0)) "$n")
  if [ "$n" -gt 0 ]; then
    status=1
    line="$line ${paths# } ${kind:+($kind)}"
  elif [ "$rc" -ne 0 ]; then
    status=1
    line="$line  exit status $rc, no crash input: see $log ${kind:+($kind)}"
  fi
  printf '%s\n' "$line" >"$work/result/$t"
  echo "$status" >"$work/result/$t.status"
}

echo "fuzz.sh: $secs s per target, $njobs at a time: $targets" >&2
echo "fuzz.sh: corpora, crash inputs and logs in $work" >&2
for t in $targets; do
  rm -f "$work/result/$t" "$work/result/$t.status"
  while [ "$(jobs -rp | wc -l)" -ge "$njobs" ]; do wait -n; done
  run_target "$t" &
done
wait

fail=0
for t in $targets; do
  if [ -f "$work/result/$t" ]; then
    cat "$work/result/$t"
    [ "$(cat "$work/result/$t.status")" = 0 ] || fail=1
  else
    echo "$t: no result"
    fail=1
  fi
done
exit $fail
