#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer run of the test suite (gcc, -O1, own build folder).
#   scripts/test_sanitizers.sh                     # every test (consumer_build excepted, see below)
#   scripts/test_sanitizers.sh -R io_              # extra arguments go to ctest
#   SANITIZER_MODULES="core io backend" scripts/test_sanitizers.sh
#                                                  # only these modules' tests (label = module),
#                                                  # building only their test executables (CI)
# Env: BUILD_DIR (build-asan), JOBS (2), SANITIZER_EXCLUDE (ctest -E regex; default: consumer_build),
#      SANITIZER_MODULES (default: all).
# consumer_build is left out: it links an unsanitized find_package() consumer against the
# sanitized static libraries, which cannot link without the ASan runtime; it tests packaging,
# which scripts/test.sh covers. Leak reports are on; scripts/sanitizers/lsan.supp suppresses only
# the leak Mesa's EGL/DRI driver makes at exit. Any ASan, UBSan or LSan report fails the test.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build-asan}
JOBS=${JOBS:-2}
SANITIZER_EXCLUDE=${SANITIZER_EXCLUDE:-^consumer_build$}

scripts/install_deps.sh
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DSLAM_MMS_SANITIZE=ON -DSLAM_MMS_BUILD_BENCHMARKS=OFF ${CMAKE_ARGS:-}
ctest_args=()
if [[ -n "${SANITIZER_MODULES:-}" ]]; then
  targets=()
  for m in $SANITIZER_MODULES; do
    for t in tests/"$m"/*_test.cpp; do
      [[ -e "$t" ]] && targets+=("${m}_$(basename "$t" .cpp)")
    done
  done
  cmake --build "$BUILD_DIR" -j"$JOBS" --target "${targets[@]}"
  ctest_args+=(-L "^($(echo $SANITIZER_MODULES | tr ' ' '|'))\$")
else
  cmake --build "$BUILD_DIR" -j"$JOBS"
fi

supp="$PWD/scripts/sanitizers/lsan.supp"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1:strict_init_order=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
cd "$BUILD_DIR"
ctest -j"$JOBS" --output-on-failure --timeout 1800 -E "$SANITIZER_EXCLUDE" "${ctest_args[@]}" "$@"
