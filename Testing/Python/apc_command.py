"""What the drivers that check a command's printed words share: run the command given after
"--" and return its output (stdout and stderr together) without the ANSI colours of VTK's
logger, which would split words."""

import re
import subprocess


def run_after_dashdash(argv, timeout=600):
    command = argv[argv.index("--") + 1:]
    run = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         timeout=timeout)
    return run, re.sub(r"\x1b\[[0-9;]*m", "", run.stdout)
