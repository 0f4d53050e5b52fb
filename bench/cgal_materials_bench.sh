#!/usr/bin/env bash
# Several materials (issue 26): mixoct --materials side by side with CGAL's
# Mesh_3 (tetrahedra, CGAL::Polyhedral_complex_mesh_domain_3:
# bench/cgal/mesh3_materials.cpp) on tests/make_surfaces.py's hollow ball
# shell.off (a sphere of radius 1 with one of radius 0.5 inside, both about
# the centre (0.013, 0.021, -0.017): two materials, the interface the inner
# sphere).
#
# For each mixoct LEVEL (`mixoct -i shell.off --materials -s LEVEL`), CGAL's
# sizes are chosen to give about the same mesh: facet_size so that the
# interface has as many nodes as mixoct's (within 5%), cell_size so that the
# whole mesh has as many nodes (within 10%, when the surfaces leave room),
# found by a few runs without CGAL's optimisation (perturb and exude do not
# move the surface nodes nor add any); then both run REPEAT times (CGAL with
# its default optimisation). Reported for each mesh:
#   - nodes, elements; wall and CPU time (median of REPEAT runs; mixoct with
#     all threads and with --threads 1, CGAL being sequential: its parallel
#     mode needs TBB);
#   - worst J_ENS and defects (`mixoct check --surface shell.off --json`);
#   - each material's volume error against the exact ball and shell
#     (4/3 pi r^3) and against the tessellation's (what both mesh);
#   - the interface (faces between elements of two materials,
#     bench/cgal/interface_distance.py): nodes, and the max and mean of
#     | |x - C| - 0.5 | over its nodes and over its faces' centroids. Both
#     tools put the interface nodes on the input triangles, so the node
#     distance has the input's own chord error as its floor (printed).
# Then, for each level, mixoct's CPU time (one thread) against the cheapest
# CGAL mesh whose interface faces are no farther from the sphere (face
# distance max): the time at equal interface accuracy.
# A table, then one JSON object on the last line. Slow (minutes): not in CI.
#
#   bench/cgal_materials_bench.sh MIXOCT [LEVELS] [REPEAT]   (default "5 6", 3)
#
# MESH3_MATERIALS=path skips the build (a mesh3_materials built before);
# otherwise it is built with g++ -O2 into the temporary directory (about a
# minute), and the bench is skipped (exit 0, with a message) without the
# CGAL headers.
set -u
BIN=${1:?usage: cgal_materials_bench.sh MIXOCT [LEVELS] [REPEAT]}
LEVELS=${2:-5 6}
REPEAT=${3:-3}
HERE=$(cd "$(dirname "$0")" && pwd)
T=$(mktemp -d "${TMPDIR:-/tmp}/mixoct_cgal_bench.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT

CGAL_BIN=${MESH3_MATERIALS:-}
if [ -z "$CGAL_BIN" ]; then
  CXX=${CXX:-g++}
  if ! command -v "$CXX" >/dev/null 2>&1; then
    echo "cgal_materials_bench: skipped: no C++ compiler ($CXX)"
    exit 0
  fi
  if ! printf '#include <CGAL/Polyhedral_complex_mesh_domain_3.h>\n' |
    "$CXX" -x c++ -std=c++17 -fsyntax-only - >/dev/null 2>&1; then
    echo "cgal_materials_bench: skipped: CGAL's Mesh_3 headers not found (Debian: libcgal-dev)"
    exit 0
  fi
  echo "building bench/cgal/mesh3_materials.cpp (CGAL, about a minute)..."
  CGAL_BIN=$T/mesh3_materials
  "$CXX" -O2 -DNDEBUG -std=c++17 "$HERE/cgal/mesh3_materials.cpp" -o "$CGAL_BIN" \
    -lgmp -lmpfr || exit 1
fi
python3 "$HERE/../tests/make_surfaces.py" "$T" >"$T/volumes.json" || exit 1

python3 - "$BIN" "$CGAL_BIN" "$T" "$LEVELS" "$REPEAT" "$HERE/cgal/interface_distance.py" <<'EOF'
import json, math, os, resource, statistics, subprocess, sys, time

MIXOCT, CGAL, T, LEVELS, REPEAT, IFACE = sys.argv[1:7]
LEVELS = [int(x) for x in LEVELS.split()]
REPEAT = int(REPEAT)
SHELL = os.path.join(T, "shell.off")
CENTRE, R_IN, R_OUT = (0.013, 0.021, -0.017), 0.5, 1.0
EXACT = {1: 4 / 3 * math.pi * (R_OUT ** 3 - R_IN ** 3), 2: 4 / 3 * math.pi * R_IN ** 3}


def run(cmd):
    """(wall s, CPU s of the child, stdout); exits on failure"""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit("cgal_materials_bench: %s failed (%d): %s" % (" ".join(cmd), p.returncode,
                                                               p.stderr.strip()[-500:]))
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, p.stdout


def last_json(text):
    return json.loads(text.strip().splitlines()[-1])


def judge(mesh):
    """the checker's and the interface's figures for one .mesh"""
    p = subprocess.run([MIXOCT, "check", mesh, "--surface", SHELL, "--json", "--quiet"],
                       stdout=subprocess.PIPE, text=True)
    c = last_json(p.stdout)
    i = last_json(run(["python3", IFACE, mesh, *map(str, CENTRE), str(R_IN)])[2])
    mats = {m["label"]: m for m in c.get("materials", [])}
    return {
        "nodes": c["nodes"], "elements": c["elements"], "by_type": c.get("by_type"),
        "jens_min": c["jens_min"], "invalid": c["invalid"], "check_defects": c["defects"],
        "check_exit": p.returncode, "interface_faces_check": c.get("interface_faces"),
        "volume_error_exact": {k: (mats[k]["volume"] - EXACT[k]) / EXACT[k]
                               for k in EXACT if k in mats},
        "volume_error_input": {k: mats[k]["volume_error"] for k in EXACT if k in mats},
        "interface_nodes": i["interface_nodes"], "interface_faces": i["interface_faces"],
        "node_dist": i["node_dist"], "face_dist": i["face_dist"],
    }


def timed(cmd, out):
    walls, cpus = [], []
    for _ in range(REPEAT):
        w, c, _ = run(cmd)
        walls.append(w)
        cpus.append(c)
    return {"wall_s": statistics.median(walls), "cpu_s": statistics.median(cpus),
            "walls": walls, **judge(out)}


def input_sag():
    """the inner shell's largest distance from the sphere: R - the distance
    of the centre to the plane of each of its triangles"""
    words = open(SHELL).read().split()
    nv, nf = int(words[1]), int(words[2])
    v = [tuple(float(x) for x in words[4 + 3 * k:7 + 3 * k]) for k in range(nv)]
    f = [tuple(int(x) for x in words[4 + 3 * nv + 4 * k + 1:4 + 3 * nv + 4 * k + 4])
         for k in range(nf)]
    worst = 0.0
    for a, b, c in f:
        pa, pb, pc = v[a], v[b], v[c]
        if abs(math.dist(pa, CENTRE) - R_IN) > 1e-9:
            continue
        u = [pb[k] - pa[k] for k in range(3)]
        w = [pc[k] - pa[k] for k in range(3)]
        n = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        h = abs(sum(n[k] * (pa[k] - CENTRE[k]) for k in range(3))) / math.sqrt(sum(x * x for x in n))
        worst = max(worst, R_IN - h)
    return worst


def cgal_cmd(out, fs, cs, optimise=True):
    cmd = [CGAL, SHELL, out, "--facet-size", "%.6g" % fs, "--cell-size", "%.6g" % cs]
    return cmd if optimise else cmd + ["--no-perturb", "--no-exude"]


def calibrate(target):
    """facet and cell sizes giving target's interface and total node counts"""
    want_i, want_n = target["interface_nodes"], target["nodes"]
    # start: equilateral triangles on the inner sphere, 2 per node, whose
    # circumradius (e / sqrt 3) is what facet_size bounds
    e = math.sqrt(4 * (4 * math.pi * R_IN ** 2) / (math.sqrt(3) * 2 * want_i))
    fs, cs = e / math.sqrt(3), 3 * e
    out = os.path.join(T, "calibrate.mesh")
    tries = []
    for _ in range(8):
        run(cgal_cmd(out, fs, cs, optimise=False))
        j = judge(out)
        tries.append({"facet_size": fs, "cell_size": cs, "interface_nodes": j["interface_nodes"],
                      "nodes": j["nodes"]})
        ri = j["interface_nodes"] / want_i
        rn = j["nodes"] / want_n
        if abs(ri - 1) <= 0.05 and (abs(rn - 1) <= 0.10 or (rn > 1 and cs > 50 * fs)):
            break
        fs *= math.sqrt(ri)  # interface nodes ~ facet_size^-2
        # the nodes off the surfaces ~ cell_size^-3; cap the step
        cs *= min(2.0, max(0.5, rn ** (1 / 3) if abs(ri - 1) <= 0.2 else 1.0))
    return fs, cs, tries


sag = input_sag()
results = {"bench": "cgal_materials", "input": "tests/make_surfaces.py shell.off",
           "exact_volumes": EXACT, "input_sag": sag, "repeat": REPEAT, "cpus": os.cpu_count(),
           "load_before": os.getloadavg()[0], "levels": {}}
rows = []
for L in LEVELS:
    mesh = os.path.join(T, "m%d.mesh" % L)
    base = [MIXOCT, "-i", SHELL, "--materials", "-s", str(L), "-o", mesh, "--quiet"]
    m1 = timed(base + ["--threads", "1"], mesh)
    m = timed(base, mesh)
    fs, cs, tries = calibrate(m)
    cmesh = os.path.join(T, "c%d.mesh" % L)
    c = timed(cgal_cmd(cmesh, fs, cs), cmesh)
    c.update({"facet_size": fs, "cell_size": cs, "calibration": tries})
    results["levels"][L] = {"mixoct": m, "mixoct_1thread": m1, "cgal": c,
                            "cgal_over_mixoct_wall": c["wall_s"] / m["wall_s"],
                            "cgal_over_mixoct_1thread_cpu": c["cpu_s"] / m1["cpu_s"]}
    rows += [("mixoct", "-s %d" % L, m), ("mixoct -t1", "-s %d" % L, m1),
             ("CGAL Mesh_3", "fs %.4g cs %.3g" % (fs, cs), c)]

head = ("tool", "level/size", "nodes", "elements", "wall s", "cpu s", "J_ENS min", "vol err m1/m2",
        "(vs input)", "if nodes", "node dist max/mean", "face dist max/mean", "defects")
fmt = "%-11s %-17s %7s %8s %7s %7s %9s %-15s %-15s %8s %-19s %-19s %s"
print(fmt % head)
for tool, size, r in rows:
    ve, vi = r["volume_error_exact"], r["volume_error_input"]
    print(fmt % (tool, size, r["nodes"], r["elements"], "%.3f" % r["wall_s"], "%.3f" % r["cpu_s"],
                 "%.4f" % r["jens_min"], "%+.2f%%/%+.2f%%" % (100 * ve[1], 100 * ve[2]),
                 "%+.2f%%/%+.2f%%" % (100 * vi[1], 100 * vi[2]), r["interface_nodes"],
                 "%.5f/%.5f" % (r["node_dist"]["max"], r["node_dist"]["mean"]),
                 "%.5f/%.5f" % (r["face_dist"]["max"], r["face_dist"]["mean"]), r["check_defects"]))
# equal interface accuracy: for each mixoct level, the cheapest CGAL mesh
# (among those above) whose interface faces lie as close to the sphere
# (face dist max no larger)
eq = {}
cg = [(L, v["cgal"]) for L, v in results["levels"].items()]
for L, v in results["levels"].items():
    m = v["mixoct_1thread"]
    ok = [(c["cpu_s"], K) for K, c in cg if c["face_dist"]["max"] <= m["face_dist"]["max"]]
    if ok:
        cpu, K = min(ok)
        eq[L] = {"cgal_matched_to_level": K, "cgal_cpu_s": cpu, "mixoct_1thread_cpu_s": m["cpu_s"],
                 "cgal_over_mixoct_cpu": cpu / m["cpu_s"]}
        print("equal interface accuracy: mixoct -s %d (face dist max %.5f) %.3f s CPU with 1 thread, "
              "CGAL sized for -s %d (%.5f) %.3f s CPU: x%.1f"
              % (L, m["face_dist"]["max"], m["cpu_s"], K, results["levels"][K]["cgal"]["face_dist"]["max"],
                 cpu, cpu / m["cpu_s"]))
    else:
        print("equal interface accuracy: no CGAL mesh here with its interface faces as close as "
              "mixoct -s %d's" % L)
results["equal_face_accuracy"] = eq
print("input's own distance from the inner sphere (chord error of its triangles): %.5f" % sag)
print("wall and cpu: median of %d runs; mixoct with all threads, then --threads 1; CGAL "
      "sequential, perturb and exude on" % REPEAT)
print(json.dumps(results))
EOF
