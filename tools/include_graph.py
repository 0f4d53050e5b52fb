#!/usr/bin/env python3
"""Include structure of src/: circles and layer violations (issue 25).

usage: tools/include_graph.py [SRC_DIR]   (default: src next to this file)

Prints:
  - include circles between headers (a header including, through others,
    itself);
  - include circles between modules (strongly connected components of the
    "#include" graph of src/*/*.h and their .c files, a .c merged with its
    header: two modules that call each other), each with its files;
  - include circles between directories (the same graph with a node per
    directory), each with the edges closing it;
  - layer violations: an include from a directory to one the layer order
    of ../shared/DESIGN.md does not allow:
      cli -> mesher -> kernels -> patterns -> geom -> soa -> base,
      io and verify -> soa, geom, base only; quad (2D kernels) -> patterns,
      geom, soa, base, io (its view); sizing (size fields) -> base only
      for now; mpi -> mesher and below; cli -> its
      own headers and include/mixoct.h only.
The last line: "H header circles, N module circles, M directory circles, K layer
violations".
"""
import os
import re
import sys
from collections import defaultdict

here = os.path.dirname(os.path.abspath(__file__))
src = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "src")
src = os.path.abspath(src)

# rank: a directory may include directories of lower or equal rank only,
# except where `extra` says otherwise; `only` restricts some directories.
rank = {"base": 0, "morton": 0, "soa": 1, "geom": 2, "patterns": 3, "kernels": 4, "io": 2.5,
        "verify": 2.5, "sizing": 2, "quad": 4, "mesher": 5, "mpi": 6, "cli": 7}
only = {"io": {"io", "soa", "geom", "base"}, "sizing": {"sizing", "base"}, "verify": {"verify", "soa", "geom", "base"},
        "cli": {"cli"}}  # the programs: include/mixoct.h and their own headers

inc_re = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
files = {}
for d, _, names in os.walk(src):
    for n in names:
        if n.endswith((".c", ".h")):
            p = os.path.join(d, n)
            files[os.path.relpath(p, src)] = p


def unit(rel):
    """A .c and its .h are one unit (named by the path without extension)."""
    return rel[:-2]


graph = defaultdict(set)
hgraph = defaultdict(set)   # headers only: a header including a header
violations = []
for rel, p in sorted(files.items()):
    text = open(p, encoding="utf-8", errors="replace").read()
    a = unit(rel)
    da = rel.split("/")[0] if "/" in rel else "."
    for inc in inc_re.findall(text):
        if inc not in files:  # beside the including file ("cli.h"), or
            inc = os.path.normpath(os.path.join(os.path.dirname(rel), inc))
        if inc not in files:
            continue  # a system or the public header (include/mixoct.h)
        b = unit(inc)
        if rel.endswith(".h") and inc.endswith(".h"):
            hgraph[rel].add(inc)
        if b != a:
            graph[a].add(b)
        db = inc.split("/")[0] if "/" in inc else "."
        if da == db or da == "." or db == ".":
            continue
        ok = db in only[da] if da in only else rank.get(db, 99) <= rank.get(da, -1)
        if da == "quad" and db == "io":
            ok = True
        if not ok:
            violations.append((rel, inc))


def sccs(g):
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]
    nodes = set(g) | {b for v in g.values() for b in v}

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(g.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(100000)
    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return out


file_circles = sccs(graph)
header_circles = sccs(hgraph)
dgraph = defaultdict(set)
dedges = defaultdict(list)
for a, bs in graph.items():
    for b in bs:
        da, db = a.split("/")[0], b.split("/")[0]
        if da != db:
            dgraph[da].add(db)
            dedges[(da, db)].append((a, b))
dir_circles = sccs(dgraph)

print("include circles between headers:")
for c in header_circles:
    print("  " + " <-> ".join(c))
print("include circles between modules (a .c with its .h as one unit):")
for c in file_circles:
    print("  " + " <-> ".join(c))
print("include circles between directories:")
for c in dir_circles:
    members = set(c)
    print("  " + " <-> ".join(c))
    for (da, db), es in sorted(dedges.items()):
        if da in members and db in members:
            print("      %s -> %s: %s" % (da, db, ", ".join("%s->%s" % e for e in es[:4])
                                          + (" ..." if len(es) > 4 else "")))
print("layer violations (DESIGN.md order):")
for rel, inc in violations:
    print("  %s includes %s" % (rel, inc))
print("%d header circles, %d module circles, %d directory circles, %d layer violations"
      % (len(header_circles), len(file_circles), len(dir_circles), len(violations)))
