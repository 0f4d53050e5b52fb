#!/usr/bin/env bash
# The adaptive Poisson example (examples/adaptive_poisson.py) refined two
# ways on the same problem (issue 27's target: the same error in fewer
# elements with a size map than with marking a fixed fraction):
#   mark     Doerfler marking (theta 0.7), the marked leaves split once
#   sizemap  a size per element from the estimate (set_size_elements or
#            set_size_points at the centroids), the octree refined to it
# For every round of each sizemap run, the elements the marking run needed
# for the same relative H1 error (log-log interpolation between its rounds)
# and the ratio sizemap / mark (below 1: the size map wins), and the
# rounds (solves) each needed.
#
#   PATH=/usr/bin:$PATH bench/adaptive_sizemap_bench.sh BUILD_DIR [MARK_ROUNDS]
build=${1:?usage: adaptive_sizemap_bench.sh BUILD_DIR [MARK_ROUNDS]}
rounds=${2:-8}
src=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT
run() { # NAME ARGS...
  local name=$1
  shift
  PYTHONPATH="$build/python" OMP_WAIT_POLICY=passive /usr/bin/python3 \
    "$src/examples/adaptive_poisson.py" -s 4 --json "$@" >"$tmp/$name.out" 2>&1 ||
    { echo "$name: failed"; cat "$tmp/$name.out"; exit 1; }
}
run mark --rounds "$rounds"
run elem15 --refine sizemap --reduction 1.5 --rounds 3
run elem3 --refine sizemap --reduction 3 --rounds 4
run cen15 --refine sizemap --reduction 1.5 --at centroids --rounds 4
run cen3 --refine sizemap --reduction 3 --at centroids --rounds 4
/usr/bin/python3 - "$tmp" <<'PY'
import json, math, sys
d = sys.argv[1]
def rows(n):
    return [json.loads(l) for l in open("%s/%s.out" % (d, n)) if l.startswith("{")]
mark = rows("mark")
print("mark (Doerfler 0.7):", ", ".join("%d:%.4f" % (r["elements"], r["rel_h1"]) for r in mark))
def mark_elements(e):
    """Elements marking needed for the relative H1 error e: the first pair of
    rounds around it (log-log), None beyond its last round."""
    for a, b in zip(mark, mark[1:]):
        if a["rel_h1"] >= e >= b["rel_h1"] and a["rel_h1"] > b["rel_h1"]:
            f = math.log(a["rel_h1"] / e) / math.log(a["rel_h1"] / b["rel_h1"])
            return a["elements"] * (b["elements"] / a["elements"]) ** f, b["round"]
    return None, None
print("%-28s %5s %9s %8s %12s %7s %12s" % ("sizemap run", "round", "elements", "rel H1",
                                          "mark needs", "ratio", "mark rounds"))
for name, what in (("elem15", "elements, reduction 1.5"), ("elem3", "elements, reduction 3"),
                   ("cen15", "centroids, reduction 1.5"), ("cen3", "centroids, reduction 3")):
    for r in rows(name)[1:]:
        m, mr = mark_elements(r["rel_h1"])
        print("%-28s %5d %9d %8.4f %12s %7s %12s" % (
            what, r["round"], r["elements"], r["rel_h1"],
            "%.0f" % m if m else "-", "%.3f" % (r["elements"] / m) if m else "-",
            mr if mr is not None else "-"))
PY
