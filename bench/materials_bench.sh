#!/usr/bin/env bash
# Several materials (issue 26), the targets that can be measured today, on
# tests/make_surfaces.py's hollow ball shell.off (a sphere of radius 1 with
# one of radius 0.5 inside: two materials with --materials) against the
# same file without --materials (the inner ball a hole) and the outer
# sphere alone (sphere.off: one material), at each LEVEL:
#   - each material's volume (mixoct check --json of the .msh) against the
#     volume its shells enclose (the tessellations', from make_surfaces.py):
#     the target is 0.5% at -s 6;
#   - the elements across the interface (the target: none) and the worst
#     J_ENS (the target: no lower than the one-material mesh's);
#   - the wall time, median of REPEAT runs, against the hollow ball without
#     materials (5.6% fewer leaves at -s 6) and the outer sphere alone, and
#     per leaf (the target: 1.3x the one-material run with the same leaves).
# Measured 2026-12-05 (2 cores, idle, median of 5): -s 6 materials 0.79 s
# against 0.16 s for the hole (x4.9, x4.6 per leaf; x10.2 on 2026-12-04
# before the untangling's early exit and threads on small colours): the
# cleaving 0.6 s, half of it the band's smoothing; volumes -0.06%/-0.11%,
# 0 across, worst J_ENS 0.205 (the sphere alone 0.205, the hole 0.200);
# -s 5 x4.0, worst 0.214 (hole 0.196). Cortex + tumour -s 7: x2.2, worst
# J_ENS 0.126 as the cortex alone.
# Last line: one JSON object.
#
#   bench/materials_bench.sh MIXOCT [LEVELS] [REPEAT]     (default "5 6", 3)
set -u
BIN=${1:?usage: materials_bench.sh MIXOCT [LEVELS] [REPEAT]}
LEVELS=${2:-5 6}
REPEAT=${3:-3}
HERE=$(cd "$(dirname "$0")" && pwd)
T=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_materials_bench.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT
python3 "$HERE/../tests/make_surfaces.py" "$T" >"$T/volumes.json" || exit 1

run() { # name level args...: appends one JSON line per run to $T/runs
  local name=$1 level=$2
  shift 2
  for ((r = 0; r < REPEAT; r++)); do
    "$BIN" "$@" -s "$level" --json --quiet >"$T/out.json" 2>/dev/null
    python3 - "$name" "$level" "$T/out.json" >>"$T/runs" <<'EOF'
import json, sys
name, level, path = sys.argv[1], int(sys.argv[2]), sys.argv[3]
d = json.loads(open(path).read().strip().splitlines()[-1])
print(json.dumps({"name": name, "level": level, "wall": d["total_s"], "leaves": d["leaves"],
                  "elements": d["elements"], "jens_min": d["jens_min"], "valid": d["valid"],
                  "materials": d.get("materials")}))
EOF
  done
}

for L in $LEVELS; do
  run materials "$L" -i "$T/shell.off" --materials -o "$T/m$L.msh"
  "$BIN" check "$T/m$L.msh" --json >"$T/check$L.json" 2>/dev/null
  run hole "$L" -i "$T/shell.off"
  run sphere "$L" -i "$T/sphere.off"
done

# The cortex with a sphere of radius 12 inside (a "tumour": two materials
# in the brain case) at -s 7, against the cortex alone, when the data is
# there (MIXOCT_DATA or ../shared/data).
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
if [ -f "$DATA/surfaces/cortex.off" ]; then
  python3 - "$T/tumour.off" <<'EOF2'
import math, sys
c, r, n = (140.4, 131.1, 85.0), 12.0, 24
V = [(c[0], c[1], c[2] + r)]
for i in range(1, n):
    th = math.pi * i / n
    for j in range(2 * n):
        ph = math.pi * j / n
        V.append((c[0] + r * math.sin(th) * math.cos(ph), c[1] + r * math.sin(th) * math.sin(ph),
                  c[2] + r * math.cos(th)))
V.append((c[0], c[1], c[2] - r))
m, F = 2 * n, []
for j in range(m):
    F.append((0, 1 + j, 1 + (j + 1) % m))
for i in range(n - 2):
    for j in range(m):
        a, b = 1 + i * m + j, 1 + i * m + (j + 1) % m
        F += [(a, a + m, b + m), (a, b + m, b)]
last, base = len(V) - 1, 1 + (n - 2) * m
for j in range(m):
    F.append((last, base + (j + 1) % m, base + j))
with open(sys.argv[1], "w") as f:
    f.write("OFF\n%d %d 0\n" % (len(V), len(F)))
    f.writelines("%.17g %.17g %.17g\n" % v for v in V)
    f.writelines("3 %d %d %d\n" % t for t in F)
EOF2
  run cortex_tumour 7 -i "$DATA/surfaces/cortex.off" -i "$T/tumour.off" --materials
  run cortex 7 -i "$DATA/surfaces/cortex.off"
fi

python3 - "$T" "$LEVELS" <<'EOF'
import json, math, statistics, sys
T, levels = sys.argv[1], [int(x) for x in sys.argv[2].split()]
vol = json.load(open(T + "/volumes.json"))
# the tessellated shells: the outer sphere's volume (sphere.off, the same
# icosphere) less the hollow ball's gives the inner ball's
inner = vol["sphere"] - vol["shell"]
exact = {1: vol["shell"], 2: inner}
runs = [json.loads(l) for l in open(T + "/runs")]
out = {"bench": "materials", "levels": {}}
for L in levels:
    by = {n: [r for r in runs if r["name"] == n and r["level"] == L] for n in ("materials", "hole", "sphere")}
    med = {n: statistics.median(r["wall"] for r in v) for n, v in by.items() if v}
    m = by["materials"][0]
    c = json.loads(open("%s/check%d.json" % (T, L)).read())
    mats = {x["label"]: x for x in c.get("materials", [])}
    err = {k: (mats[k]["volume"] - exact[k]) / exact[k] for k in exact if k in mats}
    res = {"leaves": {n: v[0]["leaves"] for n, v in by.items()},
           "elements": {n: v[0]["elements"] for n, v in by.items()},
           "wall_median_s": med,
           "materials_over_hole": med["materials"] / med["hole"],
           "per_leaf_over_hole": (med["materials"] / by["materials"][0]["leaves"]) /
                                 (med["hole"] / by["hole"][0]["leaves"]),
           "materials_over_sphere": med["materials"] / med["sphere"],
           "volume_error": err,
           "across_interfaces": (m["materials"] or {}).get("across_interfaces"),
           "jens_min": {n: v[0]["jens_min"] for n, v in by.items()},
           "valid": {n: all(r["valid"] for r in v) for n, v in by.items()},
           "check_defects": c.get("defects")}
    out["levels"][L] = res
    print("-s %d: leaves %s; wall (median of %d) materials %.3f s, hole %.3f s (x%.2f), sphere "
          "%.3f s (x%.2f)" % (L, res["leaves"], len(by["materials"]), med["materials"], med["hole"],
                               res["materials_over_hole"], med["sphere"], res["materials_over_sphere"]))
    print("       per leaf x%.2f the hole's" % res["per_leaf_over_hole"])
    print("       material volumes off the shells' by %s; %s elements across the interface; "
          "worst J_ENS %s; check defects %s"
          % ({k: "%+.2f%%" % (100 * e) for k, e in err.items()}, res["across_interfaces"],
             {k: round(v, 3) for k, v in res["jens_min"].items()}, res["check_defects"]))
ct = [r for r in runs if r["name"] == "cortex_tumour"]
cx = [r for r in runs if r["name"] == "cortex"]
if ct and cx:
    a, b = statistics.median(r["wall"] for r in ct), statistics.median(r["wall"] for r in cx)
    out["cortex_tumour"] = {"leaves": [ct[0]["leaves"], cx[0]["leaves"]], "wall_median_s": [a, b],
                            "over_cortex": a / b, "materials": ct[0]["materials"],
                            "jens_min": [ct[0]["jens_min"], cx[0]["jens_min"]],
                            "valid": all(r["valid"] for r in ct)}
    print("cortex + tumour -s 7: %d leaves, %.3f s against %.3f s for the cortex alone (%d leaves; "
          "x%.2f); %s; worst J_ENS %.3f (cortex alone %.3f)"
          % (ct[0]["leaves"], a, b, cx[0]["leaves"], a / b, ct[0]["materials"], ct[0]["jens_min"],
             cx[0]["jens_min"]))
print(json.dumps(out))
EOF
