#!/usr/bin/python3
"""The Python binding's wait policy and the library's load limit (issue 24,
"threads that never hurt"; python/mixoct/__init__.py, include/mixoct.h).

Run by meson (test 'python_threads') with PYTHONPATH=<build>/python, or by
hand:

    PYTHONPATH=<build>/python /usr/bin/python3 tests/python_threads_test.py

Each case is a fresh python3 in a clean environment (only PATH, PYTHONPATH,
PYTHONDONTWRITEBYTECODE and MIXOCT_LIB are kept, plus the case's
variables), since libgomp reads the policy once, when it is loaded:

1. nothing set: the binding sets OMP_WAIT_POLICY=passive in os.environ
   (and the C environment: the library, loaded after, sees it and leaves
   the thread count alone: a mesh with threads=0 runs with OpenMP's
   default even with MIXOCT_TEST_BUSY unset, whatever the load);
2. OMP_WAIT_POLICY=active, 3. GOMP_SPINCOUNT=1000: the user's, kept;
4. libgomp loaded before mixoct (ctypes.CDLL("libgomp.so.1")): nothing
   set (it would change nothing); the library's load limit is then on: with
   MIXOCT_TEST_BUSY (as if other processes held all processors but one) a
   mesh with threads=0 runs with 1 thread, and is the same bytes as the
   mesh with threads=2, which the limit leaves alone.

Without numpy it prints SKIP and exits 77 (meson's "skipped"), unless CI is
set, where that is a failure.
"""

import json
import os
import subprocess
import sys


def skip(why):
    if os.environ.get("CI"):
        print("FAIL: %s (CI is set: the Python test must run)" % why)
        sys.exit(1)
    print("SKIP: %s" % why)
    sys.exit(77)


try:
    import numpy  # noqa: F401
except ImportError:
    skip("numpy missing "
         "(apt-get install --no-install-recommends python3-numpy)")

# What each child prints: one JSON object.
CHILD = r"""
import ctypes, hashlib, json, os, sys
preload = sys.argv[1] == "preload"
if preload:
    ctypes.CDLL("libgomp.so.1")
env_before = {k: os.environ.get(k) for k in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
import mixoct
out = {"policy": mixoct.wait_policy,
       "env_before": env_before,
       "env_after": {k: os.environ.get(k)
                     for k in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}}
getenv = ctypes.CDLL(None).getenv
getenv.restype = ctypes.c_char_p
getenv.argtypes = [ctypes.c_char_p]
v = getenv(b"OMP_WAIT_POLICY")
out["c_env"] = v.decode() if v is not None else None
out["meshes"] = []
for threads in (0, 2):
    with mixoct.Mesher(surface_level=3, threads=threads) as m:
        m.add_demo_surface()
        m.mesh()
        used = mixoct.last_call_threads()
        h = hashlib.sha1()
        for a in (m.nodes, m.types, m.conn, m.jens, m.leaf):
            h.update(a.tobytes())
        out["meshes"].append({"threads": threads, "used": used,
                              "hash": h.hexdigest(), "elements": len(m.types)})
print(json.dumps(out))
"""

failures = 0


def check(cond, what):
    global failures
    print("%s %s" % ("ok  " if cond else "FAIL", what))
    if not cond:
        failures += 1


def child(extra, preload=False):
    env = {k: os.environ[k] for k in ("PATH", "PYTHONPATH", "PYTHONDONTWRITEBYTECODE",
                                       "MIXOCT_LIB") if k in os.environ}
    env.update(extra)
    # a fixed default thread count, so that the limit has something to cut
    env.setdefault("OMP_NUM_THREADS", "2")
    p = subprocess.run([sys.executable, "-c", CHILD, "preload" if preload else "-"],
                       env=env, capture_output=True, text=True, timeout=120)
    if p.returncode != 0:
        print(p.stdout + p.stderr)
        check(False, "child python exited %d (%s)" % (p.returncode, extra))
        return None
    return json.loads(p.stdout.strip().splitlines()[-1])


def same_meshes(r, what):
    hashes = {m["hash"] for m in r["meshes"]}
    check(len(hashes) == 1 and r["meshes"][0]["elements"] > 100,
          "%s: the same mesh with threads=0 and threads=2 (%s)"
          % (what, ", ".join("%d elements, ran with %d threads" % (m["elements"], m["used"])
                             for m in r["meshes"])))


online = os.sysconf("SC_NPROCESSORS_ONLN")

# 1. nothing set
r = child({})
if r:
    check(r["policy"] == "passive (set by mixoct)",
          "nothing set: wait_policy %r" % r["policy"])
    check(r["env_after"]["OMP_WAIT_POLICY"] == "passive",
          "nothing set: os.environ OMP_WAIT_POLICY=%r" % r["env_after"]["OMP_WAIT_POLICY"])
    check(r["c_env"] == "passive", "nothing set: the C environment has it too (%r)"
          % r["c_env"])
    # the library saw the policy when it was loaded: no load limit, whatever
    # the load of the machine
    check(r["meshes"][0]["used"] == 2,
          "nothing set: the library left the threads alone (threads=0 ran with %d)"
          % r["meshes"][0]["used"])
    same_meshes(r, "nothing set")

# 2. and 3. the user's
for name, value in (("OMP_WAIT_POLICY", "active"), ("GOMP_SPINCOUNT", "1000")):
    r = child({name: value})
    if r:
        check(r["policy"] == "the user's (%s=%s)" % (name, value),
              "%s=%s: wait_policy %r" % (name, value, r["policy"]))
        check(r["env_after"] == r["env_before"],
              "%s=%s: os.environ unchanged (%r)" % (name, value, r["env_after"]))
        check(r["meshes"][0]["used"] == 2,
              "%s=%s: no load limit (threads=0 ran with %d)"
              % (name, value, r["meshes"][0]["used"]))

# 4. libgomp loaded first
try:
    import ctypes
    ctypes.CDLL("libgomp.so.1")
    have_gomp = True
except OSError:
    have_gomp = False
if have_gomp:
    busy = str(online - 1 if online > 1 else 1)
    r = child({"MIXOCT_TEST_BUSY": busy}, preload=True)
    if r:
        check(r["policy"] == "default (libgomp was loaded before mixoct)",
              "libgomp loaded first: wait_policy %r" % r["policy"])
        check(r["env_after"]["OMP_WAIT_POLICY"] is None,
              "libgomp loaded first: OMP_WAIT_POLICY not set (%r)"
              % r["env_after"]["OMP_WAIT_POLICY"])
        check(r["meshes"][0]["used"] == 1 and r["meshes"][1]["used"] == 2,
              "libgomp loaded first, MIXOCT_TEST_BUSY=%s: threads=0 ran with %d "
              "(1 expected), threads=2 with %d (2)"
              % (busy, r["meshes"][0]["used"], r["meshes"][1]["used"]))
        same_meshes(r, "libgomp loaded first, load limit on")
else:
    print("skip libgomp loaded first: libgomp.so.1 not found")

print("%s" % ("all passed" if not failures else "%d failed" % failures))
sys.exit(1 if failures else 0)
