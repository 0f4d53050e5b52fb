#!/usr/bin/env bash
HERE=$(cd "$(dirname "$0")" && pwd) # before any cd: tests/lib.sh
# The 2D mesher's size field (issue 27; mesher2d --size EXPR|F1..F5,
# --size-min, --size-max, the -f curves as its sources), judged from the
# written files (python3 reads the ASCII legacy VTK) and `mixoct check`:
#  - the unit square with h = 0.02 + 0.2 x: every cell's quadrant (side
#    1.01 / 2^level: the root is 1.01 x the longest extent, qtree.c) is
#    not larger than the field's least value over the cell (h is linear:
#    the least of its corners), within the control space's tolerance (its
#    K_L leaves hold the value at their centre, within the metric
#    non-conformity 0.5 of the samples: a factor 1.31); no cell smaller
#    than needed (its parent, inside the cell grown by one side, was too
#    large); the mesh valid (`mixoct check --poly`, exit 0); the cell field
#    target_size, one value per cell within the field's range [0.02, 0.22];
#    the same bytes for 1 and 2 threads and for both balance methods;
#  - F1..F5 accepted by name; a bad expression exit 2 with its column and a
#    caret; sizes that are not positive exit 2; --size-min above --size-max
#    exit 2; a field finer than memory exit 3 naming its least size;
#  - -f without a field: the counts of today (recorded at 771aa04, before
#    the 2D field) and no target_size; with --size-min alone (no field) the
#    same bytes; with a field, the cells the circle crosses (corners on both
#    sides) of level RL or finer, every cell within its tolerance of the
#    field min(h, s + distance to the circle), s the side of level RL.
# The argument is the mixoct program (the script links mesher2d to it).
BIN=${1:?usage: size2d_test.sh path/to/mixoct}
BIN=$(readlink -f "$BIN")
DATA=${MIXOCT_DATA:-$HERE/../../shared/data}
[ -d "$DATA/polylines" ] || DATA=$HERE/../../shared/data
PL=$DATA/polylines
SQ=$PL/unit_square.poly
[ -f "$SQ" ] || { echo "SKIP: $SQ not found (set MIXOCT_DATA)"; exit 77; }
command -v python3 >/dev/null || { echo "SKIP: python3 not found"; exit 77; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
ln -s "$BIN" "$T/mesher2d"
M2=$T/mesher2d
cd "$T" || exit 1
. "$HERE/lib.sh"

# judge.py VTK FIELD [circle cx cy r RL]: the cells against the field
# (FIELD a python expression of x and y, here linear in x and y, or with a
# circle the least of it and s + |distance to the circle|: its least over a
# cell is at a corner or, for the distance, where the circle crosses the
# cell: 0 there). Prints the figures; exit 1 when a rule is broken.
cat >judge.py <<'EOS'
import math, sys
path, expr = sys.argv[1], sys.argv[2]
circle = list(map(float, sys.argv[4:8])) if len(sys.argv) > 3 and sys.argv[3] == 'circle' else None
ROOT, TOL = 1.01, 1.31
lines = open(path).read().split('\n')
def at(word):
    return next(k for k, l in enumerate(lines) if l.startswith(word))
i = at('POINTS'); n = int(lines[i].split()[1])
pts = [tuple(map(float, lines[i + 1 + k].split()[:2])) for k in range(n)]
c = at('CELLS'); m = int(lines[c].split()[1])
cells = [list(map(int, lines[c + 1 + k].split()))[1:] for k in range(m)]
def field(name):
    k = next((k for k, l in enumerate(lines) if l.startswith('SCALARS %s ' % name)), None)
    return None if k is None else [float(lines[k + 2 + j]) for j in range(m)]
level = field('level')
target = field('target_size')
def h(x, y):
    v = eval(expr, {'math': math, 'x': x, 'y': y, 'abs': abs, 'min': min})
    if circle:
        v = min(v, ROOT / 2 ** circle[3] + abs(math.hypot(x - circle[0], y - circle[1]) - circle[2]))
    return v
def crossed(cell):
    if not circle: return False
    s = [math.hypot(pts[p][0] - circle[0], pts[p][1] - circle[1]) - circle[2] for p in cell]
    return min(s) <= 0 <= max(s)
big = small = coarse = 0
worst = 0.0
for k, cell in enumerate(cells):
    side = ROOT / 2 ** level[k]
    least = min(h(*pts[p]) for p in cell)
    if crossed(cell):
        least = min(least, ROOT / 2 ** circle[3])
        coarse += level[k] < circle[3]
    worst = max(worst, side / least)
    big += side > TOL * least
    # the parent: a box of side 2 side within the cell's box grown by side
    xs = [pts[p][0] for p in cell]; ys = [pts[p][1] for p in cell]
    grown = min(h(x, y) for x in (min(xs) - side, max(xs) + side)
                for y in (min(ys) - side, max(ys) + side))
    if not circle:
        small += 2 * side <= grown / TOL
bad = []
if big: bad.append('%d cells larger than the field' % big)
if small: bad.append('%d cells smaller than needed' % small)
if coarse: bad.append('%d cells crossed by the circle coarser than level %d' % (coarse, circle[3]))
if target is None:
    bad.append('no target_size')
else:
    lo, hi = float(sys.argv[-2]), float(sys.argv[-1])
    out = sum(1 for v in target if not lo - 1e-12 <= v <= hi + 1e-12)
    if out: bad.append('%d target_size values out of [%g, %g]' % (out, lo, hi))
print('; '.join(bad) if bad else '%d cells, side / least size at most %.3f' % (m, worst))
sys.exit(1 if bad else 0)
EOS

json_get() { # file, python expression of d
  tail -n 1 "$1" | python3 -c "import json,sys; d=json.load(sys.stdin); print($2)"
}

# ---- usage and bad fields -------------------------------------------------------
expect_exit 0 "--help" "$M2" --help
has "$T/out" "--size EXPR" "the help lists --size"
has "$T/out" "--size-min H, --size-max H" "the help lists --size-min and --size-max"
expect_exit 2 "--size without its expression" "$M2" -p "$SQ" --size
expect_exit 2 "a bad expression" "$M2" -p "$SQ" --size "0.02 + 0.2*"
has "$T/err" "column 12" "a bad expression: its column"
has "$T/err" "^ *\^$" "a bad expression: a caret under the column"
expect_exit 2 "an unknown name" "$M2" -p "$SQ" --size "F7(x)"
expect_exit 2 "sizes that are not positive" "$M2" -p "$SQ" --size "x - 0.5"
has "$T/err" "finite and positive" "sizes that are not positive: says so"
expect_exit 2 "--size-min above --size-max" "$M2" -p "$SQ" --size "x + 1" --size-min 0.2 --size-max 0.1
has "$T/err" "bad bounds" "--size-min above --size-max: says so"
expect_exit 2 "a negative --size-min" "$M2" -p "$SQ" --size 1 --size-min -1
expect_exit 2 "--size-max that is not a number" "$M2" -p "$SQ" --size-max big
expect_exit 2 "--size-min alone is no request" "$M2" -p "$SQ" --size-min 0.1
expect_exit 3 "a field finer than memory" "$M2" -p "$SQ" --size 1e-7 -O tiny.vtu
has "$T/err" "asks for about .* quadrants (its least size 1e-07" "finer than memory: the least size named"
absent tiny.vtu "finer than memory: nothing written"
"$M2" -p "$SQ" --size 1e-7 --json >tiny.json 2>/dev/null
same "$(json_get tiny.json 'd["exit_code"], d["valid"]')" "3 False" "finer than memory: --json says exit 3"
for f in F1 F3 F4 F5; do expect_exit 0 "--size $f" "$M2" -p "$SQ" --size $f; done
# F2 is 1e-10 on its line, which meets the square at (0.5, 1): bounded, it meshes
expect_exit 3 "--size F2: 1e-10 on its line" "$M2" -p "$SQ" --size F2
expect_exit 0 "--size F2 --size-min 0.02" "$M2" -p "$SQ" --size F2 --size-min 0.02

# ---- the unit square with h = 0.02 + 0.2 x --------------------------------------------
F="0.02 + 0.2*x"
if "$M2" -p "$SQ" --size "$F" -u lin -v -O lin.vtu -O lin.msh --json >lin.json 2>"$T/err"; then
  ok "--size '$F': exit 0"
  if msg=$(python3 judge.py lin.vtk "$F" 0.02 0.22); then ok "--size '$F': $msg"; else bad "--size '$F': $msg"; fi
  for f in lin.vtu lin.vtk lin.msh; do
    if "$BIN" check "$f" --poly "$SQ" >"$T/out" 2>&1; then ok "mixoct check $f --poly: valid"
    else bad "mixoct check $f: $(tail -3 "$T/out")"; fi
  done
  has lin.vtu 'Name="target_size"' "the .vtu carries target_size"
  same "$(json_get lin.json 'd["size_field"]["structure"], d["size_field"]["leaves"] > 1, d["size_field"]["curves"]')" \
    "K_L s_S True 0" "--json: the field's structure and leaves"
else
  bad "--size '$F': exit $? $(cat "$T/err")"
fi
"$M2" -p "$SQ" --size "$F" >sum.txt 2>&1
has sum.txt "size field .* leaves (K_L s_S" "the summary names the field's structure"
"$M2" -p "$SQ" -a 4 -u plain -v --no-restart >/dev/null 2>&1
if grep -q target_size plain.vtk; then bad "target_size written without a field"; else ok "no target_size without a field"; fi
# the finer wins: -a 6 everywhere (side 0.0158) is finer than the field but at x < 0
"$M2" -p "$SQ" --size "$F" -a 6 --json >a6f.json 2>/dev/null
"$M2" -p "$SQ" -a 6 --json >a6.json 2>/dev/null
same "$(json_get a6f.json 'd["leaves"]')" "$(json_get a6.json 'd["leaves"]')" "-a 6 with a coarser field: -a 6's leaves"
# the same bytes for 1 and 2 threads and with the recursive balance
"$M2" -p "$PL/a.poly" -s 5 --size "0.004 + 0.1*abs(y + 0.5)" --threads 1 -O t1.vtu --binary 2>/dev/null
"$M2" -p "$PL/a.poly" -s 5 --size "0.004 + 0.1*abs(y + 0.5)" --threads 2 -O t2.vtu --binary 2>/dev/null
"$M2" -p "$PL/a.poly" -s 5 --size "0.004 + 0.1*abs(y + 0.5)" --balance recursive -O r.vtu --binary 2>/dev/null
if [ -s t1.vtu ] && cmp -s t1.vtu t2.vtu; then ok "a field: the same file for 1 and 2 threads"; else bad "a field: files differ with the thread count"; fi
if [ -s t1.vtu ] && cmp -s t1.vtu r.vtu; then ok "a field: the same mesh with --balance recursive"; else bad "a field: --balance recursive differs"; fi
if "$BIN" check t1.vtu --poly "$PL/a.poly" >"$T/out" 2>&1; then ok "a.poly with a field: valid"; else bad "a.poly with a field: $(tail -3 "$T/out")"; fi
# the bounds: --size-max 0.1 alone is a uniform field (16 x 16 quadrants of 1.01 / 16)
"$M2" -p "$SQ" --size-max 0.1 --json >max.json 2>/dev/null
same "$(json_get max.json 'd["leaves"], d["exit_code"]')" "256 0" "--size-max 0.1 alone: 256 leaves"
# and --size-min 0.05 raises the field's least sizes: no quadrant below level 5 (0.0316)
"$M2" -p "$SQ" --size "$F" --size-min 0.05 -u lo -v --no-restart >/dev/null 2>&1
same "$(python3 -c "
lines = open('lo.vtk').read().split('\n')
k = next(k for k, l in enumerate(lines) if l.startswith('SCALARS level'))
n = int(next(l for l in lines if l.startswith('CELL_DATA')).split()[1])
print(max(int(lines[k + 2 + j]) for j in range(n)))")" "5" "--size-min 0.05: the finest quadrants of level 5"

# ---- -f: requests without a field, sources with one ----------------------------------
CIRCLE="-f circle 0.5 0.5 0.3 6"
# shellcheck disable=SC2086
"$M2" -p "$SQ" -a 3 $CIRCLE -u c -v -o --json >c.json 2>/dev/null
same "$(json_get c.json 'd["leaves"], d["nodes"], d["elements"], "size_field" in d')" "640 793 1008 False" \
  "-f without a field: today's counts (640 leaves, 793 nodes, 1008 cells)"
if grep -q target_size c.vtk; then bad "-f without a field: target_size written"; else ok "-f without a field: no target_size"; fi
# shellcheck disable=SC2086
"$M2" -p "$SQ" -a 3 $CIRCLE --size-min 0.5 -u cm -v -o --json >/dev/null 2>&1
if cmp -s c.vtk cm.vtk && cmp -s c.off cm.off && cmp -s c.oct cm.oct; then ok "-f with --size-min alone (no field): the same bytes"
else bad "-f with --size-min alone: other files"; fi
for H in 0.5 "0.05 + 0.2*abs(y - 0.5)"; do
  # shellcheck disable=SC2086
  if "$M2" -p "$SQ" -a 3 $CIRCLE --size "$H" -u cf -v --json >cf.json 2>"$T/err"; then
    if msg=$(python3 judge.py cf.vtk "min($H, 1e9)" circle 0.5 0.5 0.3 6 0.01578125 0.5); then
      ok "-f circle level 6 with --size '$H': $msg ($(json_get cf.json 'd["elements"]') cells against 1008)"
    else
      bad "-f circle with --size '$H': $msg"
    fi
    same "$(json_get cf.json 'd["size_field"]["curves"]')" "1" "--json: the curve among the field's sources"
    if "$BIN" check cf.vtk --poly "$SQ" >"$T/out" 2>&1; then ok "-f circle with --size '$H': valid"
    else bad "-f circle with --size '$H': $(tail -3 "$T/out")"; fi
  else
    bad "-f circle with --size '$H': exit $? $(cat "$T/err")"
  fi
done

if [ "$fails" -eq 0 ]; then echo "all size2d tests passed"; exit 0; fi
echo "$fails failure(s)"
exit 1
