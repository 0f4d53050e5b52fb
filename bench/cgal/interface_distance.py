#!/usr/bin/env python3
"""The interface of a two-material Medit mesh against the exact sphere it
should follow (bench/cgal_materials_bench.sh, issue 26).

usage: interface_distance.py MESH.mesh CX CY CZ R

Reads an ASCII Medit .mesh (Vertices, and any of Tetrahedra, Pyramids,
Prisms, Hexahedra with the element reference as its material; node orders
as mixoct writes them, see src/io/write_medit.c: a face is a set of nodes,
so only which nodes make a face matters here). An interface face is a face
of two elements of different materials. Over the nodes of the interface
faces: max and mean of | |x - C| - R |; over the interface faces' centroids
(how far the faces themselves are from the sphere): the same. Prints one
JSON object: nodes, elements, elements per material, interface faces,
interface nodes, node_dist {max, mean}, face_dist {max, mean}.
"""
import json
import math
import sys

# the faces of each element type as node positions (mixoct's orders)
FACES = {
    "Tetrahedra": [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)],
    "Pyramids": [(0, 1, 2, 3), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
    "Prisms": [(0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
    "Hexahedra": [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5),
                  (2, 3, 7, 6), (3, 0, 4, 7)],
}
NODES = {"Tetrahedra": 4, "Pyramids": 5, "Prisms": 6, "Hexahedra": 8}
SKIP = {"Triangles": 4, "Quadrilaterals": 5, "Edges": 3, "Corners": 1,
        "Ridges": 1, "RequiredVertices": 1, "RequiredEdges": 1}


def read_medit(path):
    """(xyz list, [(type, [node tuples 0-based], [refs])])"""
    words = open(path).read().split()
    i, xyz, blocks = 0, [], []
    while i < len(words):
        w = words[i]
        i += 1
        if w.startswith("#"):
            continue
        if w in ("MeshVersionFormatted", "Dimension"):
            i += 1
        elif w == "Vertices":
            n = int(words[i])
            i += 1
            xyz = [(float(words[i + 4 * k]), float(words[i + 4 * k + 1]),
                    float(words[i + 4 * k + 2])) for k in range(n)]
            i += 4 * n
        elif w in NODES:
            n, m = int(words[i]), NODES[w] + 1
            i += 1
            conn = [tuple(int(x) - 1 for x in words[i + m * k:i + m * k + m - 1]) for k in range(n)]
            refs = [int(words[i + m * k + m - 1]) for k in range(n)]
            blocks.append((w, conn, refs))
            i += m * n
        elif w in SKIP:
            i += 1 + SKIP[w] * int(words[i])
        elif w == "End":
            break
        else:
            sys.exit("interface_distance.py: %s: unknown keyword %r" % (path, w))
    return xyz, blocks


def main(argv):
    if len(argv) != 6:
        sys.stderr.write("usage: interface_distance.py MESH.mesh CX CY CZ R\n")
        return 2
    xyz, blocks = read_medit(argv[1])
    c = [float(x) for x in argv[2:5]]
    radius = float(argv[5])
    # nodes that belong to elements of more than one material: only their
    # faces can be interface faces
    mats = [0] * len(xyz)
    per_material = {}
    for kind, conn, refs in blocks:
        for e, r in zip(conn, refs):
            per_material[r] = per_material.get(r, 0) + 1
            for v in e:
                mats[v] = mats[v] | (1 << r) if r < 60 else -1
    mixed = [m == -1 or (m & (m - 1)) != 0 for m in mats]
    seen = {}
    interface = []
    for kind, conn, refs in blocks:
        for e, r in zip(conn, refs):
            for f in FACES[kind]:
                nodes = [e[k] for k in f]
                if not all(mixed[v] for v in nodes):
                    continue
                key = tuple(sorted(nodes))
                other = seen.get(key)
                if other is None:
                    seen[key] = r
                elif other != r:
                    interface.append(key)

    def dist(p):
        return abs(math.sqrt(sum((p[a] - c[a]) ** 2 for a in range(3))) - radius)

    inodes = sorted({v for f in interface for v in f})
    nd = [dist(xyz[v]) for v in inodes]
    fd = [dist([sum(xyz[v][a] for v in f) / len(f) for a in range(3)]) for f in interface]
    out = {
        "nodes": len(xyz),
        "elements": sum(len(b[1]) for b in blocks),
        "elements_per_material": {str(k): v for k, v in sorted(per_material.items())},
        "interface_faces": len(interface),
        "interface_nodes": len(inodes),
        "node_dist": {"max": max(nd) if nd else None, "mean": sum(nd) / len(nd) if nd else None},
        "face_dist": {"max": max(fd) if fd else None, "mean": sum(fd) / len(fd) if fd else None},
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
