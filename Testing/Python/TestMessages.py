"""Counts what a pvbatch run says: runs the command after "--" (mpiexec ... pvbatch
messages_scene.py --case NAME), captures everything every rank prints, and checks the
expectations the scene states on its own output, one per line:

    APC-EXPECT <min> <max> <python regex>

each meaning "between min and max lines of the whole output (all ranks, stdout and stderr)
match regex" (the APC-EXPECT lines themselves are not counted). The scene's own verdict
(APC-TEST-PASSED / APC-TEST-FAILED) must be PASSED too. Prints APC-MESSAGES-PASSED or
APC-MESSAGES-FAILED (not the scene's words, which ctest would take for this verdict).

    TestMessages.py -- <command...>
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from apc_command import run_after_dashdash  # noqa: E402


def main(argv):
    run, output = run_after_dashdash(argv)
    lines = output.splitlines()
    expectations = []
    others = []
    for line in lines:
        found = re.search(r"APC-EXPECT (\d+) (\d+) (.*)$", line)
        if found:
            expectations.append((int(found.group(1)), int(found.group(2)), found.group(3)))
        else:
            others.append(line)
    print("\n".join(others))
    failures = []
    if run.returncode != 0:
        failures.append("the run exited with %d" % run.returncode)
    if "APC-TEST-PASSED" not in output or "APC-TEST-FAILED" in output:
        failures.append("the scene's own checks did not pass")
    if not expectations:
        failures.append("the scene stated no expectation")
    for low, high, pattern in expectations:
        count = sum(1 for line in others if re.search(pattern, line))
        verdict = "ok" if low <= count <= high else "WRONG"
        print("expect %d..%d lines matching %r: %d (%s)" % (low, high, pattern, count, verdict))
        if verdict != "ok":
            failures.append("%d lines match %r (expected %d..%d)" % (count, pattern, low, high))
    for failure in failures:
        print("check failed:", failure)
    print("APC-MESSAGES-FAILED" if failures else "APC-MESSAGES-PASSED")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
