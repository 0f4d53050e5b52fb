"""mixoct: the mixed-element octree mesher (3D) and quadtree mesher (2D),
from Python (ctypes + numpy).

A thin binding over the C API of ``include/mixoct.h`` (``libmixoct.so``)::

    import mixoct
    with mixoct.Mesher(surface_level=4) as m:
        m.add_demo_surface()
        m.mesh()
        print(m.counts, m.nodes.shape, m.conn.shape)
        worst = [12, 40]                  # elements with a large error
        m.refine_elements(worst)          # Algorithm 3 of the 2021 paper
        m.write("demo.vtu")

and in 2D (closed polylines in, counter-clockwise triangles and
quadrilaterals out; the ``mesher2d`` program's calls)::

    with mixoct.Mesher2D(surface_level=5) as m:
        m.set_domain("box.poly")          # .poly, .off or a 2D .mdl
        m.mesh()
        print(m.counts, m.nodes.shape, m.cells.shape)   # (n, 2), (m, 4)
        m.save_restart("box.oct")
        m.refine_elements([7])
        m.write("box.vtu")

The library is looked for, in this order: the path in the environment
variable ``MIXOCT_LIB``; ``libmixoct.so`` in this package's directory; the
build directory this package was copied into (``<build>/python/mixoct`` ->
``<build>/libmixoct.so``); the path meson wrote into ``_libpath.py`` at
install time; the library on the linker's path (``ctypes.util``).

From Python to meshio in one call
--------------------------------
``mixoct.generate(surface, surface_level=..., **params)`` meshes a surface
file, ``"demo"`` or ``(xyz, tri)`` arrays and returns a ``meshio.Mesh``;
``Mesher.to_meshio()`` (and ``Mesher2D.to_meshio()``) converts the current
mesh: cell blocks by type in meshio's node order, the boundary faces as
"triangle"/"quad" blocks with their ``surface_tag``, point data
``boundary`` and ``surface_tag``, cell data ``J_ENS``, ``leaf``,
``level``, ``body`` (and ``material``), one array per block.
``Mesher.boundary_faces()`` gives the boundary faces (nodes, tag, the
element and local face each bounds) and each element's body as arrays.

Parameters
----------
Every field of the library's parameters (``mx_params``, ``mx_params2d``)
is a keyword of ``Mesher`` (``Mesher2D``); None or left out: the
library's default (``Mesher.defaults()``). Values are checked against the
command line's ranges: out of range raises InputError naming the argument.

Mesh arrays are views, not copies
---------------------------------
``Mesher.nodes``, ``conn``, ``types``, ``jens``, ``leaf``, ``level``,
``boundary`` and ``material`` (and ``Mesher2D.nodes``, ``cells``,
``types``, ``leaf`` and ``level``) are read-only numpy arrays over the
library's own memory (no copy). A view never reads freed memory: when a
call changes the mesh (``mesh``, ``build_octree``, ``transition``,
``boundary_stage``, ``refine``, ``refine_elements``, ``refine_leaves``,
``load_restart``) while views of the mesh are alive, the library hands the
memory of the old mesh's arrays over to the views
(``mx_mesher_detach_mesh_buffers``: it goes on with a copy, made then and
only then; with no view alive nothing is copied), and the old views keep
the values they had; the memory is freed with the last of them. The cost:
one copy of the mesh arrays per re-mesh while old views are held (42
bytes an element, 44 with materials, and 25 a node in 3D; 26 and 16 in
2D), for as long as the old views live. Each view's ``.base`` chain ends
in a :class:`MeshBuffer` that records the mesh generation it was taken
from (``detached``: its memory was handed over): ``Mesher.is_current(array)``
tells whether it shows the current mesh, and ``Mesher.generation`` counts
the mesh changes. ``close()`` (or leaving the ``with`` block) is safe with
views alive: the C object is freed when the last view of it is gone. All of
this holds for ``Mesher2D`` alike.

Progress, cancellation, Ctrl-C
------------------------------
``Mesher(..., progress=f)`` or ``set_progress(f)``: ``f(stage, info)`` is
called before each stage (``info`` None), each octree level (``"level"``,
``(level, max_level)``) and each repair round (``"repair"``, the round).
Returning False cancels the call: it raises :class:`CancelledError`
(status 6) and leaves no mesh (a cancelled re-mesh keeps the octree with
the levels it completed: the next ``mesh()`` meshes it); an exception raised by ``f`` cancels the
call and is raised by it. ``cancel()`` from another thread does the same.
The long calls (meshing, re-meshing, writing) run, from the main thread,
in a worker thread while the main thread waits in short slices: Ctrl-C
(SIGINT) cancels the library's call (it checks the flag between its
passes and in its longest loops) and raises ``KeyboardInterrupt`` once
the call has stopped, within about a second. The mesher stays usable.

Several materials
-----------------
``Mesher(..., materials=True)`` (``mx_params.materials``, the program's
``--materials``) makes the shells nested in the outermost one materials
instead of holes, and surfaces added as several inputs that share faces
materials glued along them: ``Mesher.material`` gives each element's
material, a uint16 view numbered by nesting depth (1 inside one shell, 2
inside two, ...; at the transition stage 0 outside every shell) and input.
Without ``materials`` it is None. At the full stage the interfaces are cut
along the input surfaces: no element lies across one. Re-meshing
(``refine_elements``, ``refine``, ...) keeps the materials; a restart file
written with materials turns them on when read back with the same inputs
(before anything else used the inputs). ``set_material(input, number,
name)`` numbers and names them, ``set_input_level(input, surface_level,
inside_level)`` refines one surface or one material.

``Mesher2D(..., materials=True)`` does the same in 2D (``mesher2d
--materials``): a loop nested in an outer one is the interface between two
materials; the cells are cut along it (no cell lies across it, its edges
have both nodes on the loop) and ``Mesher2D.material`` gives each cell's
material number (by default its nesting depth; ``set_material(depth,
number, name)`` chooses them). Re-meshing keeps them.

Errors
------
Every non-zero status of the library raises a subclass of :class:`Error`
(``status`` the code, ``message`` the library's message naming the file and
line for bad input): :class:`InternalError` (1), :class:`InputError` (2,
also a ``ValueError``), :class:`OutOfMemoryError` (3, also a
``MemoryError``), :class:`OutputError` (4), :class:`InvalidMeshError` (5:
elements with J_ENS <= 0 are left, or in 2D the mesh failed the independent
check; the mesh is still there to inspect or write), :class:`CancelledError`
(6). The messages are shared with the command-line programs; the binding
gives the flags and C functions they name as the Python arguments and
methods that do the same (``-s`` as ``surface_level``, ``mx_mesher_mesh``
as ``mesh()``). Warnings of the library do not go to stderr: they are
collected in ``Mesher.warnings`` (a list of str).

Threads: the library runs its passes with OpenMP threads and the GIL is
released during each call; one Mesher must not be used from two Python
threads at once. Two Meshers may work at the same time in two Python
threads: the library's messages go to the handler of the calling thread's
mesher, so each sees its own warnings only.

The wait policy: libgomp (the OpenMP runtime of libmixoct.so) makes a
thread that waits at a barrier spin by default, and when another job holds
a core the spinning thread takes the time slice of the thread it waits
for: on a shared machine 2 threads then run several times slower than 1.
libgomp reads ``OMP_WAIT_POLICY`` once, when it is loaded, so on import,
before anything loads the library, this module sets
``os.environ["OMP_WAIT_POLICY"] = "passive"`` (waiting threads sleep; the
C environment changes too, and child processes inherit it) unless
``OMP_WAIT_POLICY`` or ``GOMP_SPINCOUNT`` is set already (yours is kept;
``GOMP_SPINCOUNT=300000`` keeps libgomp's default) or libgomp is loaded
already (another module started it: setting the variable would change
nothing; the library then limits each call's threads to the processors
other processes leave free, see include/mixoct.h). ``wait_policy`` says
which: ``"passive (set by mixoct)"``, ``"the user's (OMP_WAIT_POLICY=...)"``
or ``"the user's (GOMP_SPINCOUNT=...)"``, or ``"default (libgomp was loaded
before mixoct)"``. :func:`last_call_threads` gives the thread count the
last call ran with.
"""

__version__ = "0.1.0"  # meson.build's project version (tests/python_binding_test.py)


import os


def _libgomp_loaded():
    """Whether libgomp.so (the one libmixoct.so needs; not a copy that a
    wheel bundles under another name) is mapped in this process."""
    try:
        with open("/proc/self/maps") as f:
            # address perms offset dev inode path
            paths = (line.split(None, 5)[5:] for line in f)
            return any(os.path.basename(p[0].strip()).startswith("libgomp.so")
                       for p in paths if p)
    except OSError:
        return False


def _choose_wait_policy():
    for name in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT"):
        if name in os.environ:
            return "the user's (%s=%s)" % (name, os.environ[name])
    if _libgomp_loaded():
        return "default (libgomp was loaded before mixoct)"
    os.environ["OMP_WAIT_POLICY"] = "passive"
    return "passive (set by mixoct)"


#: what OpenMP threads do when they wait (see the module's doc); chosen on
#: import, before numpy or the library can load libgomp
wait_policy = _choose_wait_policy()

# the modules below import numpy and ctypes: after the wait policy

__all__ = [
    "Mesher", "Mesher2D", "MeshBuffer", "read_element_list", "load_library",
    "Error", "InternalError", "InputError", "OutOfMemoryError", "OutputError",
    "InvalidMeshError", "TET", "PYRAMID", "PRISM", "HEX", "TYPE_NAMES",
    "NODES_PER_TYPE", "TRI", "QUAD", "NO_NODE", "status_string",
    "wait_policy", "last_call_threads", "CancelledError", "generate",
    "MAX_LEVEL", "MAX_LEVEL_2D",
]

from ._capi import (  # noqa: E402,F401
    CancelledError, ECANCELED, EINPUT, EINTERNAL, EINVALID, EIO, ENOMEM, Error, HEX,
    InputError, InternalError, InvalidMeshError, MAX_LEVEL, MAX_LEVEL_2D, MSG_ERROR,
    MSG_WARNING, NODES_PER_TYPE, NO_NODE, OK, OutOfMemoryError, OutputError, PRISM,
    PYRAMID, QUAD, TET, TRI, TYPE_NAMES, _Params, _Params2D, last_call_threads,
    load_library, status_string)
from ._args import (  # noqa: E402,F401
    _pythonic)
from ._base import (  # noqa: E402,F401
    MeshBuffer)
from ._mesher import (  # noqa: E402,F401
    Mesher, generate)
from ._mesher2d import (  # noqa: E402,F401
    Mesher2D)
from ._element_list import (  # noqa: E402,F401
    read_element_list)
