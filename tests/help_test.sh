#!/bin/bash
# --help is complete and true (issue 30): for the mesher and `mixoct check`,
# the option table the parser goes by (`--list-options`: the parser refuses
# every other option) against the options --help documents, both ways, and
# every option of the table accepted by the parser (never "unknown
# option"); for `patterns`, `mesher2d` and `mesher_roi`, which have no
# table, every option their --help names is accepted and every option
# literal of their parser's source file is named by their --help.
#
#   bash tests/help_test.sh path/to/mixoct SOURCE_ROOT
set -u
MIXOCT=${1:?usage: help_test.sh path/to/mixoct SOURCE_ROOT}
ROOT=${2:?usage: help_test.sh path/to/mixoct SOURCE_ROOT}
T=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_help.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT
pass=0 fail=0
ok() { pass=$((pass + 1)); echo "ok   $1"; }
bad() { fail=$((fail + 1)); echo "FAIL $1"; }

# The option words of a help text: long options anywhere, short ones where
# a line starts with them ("  -s, --surface-level", "  -u NAME").
options_of() {
  { grep -o -- '--[a-z][a-z0-9-]*' "$1"; grep -oE '^ +-[a-zA-Z]([ ,]|$)' "$1" | tr -d ' ,'; } |
    grep -v -- '^--$' | sort -u
}
# Each word of $2 (a file, one a line) passed to "$@" alone: not unknown.
accepted() {
  local list=$1 what=$2
  shift 2
  local refused=""
  while IFS= read -r o; do
    [ -z "$o" ] && continue
    case "$o" in --p4est|--p4est-compare) continue ;; esac  # starts MPI in MPI builds
    timeout 20 "$@" "$o" </dev/null >"$T/o" 2>"$T/e"
    grep -qi "unknown option" "$T/e" && refused="$refused $o"
  done <"$list"
  [ -z "$refused" ] && ok "$what: every option is accepted" || bad "$what: refused as unknown:$refused"
}
same_sets() { # what, table file, help file
  local missing extra
  missing=$(comm -23 "$2" "$3" | tr '\n' ' ')
  extra=$(comm -13 "$2" "$3" | tr '\n' ' ')
  [ -z "$missing" ] && ok "$1: --help documents every option of the table" ||
    bad "$1: not in --help: $missing"
  [ -z "$extra" ] && ok "$1: --help names no option the parser lacks" ||
    bad "$1: in --help but not in the table: $extra"
}

# the mesher: the text up to "Subcommands:", its table
"$MIXOCT" --help >"$T/help" || bad "mixoct --help exits non-zero"
sed '/^Subcommands:/,$d' "$T/help" >"$T/help_main"
options_of "$T/help_main" | grep -v -- '--output=x' >"$T/h_main"
"$MIXOCT" --list-options | tr ' ' '\n' | grep . | sort -u >"$T/t_main"
[ "$(wc -l <"$T/t_main")" -gt 40 ] && ok "mixoct --list-options lists the options" || bad "mixoct --list-options: $(wc -l <"$T/t_main") options"
same_sets "mixoct" "$T/t_main" "$T/h_main"
accepted "$T/t_main" "mixoct" "$MIXOCT"
"$MIXOCT" --no-such-option 2>"$T/e" >/dev/null
[ $? -eq 2 ] && grep -q "unknown option" "$T/e" && ok "mixoct: an unknown option is exit 2, named" || bad "mixoct --no-such-option: $(cat "$T/e")"
"$MIXOCT" remesh --help >"$T/help_remesh" && cmp -s "$T/help" "$T/help_remesh" &&
  ok "mixoct remesh --help is the mesher's" || bad "mixoct remesh --help differs"

# check: its own usage and table; the mesher's Subcommands section names
# only check options of that table
"$MIXOCT" check --help >"$T/help_check" || bad "mixoct check --help exits non-zero"
options_of "$T/help_check" >"$T/h_check"
"$MIXOCT" check --list-options | sort -u >"$T/t_check"
same_sets "mixoct check" "$T/t_check" "$T/h_check"
accepted "$T/t_check" "mixoct check" "$MIXOCT" check
sed -n '/^Subcommands:/,/^Exit codes:/p' "$T/help" | sed -n '/check MESH/,/patterns/p' >"$T/help_sub"
extra=$(options_of "$T/help_sub" | comm -23 - "$T/t_check" | tr '\n' ' ')
[ -z "$extra" ] && ok "mixoct --help's check entry names check's options only" || bad "mixoct --help's check entry: not check options: $extra"
grep -q "5 defects" "$T/help_sub" && ok "mixoct --help: check's defects are exit 5" || bad "mixoct --help: check's exit code"

# patterns, mesher2d, mesher_roi: help against the parser's source
check_front() { # what, help file, source file, command...
  local what=$1 help=$2 src=$3
  shift 3
  options_of "$help" >"$T/h_front"
  grep -oE '"--?[a-zA-Z][a-zA-Z0-9-]*"' "$src" | tr -d '"' | sort -u >"$T/s_front"
  local extra
  extra=$(comm -23 "$T/s_front" "$T/h_front" | tr '\n' ' ')
  [ -z "$extra" ] && ok "$what: --help names every option of its parser" || bad "$what: parsed but not in --help: $extra"
  accepted "$T/h_front" "$what" "$@"
}
"$MIXOCT" patterns --help >"$T/help_patterns" 2>&1 && ok "mixoct patterns --help" || bad "mixoct patterns --help: $(head -2 "$T/help_patterns")"
check_front "mixoct patterns" "$T/help_patterns" "$ROOT/src/cli/patterns_cmd.c" "$MIXOCT" patterns
ln -s "$(cd "$(dirname "$MIXOCT")" && pwd)/$(basename "$MIXOCT")" "$T/mesher2d"
ln -s "$(cd "$(dirname "$MIXOCT")" && pwd)/$(basename "$MIXOCT")" "$T/mesher_roi"
"$T/mesher2d" --help >"$T/help_2d" || bad "mesher2d --help exits non-zero"
check_front "mesher2d" "$T/help_2d" "$ROOT/src/cli/mesher2d.c" "$T/mesher2d"
"$T/mesher_roi" --help >"$T/help_roi" 2>&1 || bad "mesher_roi --help exits non-zero"
check_front "mesher_roi" "$T/help_roi" "$ROOT/src/cli/mesher_roi.c" "$T/mesher_roi"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
