#!/bin/bash
# The Python binding (python/mixoct) and the adaptive example
# (examples/adaptive_poisson.py) against a build:
#
#   bash tests/python_test.sh BUILD_DIR
#
# Uses Debian's /usr/bin/python3 with python3-numpy and python3-getfem;
# without them it prints SKIP and exits 77 (meson's "skipped"), unless CI is
# set, where that is a failure. The package is taken from BUILD_DIR/python
# (where meson copies it), else from the source tree with MIXOCT_LIB pointing
# at BUILD_DIR/libmixoct.so. MIXOCT_DATA (optional): the shared data folder.
set -u

BUILD=${1:?usage: python_test.sh BUILD_DIR}
BUILD=$(cd "$BUILD" && pwd) || exit 1
SRC=$(cd "$(dirname "$0")/.." && pwd)
PY=/usr/bin/python3
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}   # getfem shares the cores
export PYTHONDONTWRITEBYTECODE=1                    # no __pycache__ in the tree

skip() {
  if [ -n "${CI:-}" ]; then
    echo "FAIL: $1 (CI is set: the Python test must run)"
    exit 1
  fi
  echo "SKIP: $1"
  exit 77
}

[ -x "$PY" ] || skip "$PY not found (apt-get install python3)"
"$PY" -c 'import numpy' 2>/dev/null ||
  skip "python3-numpy missing (apt-get install --no-install-recommends python3-numpy)"
"$PY" -c 'import getfem' 2>/dev/null ||
  skip "python3-getfem missing (apt-get install --no-install-recommends python3-getfem)"

if [ -f "$BUILD/python/mixoct/__init__.py" ]; then
  export PYTHONPATH="$BUILD/python${PYTHONPATH:+:$PYTHONPATH}"
else
  export PYTHONPATH="$SRC/python${PYTHONPATH:+:$PYTHONPATH}"
fi
if [ -z "${MIXOCT_LIB:-}" ] && [ ! -e "$BUILD/python/mixoct/libmixoct.so" ]; then
  [ -e "$BUILD/libmixoct.so" ] || { echo "FAIL: $BUILD/libmixoct.so not built"; exit 1; }
  export MIXOCT_LIB="$BUILD/libmixoct.so"
fi
MIXOCT="$BUILD/mixoct"
[ -x "$MIXOCT" ] || { echo "FAIL: $MIXOCT not built"; exit 1; }

TMP=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_py.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
fail=0
pass=0

# ---- 1. the binding --------------------------------------------------------
echo "== binding ($("$PY" -c 'import mixoct, sys; sys.stdout.write(mixoct.load_library()._name)'))"
if "$PY" "$SRC/tests/python_binding_test.py" "$TMP/binding"; then
  pass=$((pass + 1))
else
  echo "FAIL: tests/python_binding_test.py"
  fail=$((fail + 1))
fi

# ---- 2. the adaptive example, short ------------------------------------------
echo "== examples/adaptive_poisson.py --rounds 3 -s 4"
if "$PY" "$SRC/examples/adaptive_poisson.py" --rounds 3 -s 4 --linear-check \
    --verify-orders --check "$TMP/rounds" --json >"$TMP/example.out" 2>&1; then
  cat "$TMP/example.out"
  if "$PY" - "$TMP/example.out" <<'EOF'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
ok = True
def bad(msg):
    global ok
    ok = False
    print("FAIL: " + msg)
if len(rows) != 3:
    bad("3 JSON rounds expected, got %d" % len(rows))
for a, b in zip(rows, rows[1:]):
    if not b["h1"] < a["h1"]:
        bad("H1 error did not fall: round %d %.6g -> round %d %.6g"
            % (a["round"], a["h1"], b["round"], b["h1"]))
    if not b["leaves"] > a["leaves"]:
        bad("round %d did not refine" % b["round"])
for r in rows:
    if r.get("linear_max_err", 1.0) > 1e-9:
        bad("round %d: linear solution not exact (%g): node orders?"
            % (r["round"], r.get("linear_max_err", float("nan"))))
    if any(r.get("bad_jacobian", {"x": 1}).values()):
        bad("round %d: det(J) <= 0 in GetFEM: %s" % (r["round"], r.get("bad_jacobian")))
    if sum(r["by_type"].values()) != r["elements"]:
        bad("round %d: counts by type do not add up" % r["round"])
sys.exit(0 if ok else 1)
EOF
  then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
  fi
else
  cat "$TMP/example.out"
  echo "FAIL: examples/adaptive_poisson.py exited non-zero"
  fail=$((fail + 1))
fi

# ---- 2b. the same refined by a size map from the estimate (issue 27) -----------
echo "== examples/adaptive_poisson.py --rounds 2 -s 4 --refine sizemap --reduction 3"
if "$PY" "$SRC/examples/adaptive_poisson.py" --rounds 2 -s 4 --refine sizemap --reduction 3 \
    --check "$TMP/rounds_sizemap" --json >"$TMP/sizemap.out" 2>&1 &&
  "$PY" - "$TMP/sizemap.out" <<'EOF'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
ok = len(rows) == 2 and rows[1]["h1"] < 0.7 * rows[0]["h1"] and rows[1]["leaves"] > rows[0]["leaves"]
print("sizemap rounds: %s" % [(r["elements"], round(r["rel_h1"], 4)) for r in rows])
sys.exit(0 if ok else 1)
EOF
then
  pass=$((pass + 1))
else
  cat "$TMP/sizemap.out"
  echo "FAIL: the size-map round did not refine or the H1 error did not fall by 30%"
  fail=$((fail + 1))
fi

# ---- 3. every round's mesh passes mixoct check ----------------------------------
n=0
for f in "$TMP"/rounds/round*.vtu "$TMP"/rounds_sizemap/round*.vtu; do
  [ -e "$f" ] || continue
  n=$((n + 1))
  "$MIXOCT" check "$f" >"$TMP/check.out" 2>&1
  rc=$?
  if [ "$rc" -eq 0 ]; then
    echo "ok   mixoct check $(basename "$f")"
    pass=$((pass + 1))
  else
    cat "$TMP/check.out"
    echo "FAIL: mixoct check $(basename "$f") (exit $rc)"
    fail=$((fail + 1))
  fi
done
if [ "$n" -ne 5 ]; then
  echo "FAIL: 5 round meshes expected in the --check DIRs (3 marked, 2 size map), found $n"
  fail=$((fail + 1))
fi

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
