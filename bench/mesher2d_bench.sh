#!/usr/bin/env bash
# The 2D mesher's targets of issue 13 in one run:
#
#   bench/mesher2d_bench.sh MESHER2D [POLY] [LEVELS]
#
# 1. The letter A (POLY, default ../shared/data/polylines/a.poly) meshed with
#    uniform levels (-a) and surface levels (-s) of LEVELS (default
#    "8 10 12"), one run each: nodes, cells, wall seconds and peak RSS from
#    `mesher2d --json`, beside the published 2D program's figures of
#    REFERENCE.md (measured on the machine the reference was made on), and
#    the ratio of the two times.
# 2. Gmsh 2D (Debian's gmsh) on the same polygon, written as a .geo (points,
#    lines, one curve loop per polyline, the outer one with the others as
#    holes), meshed with -2 as triangles and as quad-dominant
#    (Mesh.RecombineAll), with a mesh size chosen so that Gmsh gives about
#    as many vertices as mesher2d with the requests of GMSH_RUNS (runs
#    separated by ';', default "-a 9 -s 11;-a 12": about 90 k and 4 M
#    vertices on the A): vertices, 2D elements, wall, peak RSS, and
#    validity by `mixoct check` (the mixoct beside MESHER2D) for both, side
#    by side. A Gmsh run longer than GMSH_TIMEOUT seconds (default 900) is
#    stopped and reported as such. GMSH_RUNS=none skips this part.
# Timings are single runs (REPEAT=N for the median of N). Last line: one
# JSON object with every row.
set -eu
m2d=${1:?usage: mesher2d_bench.sh MESHER2D [POLY] [LEVELS]}
here=$(cd "$(dirname "$0")" && pwd)
poly=${2:-$here/../../shared/data/polylines/a.poly}
levels=${3:-8 10 12}
gruns=${GMSH_RUNS:--a 9 -s 11;-a 12}
gtimeout=${GMSH_TIMEOUT:-900}
mixoct=$(dirname "$(readlink -f "$m2d")")/mixoct
repeat=${REPEAT:-1}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
rows=""

# one timed command, REPEAT times: prints "wall peak_kb" (medians)
timed() {
  local out=$1
  shift
  : >"$tmp/times"
  for _ in $(seq "$repeat"); do
    /usr/bin/time -f "%e %M" -o "$tmp/t1" "$@" >"$out" 2>"$tmp/err" || {
      if grep -q "Command terminated by signal 15\|exited with non-zero status 124" "$tmp/t1"; then
        echo "timeout 0" # stopped by `timeout`
        return 0
      fi
      echo "failed: $*" >&2
      tail -3 "$tmp/err" >&2
      return 1
    }
    cat "$tmp/t1" >>"$tmp/times"
  done
  python3 -c '
import statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
print(statistics.median(float(r[0]) for r in rows), statistics.median(int(r[1]) for r in rows))' "$tmp/times"
}

# the published 2D program (REFERENCE.md, "2D: letter A"): nodes cells wall peak
ref() {
  case "$1" in
    a8) echo "16537 16078 0.10 23" ;; a10) echo "255776 253937 1.92 286" ;;
    a12) echo "4058300 4050952 35.7 4333" ;; s8) echo "4607 5703 0.04 10" ;;
    s10) echo "20227 26168 0.19 29" ;; s12) echo "88102 114086 1.46 109" ;;
    *) echo "" ;;
  esac
}

printf '%-10s %10s %10s %9s %9s | %10s %10s %9s %9s %8s\n' run nodes cells wall_s peak_mb \
  ref_nodes ref_cells ref_s ref_mb speedup
for mode in a s; do
  for L in $levels; do
    read -r wall peak < <(timed "$tmp/out.json" "$m2d" -p "$poly" "-$mode" "$L" --json \
      -O "$tmp/m.vtu")
    row=$(python3 -c '
import json, sys
d = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
ref = sys.argv[5].split()
r = {"run": sys.argv[2], "nodes": d["nodes"], "cells": d["elements"],
     "wall_s": float(sys.argv[3]), "peak_mb": int(sys.argv[4]) / 1024.0,
     "valid": d.get("invalid", 0) == 0}
if ref:
    r.update({"ref_nodes": int(ref[0]), "ref_cells": int(ref[1]), "ref_s": float(ref[2]),
              "ref_mb": float(ref[3]), "speedup": float(ref[2]) / max(float(sys.argv[3]), 1e-9)})
print(json.dumps(r))' "$tmp/out.json" "-$mode $L" "$wall" "$peak" "$(ref "$mode$L")")
    python3 -c '
import json, sys
r = json.loads(sys.argv[1])
line = "%-10s %10d %10d %9.3f %9.1f" % (r["run"], r["nodes"], r["cells"], r["wall_s"], r["peak_mb"])
if "ref_nodes" in r:
    line += " | %10d %10d %9.2f %9.0f %7.1fx" % (r["ref_nodes"], r["ref_cells"], r["ref_s"],
                                                r["ref_mb"], r["speedup"])
print(line)' "$row"
    rows="$rows${rows:+,}$row"
    rm -f "$tmp/m.vtu"
  done
done

# The polygon as a Gmsh .geo: loops followed from the segments; the loop of
# largest area is the outer boundary, the others holes.
python3 - "$poly" "$tmp/a.geo" <<'EOF'
import sys
lines = []
for raw in open(sys.argv[1]):
    raw = raw.split("#")[0].strip()
    if raw:
        lines.append(raw.split())
nv = int(lines[0][0]); nattr = int(lines[0][2]); nb = int(lines[0][3])
verts = {}
for r in lines[1:1 + nv]:
    verts[int(r[0])] = (float(r[1]), float(r[2]))
ns = int(lines[1 + nv][0])
segs = [(int(r[1]), int(r[2])) for r in lines[2 + nv:2 + nv + ns]]
nxt = {}
for a, b in segs:
    nxt.setdefault(a, []).append(b)
    nxt.setdefault(b, []).append(a)
seen, loops = set(), []
for a, b in segs:
    if (a, b) in seen or (b, a) in seen:
        continue
    loop, prev, cur = [a], a, b
    seen.add((a, b))
    while cur != a:
        loop.append(cur)
        n = [x for x in nxt[cur] if x != prev and (cur, x) not in seen and (x, cur) not in seen]
        if not n:
            break
        seen.add((cur, n[0]))
        prev, cur = cur, n[0]
    loops.append(loop)
def area(l):
    return 0.5 * sum(verts[l[i]][0] * verts[l[(i + 1) % len(l)]][1] -
                     verts[l[(i + 1) % len(l)]][0] * verts[l[i]][1] for i in range(len(l)))
loops.sort(key=lambda l: -abs(area(l)))
with open(sys.argv[2], "w") as f:
    for k, (x, y) in verts.items():
        f.write("Point(%d) = {%.17g, %.17g, 0, 1};\n" % (k, x, y))
    lid, cl = 1, []
    for i, l in enumerate(loops):
        ids = []
        for j in range(len(l)):
            f.write("Line(%d) = {%d, %d};\n" % (lid, l[j], l[(j + 1) % len(l)]))
            ids.append(lid)
            lid += 1
        f.write("Curve Loop(%d) = {%s};\n" % (i + 1, ", ".join(map(str, ids))))
        cl.append(i + 1)
    f.write("Plane Surface(1) = {%s};\n" % ", ".join(map(str, cl)))
    f.write("Physical Surface(\"domain\") = {1};\n")
total = abs(area(loops[0])) - sum(abs(area(l)) for l in loops[1:])
open(sys.argv[2] + ".area", "w").write("%.17g\n" % total)
EOF
area=$(cat "$tmp/a.geo.area")

# vertices and 2D elements of a Gmsh MSH 4.1 ASCII file
msh_counts() {
  python3 - "$1" <<'EOF'
import sys
f = open(sys.argv[1])
nodes = elems = 0
for line in f:
    if line.startswith("$Nodes"):
        nodes = int(f.readline().split()[1])
    elif line.startswith("$Elements"):
        nblocks = int(f.readline().split()[0])
        for _ in range(nblocks):
            dim, tag, etype, n = map(int, f.readline().split())
            for _ in range(n):
                f.readline()
            if dim == 2:
                elems += n
print(nodes, elems)
EOF
}

# valid: `mixoct check` of the file (conforming, no inverted cell; with the
# polygon: boundary on it, area), "-" when it cannot tell
valid_of() {
  if [ -x "$mixoct" ] && "$mixoct" check "$1" --poly "$poly" >/dev/null 2>&1; then echo yes
  elif [ -x "$mixoct" ]; then echo no
  else echo -; fi
}

printf '\n%-22s %10s %10s %9s %9s %7s\n' "vs gmsh -2" vertices elements wall_s peak_mb valid
IFS=';' read -r -a runs <<<"$gruns"
[ "$gruns" = none ] && runs=() # GMSH_RUNS=none: the first table only
for req in "${runs[@]}"; do
  # shellcheck disable=SC2086
  read -r wall peak < <(timed "$tmp/out.json" "$m2d" -p "$poly" $req --json -O "$tmp/m.msh")
  read -r nodes cells < <(python3 -c '
import json, sys
d = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
print(d["nodes"], d["elements"])' "$tmp/out.json")
  valid=$(valid_of "$tmp/m.msh")
  printf '%-22s %10d %10d %9.3f %9.1f %7s\n' "mesher2d $req" "$nodes" "$cells" "$wall" \
    "$(python3 -c "print($peak/1024)")" "$valid"
  rows="$rows${rows:+,}{\"run\": \"mesher2d $req\", \"nodes\": $nodes, \"cells\": $cells, \"wall_s\": $wall, \"peak_mb\": $(python3 -c "print($peak/1024)"), \"valid\": \"$valid\"}"
  rm -f "$tmp/m.msh"
  # a triangle mesh of size h has about 1.155 area / h^2 vertices
  h=$(python3 -c "import math; print(math.sqrt(1.155 * $area / $nodes))")
  for kind in tri quad; do
    extra=""
    # (Mesh.Algorithm 8, frontal for quads, crashes Gmsh 4.8.4 here: the
    # default algorithm, then recombination, which merges triangle pairs:
    # the same vertices at the same size)
    [ "$kind" = quad ] && extra="-setnumber Mesh.RecombineAll 1"
    # shellcheck disable=SC2086
    read -r gwall gpeak < <(timed "$tmp/g.log" timeout "$gtimeout" gmsh "$tmp/a.geo" -2 \
      -format msh41 -nt 2 -clmin "$h" -clmax "$h" $extra -o "$tmp/g.msh")
    if [ "$gwall" = timeout ]; then
      printf '%-22s %10s %10s %9s %9s %7s\n' "gmsh $kind h=$(printf %.2e "$h")" - - \
        "> $gtimeout" - "stopped"
      rows="$rows,{\"run\": \"gmsh $kind\", \"for\": \"$req\", \"h\": $h, \"stopped_after_s\": $gtimeout}"
      rm -f "$tmp/g.msh"
      continue
    fi
    read -r gn ge < <(msh_counts "$tmp/g.msh")
    gvalid=$(valid_of "$tmp/g.msh")
    printf '%-22s %10d %10d %9.3f %9.1f %7s\n' "gmsh $kind h=$(printf %.2e "$h")" "$gn" "$ge" \
      "$gwall" "$(python3 -c "print($gpeak/1024)")" "$gvalid"
    rows="$rows,{\"run\": \"gmsh $kind\", \"for\": \"$req\", \"h\": $h, \"nodes\": $gn, \"cells\": $ge, \"wall_s\": $gwall, \"peak_mb\": $(python3 -c "print($gpeak/1024)"), \"valid\": \"$gvalid\"}"
    rm -f "$tmp/g.msh"
  done
done
echo "{\"poly\": \"$(basename "$poly")\", \"rows\": [$rows]}"
