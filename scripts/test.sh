#!/usr/bin/env bash
# Installs the Debian packages slam_mms needs, builds it (Release, -j2) and runs the whole test suite
# through ctest, including the find_package(slam_mms) consumer build.
#   scripts/test.sh                 # everything
#   BUILD_DIR=build-x scripts/test.sh -R lie   # extra arguments go to ctest
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-2}

scripts/install_deps.sh
# Tests, apps and benchmarks named explicitly: a build/ configured earlier with other values (an
# older scripts/demo.sh turned tests off) must not leave the suite empty.
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSLAM_MMS_BUILD_TESTS=ON \
  -DSLAM_MMS_BUILD_EXAMPLES=ON -DSLAM_MMS_BUILD_BENCHMARKS=ON ${CMAKE_ARGS:-}
cmake --build "$BUILD_DIR" -j"$JOBS"
cd "$BUILD_DIR"
ctest -j"$JOBS" --output-on-failure --timeout 900 "$@"
