"""The demo's printed stages add up to its total: runs the command after "--" (mpiexec ...
pvbatch apc_demo.py ...), and for every "frame N on the display rank: <stage> <s> s, ...,
total <s> s" line it prints, checks that the stages sum to the total to the printed precision
(half a unit of the last digit per number). Prints APC-TEST-PASSED or APC-TEST-FAILED.

    TestDemoStages.py -- <command...>
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from apc_command import run_after_dashdash  # noqa: E402


def main(argv):
    run, output = run_after_dashdash(argv)
    print(output)
    failures = []
    frames = [line for line in output.splitlines() if "on the display rank:" in line]
    if run.returncode != 0:
        failures.append("the demo exited with %d" % run.returncode)
    if not frames:
        failures.append("the demo printed no frame")
    for line in frames:
        numbers = dict((name, float(value)) for name, value in
                       re.findall(r"([a-z_0-9]+) ([0-9.]+) s\b", line.split(";")[0]))
        total = numbers.pop("total", None)
        if total is None:
            failures.append("no total in: %s" % line)
            continue
        half = 0.0005  # the demo prints milliseconds
        tolerance = half * (len(numbers) + 1) + 1e-9
        stages = sum(numbers.values())
        print("stages %s sum to %.4f s, total %.4f s" % (sorted(numbers), stages, total))
        if abs(stages - total) > tolerance:
            failures.append("the stages sum to %.4f s, the total is %.4f s" % (stages, total))
    for failure in failures:
        print("check failed:", failure)
    print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
