# Shared by the shell tests (sourced after T, the scratch directory, is set):
# ok / bad count and print results; fails is the number of failures.
fails=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fails=$((fails + 1)); }
expect_exit() { # code, description, command...
  local want=$1 what=$2; shift 2
  "$@" >"$T/out" 2>"$T/err"; local got=$?
  if [ "$got" -eq "$want" ]; then ok "$what (exit $got)"; else bad "$what: exit $got, wanted $want"; cat "$T/err"; fi
}
has() { if grep -q -- "$2" "$1"; then ok "$3"; else bad "$3: '$2' not in $(cat "$1")"; fi; }
# A python3 that can import the given modules (comma-separated, as import
# takes them): $PYTHON first, then the system's, then the one on PATH.
find_python() {
  local py
  for py in ${PYTHON:-} /usr/bin/python3 python3; do
    command -v "$py" >/dev/null 2>&1 || continue
    if "$py" -c "import $1" >/dev/null 2>&1; then
      echo "$py"
      return 0
    fi
  done
  return 1
}
same() { if [ "$1" == "$2" ]; then ok "$3"; else bad "$3: '$1' != '$2'"; fi; }
exists() { if [ -s "$1" ]; then ok "$1 written"; else bad "$1 missing"; fi; }
absent() { if [ ! -e "$1" ]; then ok "$2"; else bad "$2: $1 exists"; fi; }

# A closed cube [-h, h]^3 of 12 outward triangles, as OFF.
cube_off() { # file, half side
  local h=$2
  cat >"$1" <<EOS
OFF
8 12 0
-$h -$h -$h
$h -$h -$h
-$h $h -$h
$h $h -$h
-$h -$h $h
$h -$h $h
-$h $h $h
$h $h $h
3 0 2 1
3 1 2 3
3 4 5 6
3 5 7 6
3 0 1 4
3 1 5 4
3 2 6 3
3 3 6 7
3 0 4 2
3 2 4 6
3 1 3 5
3 3 7 5
EOS
}
