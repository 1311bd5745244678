#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds, runs every ctest test under a
# virtual X server (Debian's pvbatch/pvserver need one).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$top/.ci/build"
cd "$top/build"
xvfb-run -a -s "-screen 0 1280x1024x24" ctest --output-on-failure --timeout 600 "$@"
