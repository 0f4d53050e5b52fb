#!/usr/bin/env bash
# Sharp features (issue 29) on the OpenSCAD corpus (tools/openscad_corpus.sh)
# and the shapes of tests/make_feature_shapes.py: every file meshed at
# LEVEL (default 5) with the features (the default) and with --no-features,
# alternated, each result checked with `mixoct check --surface --json`.
#
#   bench/features_bench.sh MIXOCT CORPUS_DIR [LEVEL]
#
# One line per file: exit codes and classes (valid: exit 0 and no defect;
# refused: exit 2 or 5 with a message), the ridge and corner distances over
# the diagonal, the volume errors, the seconds (mesh only), with and
# without features. Then the totals: runs valid or cleanly refused, the
# closed parts (volume measured) whose feature distance is at most 1e-6 of
# the diagonal, the median |volume error| of each, and the time ratio
# (sum over the runs valid both ways). Figures, not assertions.
set -u
MIXOCT=$1
DIR=$2
LEVEL=${3:-5}
PY=/usr/bin/python3
HERE=$(cd "$(dirname "$0")" && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$PY" "$HERE/../tests/make_feature_shapes.py" "$T/shapes" >/dev/null
"$PY" "$HERE/../tests/make_surfaces.py" "$T/shapes" >/dev/null

run() { # FILE TAG ARGS...: "exit class ridge corner volume seconds"
  local f=$1 tag=$2
  shift 2
  local out="$T/$tag.vtu"
  local t0 t1
  t0=$(date +%s.%N)
  timeout 300 "$MIXOCT" -i "$f" -s "$LEVEL" "$@" -o "$out" --quiet 2>"$T/err"
  local e=$?
  t1=$(date +%s.%N)
  local sec
  sec=$("$PY" -c "print('%.3f' % ($t1 - $t0))")
  if [ $e -ne 0 ]; then
    local cls=other
    { [ $e -eq 2 ] || [ $e -eq 5 ]; } && [ -s "$T/err" ] && cls=refused
    echo "$e $cls nan nan nan $sec"
    return
  fi
  "$MIXOCT" check "$out" --surface "$f" --json --quiet 2>/dev/null | "$PY" -c "
import json, sys
d = json.load(sys.stdin)
f = d.get('features') or {}
g = lambda x: 'nan' if x is None else '%.3g' % x
print(0, 'valid' if d['defects'] == 0 else 'broken', g(f.get('ridge_dist')), g(f.get('corner_dist')),
      g(d.get('volume_error')), '$sec')"
  rm -f "$out"
}

printf '%-36s %-34s %-34s\n' "file" "features: exit class ridge corner vol s" "--no-features: the same"
: >"$T/rows"
for f in "$T"/shapes/{tet,wedge,lbracket,cylinder,step,cube}.off "$DIR"/*.stl; do
  [ -f "$f" ] || continue
  a=$(run "$f" a)
  b=$(run "$f" b --no-features)
  printf '%-36s %-34s %-34s\n' "$(basename "$f")" "$a" "$b"
  echo "$(basename "$f") $a $b" >>"$T/rows"
done
"$PY" - "$T/rows" <<'EOF'
import math, statistics, sys
rows = [l.split() for l in open(sys.argv[1])]
def f(x):
    return float(x)
ok = lambda c: c in ("valid", "refused")
n = len(rows)
print()
print("runs: %d files at this level" % n)
for side, o in (("features", 1), ("--no-features", 7)):
    good = sum(ok(r[o + 1]) for r in rows)
    closed = [r for r in rows if r[o + 1] == "valid" and r[o + 4] != "nan"]
    exact = [r for r in closed if (r[o + 2] == "nan" or f(r[o + 2]) <= 1e-6) and
             (r[o + 3] == "nan" or f(r[o + 3]) <= 1e-6)]
    vols = [abs(f(r[o + 4])) for r in closed]
    print("%-14s valid or cleanly refused %d of %d; closed parts %d, feature distance <= 1e-6 "
          "of the diagonal on %d; median |volume error| %s" %
          (side, good, n, len(closed), len(exact),
           "%.2e" % statistics.median(vols) if vols else "-"))
both = [r for r in rows if r[2] == "valid" and r[8] == "valid"]
ta = sum(f(r[6]) for r in both)
tb = sum(f(r[12]) for r in both)
if tb > 0:
    print("time, runs valid both ways (%d): %.2f s with features, %.2f s without: ratio %.2f" %
          (len(both), ta, tb, ta / tb))
EOF
