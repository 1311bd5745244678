#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds, runs every ctest test under a
# virtual X server (Debian's pvbatch/pvserver need one).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$top/.ci/build"
cd "$top/build"
bash "$top/.ci/with-xvfb" ctest --output-on-failure --timeout 600 "$@"
