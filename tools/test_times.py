#!/usr/bin/env python3
"""Each test's run time against its timeout, from a finished `meson test` run.

    tools/test_times.py [BUILD_DIR]     # default: build

Reads BUILD_DIR/meson-logs/testlog.json (the durations of the last run) and
`meson introspect --tests` (the timeouts), prints the tests by decreasing
duration with the share of their timeout, and exits 1 when one took more than
a third of its timeout: the margin the suite keeps so that a loaded machine
(a CI runner, a second job on one core) does not time it out (issue 25).
"""
import json
import subprocess
import sys


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else "build"
    intro = subprocess.run(["meson", "introspect", "--tests", build],
                           capture_output=True, text=True, check=True).stdout
    timeout = {t["name"]: t["timeout"] for t in json.loads(intro)}
    runs = {}
    with open(build + "/meson-logs/testlog.json") as f:
        for line in f:
            r = json.loads(line)
            runs[r["name"]] = (r["duration"], r["result"])
    over = 0
    print("%-22s %9s %8s %6s  %s" % ("test", "seconds", "timeout", "share", "result"))
    for name, (d, res) in sorted(runs.items(), key=lambda x: -x[1][0]):
        t = timeout.get(name) or 0
        share = d / t if t > 0 else 0.0
        flag = "  over a third" if share > 1 / 3 else ""
        over += share > 1 / 3
        print("%-22s %9.2f %8d %5.0f%%  %s%s" % (name, d, t, 100 * share, res, flag))
    print("%d test(s), %d over a third of their timeout" % (len(runs), over))
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
