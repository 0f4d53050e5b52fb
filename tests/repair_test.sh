#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# The repair rounds and the contract of exit 5, end to end (issue 23, item 5):
#  - the triple torus of CGAL's data (data/meshes/3torus.off, from Debian's
#    libcgal-demo: /usr/share/doc/libcgal-dev/data.tar.gz, extracted here,
#    never copied into the repository) at -s 6: its repair leaves 2, 30, 10,
#    2, 0 defects; the rule that judged a round against the best one stopped
#    it at 10 (exit 5). Now exit 0, 4 rounds, `mixoct check --surface`
#    finds no defect, 1 and 2 threads write the same bytes. SKIP of this part
#    without the archive (unless CI is set: then a failure);
#  - every exit-5 message names the input, or "the inputs a, b": invalid
#    elements left (make_surfaces.py's sphere with a hole, --repair-input,
#    -s 6: a repair that gets worse each round and stops), the same with a
#    cube inside it as a second input, the volume rule (a cube at -s 1).
# The rule itself on these runs' counts: tests/test_remesh.c
# (test_repair_rule); the distributed path: tests/mpi_test.sh. A few seconds.
MIXOCT=${1:?usage: repair_test.sh path/to/mixoct}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$HERE/lib.sh"
field() { # json file, key
  python3 -c 'import json,sys
j=json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
for k in sys.argv[2].split("."): j=j[k]
print(j)' "$1" "$2"
}

# ---- the triple torus -------------------------------------------------------
CGAL_DATA=${CGAL_DATA:-/usr/share/doc/libcgal-dev/data.tar.gz}
if [ -r "$CGAL_DATA" ] && tar -xzf "$CGAL_DATA" -C "$T" data/meshes/3torus.off 2>/dev/null; then
  torus="$T/data/meshes/3torus.off"
  for t in 1 2; do
    "$MIXOCT" -i "$torus" -s 6 --threads "$t" -o "$T/torus$t.vtu" --json --quiet \
      >"$T/torus$t.json" 2>"$T/err"
    rc=$?
    if [ "$rc" -eq 0 ]; then
      ok "3torus.off -s 6, $t thread(s): exit 0"
    else
      bad "3torus.off -s 6, $t thread(s): exit $rc (5: the repair stopped)"; cat "$T/err"
    fi
  done
  # the rounds the old rule did not allow (it stopped after 2)
  same "$(field "$T/torus2.json" repair_rounds) $(field "$T/torus2.json" invalid)" "4 0" \
    "3torus.off -s 6: 4 repair rounds, no invalid element"
  if cmp -s "$T/torus1.vtu" "$T/torus2.vtu"; then
    ok "3torus.off -s 6: the same bytes for 1 and 2 threads"
  else
    bad "3torus.off -s 6: 1 and 2 threads write different files"
  fi
  expect_exit 0 "3torus.off -s 6: mixoct check --surface finds no defect" \
    "$MIXOCT" check "$T/torus2.vtu" --surface "$torus" --quiet
else
  if [ -n "${CI:-}" ]; then
    bad "$CGAL_DATA not found (Debian: apt-get install libcgal-demo)"
  else
    echo "skipped: the triple torus ($CGAL_DATA not found; Debian: libcgal-demo)"
  fi
fi

# ---- exit-5 messages name the input -----------------------------------------
if python3 "$HERE/make_surfaces.py" "$T/gen" >/dev/null 2>"$T/err"; then
  hole="$T/gen/sphere_hole.off"
  expect_exit 5 "sphere_hole.off --repair-input -s 6: invalid elements left" \
    "$MIXOCT" -i "$hole" --repair-input -s 6 --quiet
  has "$T/err" "error: $hole: [0-9]* element(s) with J_ENS < 1e-6 remain after" \
    "invalid elements left: the message names the input"
  # a second input, a cube inside the first (a hole; the same root grid):
  # "the inputs a, b"
  python3 - "$T/inner.off" <<'EOS'
import sys
V = [(-0.2 + x, -0.2 + y, -0.2 + z) for z in (0, 0.4) for y in (0, 0.4) for x in (0, 0.4)]
F = []
for a, b, c, d in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)):
    F += [(a, b, c), (a, c, d)]
with open(sys.argv[1], "w") as f:
    f.write("OFF\n8 12 0\n")
    f.writelines("%g %g %g\n" % v for v in V)
    f.writelines("3 %d %d %d\n" % t for t in F)
EOS
  expect_exit 5 "two inputs, --repair-input -s 6: invalid elements left" \
    "$MIXOCT" -i "$hole" -i "$T/inner.off" --repair-input -s 6 --quiet
  has "$T/err" "error: the inputs $hole, $T/inner.off: [0-9]* element(s) with J_ENS" \
    "two inputs: the message names both"
  # (without its features: kept, they make the cube exact even at -s 1)
  expect_exit 5 "cube.off -s 1 --no-features: the volume rule" "$MIXOCT" -i "$T/gen/cube.off" -s 1 --no-features --quiet
  has "$T/err" "error: $T/gen/cube.off: the mesh holds" "the volume rule: the message names the input"
else
  bad "make_surfaces.py"; cat "$T/err"
fi

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
