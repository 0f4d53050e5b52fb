"""The point field "boundary" of a VTU file (argv[1:]) against the nodes of
its faces used once, found here from the cells (meshio): prints the counts
and exits 1 when a node of a boundary face is not flagged or a flagged node
is on none (tests/tag_faces_test.sh)."""
import sys
from collections import Counter

import meshio
import numpy as np

FACES = {
    "tetra": [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)],
    "pyramid": [(0, 1, 2, 3), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
    "wedge": [(0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
    "hexahedron": [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                   (3, 0, 4, 7)],
}
bad = 0
for path in sys.argv[1:]:
    m = meshio.read(path)
    uses = Counter()
    for block in m.cells:
        for row in block.data:
            for f in FACES[block.type]:
                uses[tuple(sorted(row[list(f)]))] += 1
    on = set()
    for f, n in uses.items():
        if n == 1:
            on.update(int(v) for v in f)
    flagged = set(int(v) for v in np.nonzero(m.point_data["boundary"])[0])
    missing, extra = len(on - flagged), len(flagged - on)
    print(f"{path}: {len(on)} nodes on boundary faces, {len(flagged)} flagged, "
          f"{missing} missing, {extra} extra")
    bad += missing + extra
sys.exit(1 if bad else 0)
