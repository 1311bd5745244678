#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds, runs every ctest test under a
# virtual X server (Debian's pvbatch/pvserver need one), then the sanitizer job
# (.ci/sanitizers: the core and the mapper's tests under ASan and UBSan, in build-asan).
# Arguments go to ctest and select tests; the sanitizer job runs only with the whole suite
# (no arguments), and APC_SANITIZERS=0 skips it.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$top/.ci/build"
cd "$top/build"
bash "$top/.ci/with-xvfb" ctest --output-on-failure --timeout 600 "$@"
if [ $# -eq 0 ] && [ "${APC_SANITIZERS:-1}" != 0 ]; then
  bash "$top/.ci/sanitizers"
fi
