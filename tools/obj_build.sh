# Incremental compilation of the library's sources one object at a time,
# for the programs built apart with sanitizers (tools/fuzz.sh,
# tests/alloc_fail_test.sh). Sourced; the caller sets and exports
#   OBJ_ROOT   the source tree (sources are given relative to it, or absolute)
#   OBJ_DIR    where the objects go (OBJ_DIR/obj/NAME.o, NAME.d beside them)
#   OBJ_CC     the compiler
#   OBJ_FLAGS  its flags
# and runs compile_obj in parallel (xargs ... bash -c 'compile_obj "$1"').
# An object is rebuilt when a file its dependency list names is newer; a
# failed compilation leaves its messages in NAME.o.err (and no object).

# up_to_date OUT DEPFILE: OUT exists and no file DEPFILE lists is newer.
up_to_date() {
  [ -f "$1" ] && [ -f "$2" ] || return 1
  local f
  for f in $(sed -e 's/^[^:]*://' -e 's/\\$//' "$2"); do
    [ "$f" -nt "$1" ] && return 1
  done
  return 0
}

# obj_path SRC: the object of SRC (its path below src/, '/' as '_').
obj_path() {
  local s=${1#"$OBJ_ROOT"/}
  s=${s#src/}
  printf '%s/obj/%s.o' "$OBJ_DIR" "$(printf '%s' "$s" | tr / _)"
}

# compile_obj SRC: its object, unless up to date.
compile_obj() {
  local src=$1 o
  o=$(obj_path "$src")
  case $src in /*) ;; *) src=$OBJ_ROOT/$src ;; esac
  up_to_date "$o" "${o%.o}.d" && return 0
  # shellcheck disable=SC2086
  if $OBJ_CC $OBJ_FLAGS -MMD -MF "${o%.o}.d.tmp" -c "$src" -o "$o.tmp" 2>"$o.err"; then
    mv "$o.tmp" "$o" && mv "${o%.o}.d.tmp" "${o%.o}.d" && rm -f "$o.err"
  else
    cat "$o.err" >&2
    rm -f "$o.tmp" "${o%.o}.d.tmp"
    return 1
  fi
}
export -f up_to_date obj_path compile_obj
