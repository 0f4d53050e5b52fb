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
same() { if [ "$1" == "$2" ]; then ok "$3"; else bad "$3: '$1' != '$2'"; fi; }
exists() { if [ -s "$1" ]; then ok "$1 written"; else bad "$1 missing"; fi; }
absent() { if [ ! -e "$1" ]; then ok "$2"; else bad "$2: $1 exists"; fi; }
