#!/usr/bin/env bash
# The generated tables are the generator's output (issue 25, item 7): the
# transition patterns (src/patterns/table.c, about 45 s on 2 cores) and the
# surface patterns (src/patterns/surface_table.c) are generated again by
# tools/patterngen and compared byte for byte with the committed files, so a
# table edited by hand, or a generator changed without regenerating, fails.
PATTERNGEN=${1:?usage: patterngen_test.sh path/to/patterngen path/to/src/patterns}
PATTERNS=${2:?usage: patterngen_test.sh path/to/patterngen path/to/src/patterns}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
for t in "table.c" "surface_table.c --surface"; do
  set -- $t
  if ! "$PATTERNGEN" "$T/$1" "${@:2}" 2>"$T/err"; then
    echo "FAIL patterngen $t: $(tail -3 "$T/err")"; fails=$((fails + 1)); continue
  fi
  if cmp -s "$T/$1" "$PATTERNS/$1"; then
    echo "ok   $1: regenerated, the same bytes"
  else
    echo "FAIL $1: the committed file is not the generator's output"
    diff "$PATTERNS/$1" "$T/$1" | head -20
    fails=$((fails + 1))
  fi
done
echo "$fails failure(s)"
[ "$fails" -eq 0 ]
