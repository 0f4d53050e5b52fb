#!/usr/bin/env bash
# Several materials in the 2D mesher (issue 26, item 6): `mesher2d
# --materials` against the same input meshed as today (the nested loops as
# holes) and against its outer loops alone with the inner loops as a drawing
# at the same level (-w: about the same leaves, no cleave), at each LEVEL
# (-s), on:
#   - square_with_hole.off of the shared data (a quadrilateral in the unit
#     square: two materials),
#   - the letter A (a.poly: its hole becomes a material),
#   - three concentric circles of 400, 300 and 200 segments (written here:
#     three materials).
# Per run: cells, the worst scaled Jacobian (the quality mesher2d reports),
# wall seconds (median of REPEAT runs), and with --materials each material's
# area error against its region's and the cleave's own seconds.
# Last line: one JSON object with every row.
#
#   bench/materials2d_bench.sh MESHER2D [LEVELS] [REPEAT]   (default "6 9 12", 3)
set -u
BIN=${1:?usage: materials2d_bench.sh MESHER2D [LEVELS] [REPEAT]}
BIN=$(readlink -f "$BIN")
LEVELS=${2:-6 9 12}
REPEAT=${3:-3}
HERE=$(cd "$(dirname "$0")" && pwd)
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
T=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_materials2d_bench.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT
ln -s "$BIN" "$T/mesher2d" # mixoct runs as mesher2d by its name

# the inputs: the whole file, and its outer loops and inner loops apart
python3 - "$T" "$DATA" <<'EOF'
import math, sys
T, D = sys.argv[1], sys.argv[2]
def poly(path, loops):
    vs = [p for L in loops for p in L]
    with open(path, "w") as f:
        f.write("%d 2 0 0\n" % len(vs))
        f.writelines("%d %.17g %.17g\n" % (i + 1, p[0], p[1]) for i, p in enumerate(vs))
        f.write("%d 0\n" % len(vs))
        k, b = 1, 1
        for L in loops:
            for i in range(len(L)):
                f.write("%d %d %d\n" % (k, b + i, b + (i + 1) % len(L)))
                k += 1
            b += len(L)
        f.write("0\n")
def circle(r, n, ph):
    return [(r * math.cos(ph + 2 * math.pi * i / n), r * math.sin(ph + 2 * math.pi * i / n))
            for i in range(n)]
w = open(D + "/polylines/square_with_hole.off").read().split()
nv = int(w[1])
xy = [(float(w[4 + 3 * i]), float(w[5 + 3 * i])) for i in range(nv)]
sq = [xy[i] for i in (0, 1, 2, 3)]
inner = [xy[i] for i in (7, 6, 5, 4)]
poly(T + "/square_outer.poly", [sq])
poly(T + "/square_inner.poly", [inner])
c = [circle(1, 400, 0), circle(0.6, 300, 0.1), circle(0.3, 200, 0.2)]
poly(T + "/circles.poly", c)
poly(T + "/circles_outer.poly", c[:1])
poly(T + "/circles_inner.poly", c[1:])
EOF

run() { # name kind level args...: one JSON line per run into $T/runs
  local name=$1 kind=$2 level=$3
  shift 3
  for ((r = 0; r < REPEAT; r++)); do
    "$T/mesher2d" "$@" -s "$level" --json --quiet >"$T/out.json" 2>/dev/null
    python3 - "$name" "$kind" "$level" "$T/out.json" >>"$T/runs" <<'EOF'
import json, sys
name, kind, level, path = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
d = json.loads(open(path).read().strip().splitlines()[-1])
m = d.get("materials") or {}
print(json.dumps({"input": name, "kind": kind, "level": level, "wall": d["total_s"],
                  "valid": d["valid"], "leaves": d.get("leaves"), "cells": d.get("elements"),
                  "sj_min": d.get("sj_min"), "cleave_s": m.get("seconds"),
                  "area_error": [x.get("area_error") for x in m.get("list", [])]}))
EOF
  done
}

for L in $LEVELS; do
  run square materials "$L" -p "$DATA/polylines/square_with_hole.off" --materials
  run square hole "$L" -p "$DATA/polylines/square_with_hole.off"
  run square drawing "$L" -p "$T/square_outer.poly" -w "$T/square_inner.poly" "$L"
  run letterA materials "$L" -p "$DATA/polylines/a.poly" --materials
  run letterA hole "$L" -p "$DATA/polylines/a.poly"
  run circles materials "$L" -p "$T/circles.poly" --materials
  run circles hole "$L" -p "$T/circles.poly"
  run circles drawing "$L" -p "$T/circles_outer.poly" -w "$T/circles_inner.poly" "$L"
done

python3 - "$T/runs" <<'EOF'
import json, statistics, sys
runs = [json.loads(l) for l in open(sys.argv[1])]
rows, keys = [], []
for r in runs:
    k = (r["input"], r["level"])
    if k not in keys:
        keys.append(k)
print("%-8s %3s  %-9s %8s %8s %7s %9s %9s  %s" % ("input", "-s", "run", "leaves", "cells",
                                                    "sj_min", "wall_s", "x_hole", "area errors"))
for name, L in keys:
    by = {}
    for kind in ("materials", "hole", "drawing"):
        v = [r for r in runs if (r["input"], r["level"], r["kind"]) == (name, L, kind)]
        if v:
            by[kind] = dict(v[0], wall=statistics.median(x["wall"] for x in v),
                            valid=all(x["valid"] for x in v))
    for kind, r in by.items():
        ratio = r["wall"] / by["hole"]["wall"] if "hole" in by and by["hole"]["wall"] else None
        r["x_hole"] = ratio
        print("%-8s %3d  %-9s %8s %8s %7.3f %9.4f %9s  %s%s" % (
            name, L, kind, r["leaves"], r["cells"], r["sj_min"] or 0, r["wall"],
            "%.2f" % ratio if ratio else "-",
            " ".join("%.1e" % e for e in r["area_error"] if e is not None),
            "" if r["valid"] else "  NOT VALID"))
        rows.append({k: r[k] for k in ("input", "level", "kind", "leaves", "cells", "sj_min",
                                       "wall", "x_hole", "cleave_s", "area_error", "valid")})
print(json.dumps({"bench": "materials2d", "rows": rows}))
EOF
