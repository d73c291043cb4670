#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to a passing test suite:
# installs the dependencies and data, builds, and runs every test with ctest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
# Every optional part (OpenGL, Python, tests) is required here: a missing
# package fails the configure instead of leaving tests out.
bash "$root/scripts/build.sh" -DPRT_REQUIRE_ALL=ON
cd "$root/build"
rm -rf Testing/reference-cache  # every reference traced anew (tests/CMakeLists.txt)
# The documented long blocks (label `long`: 80 minutes) run with `ctest -L long`.
ctest --output-on-failure --parallel "$(nproc)" --timeout 900 -LE long
