#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer build of the library, the CLI and the tests (no benchmarks)
# in ./build-asan (or $BUILD_DIR), then the test suite under the sanitizers; any finding fails the run.
#   bash tools/sanitize.sh            everything but the `slow` label and install.consumer
#   bash tools/sanitize.sh --all      also the `slow` label
#   bash tools/sanitize.sh --quick    only io_test, mesh_test, sdf_test (target sanitize_quick: the readers, the half-edge mesh, signed
#                                     distance and marching cubes): the part that fits in CI (docs/robustness.md)
#   bash tools/sanitize.sh -R regex   only the matching tests (passed to ctest)
# install.consumer is never run here: it installs the package and builds an unsanitized consumer against it.
# Debug info is line tables only (-g1): enough for file:line in every report, 17% less compile time than -g.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build-asan}
SANITIZE=${SANITIZE:-address,undefined}
JOBS=${JOBS:-$(nproc)}  # build and ctest parallelism (JOBS=1 on a shared, loaded machine)
exclude='slow|install'
targets=()
args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --all) exclude='install'; shift ;;
    --quick) targets=(sanitize_quick); exclude='slow|install|cli'; shift ;;
    *) args+=("$1"); shift ;;
  esac
done

cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DTOPOTRACK_SANITIZE="$SANITIZE" -DTOPOTRACK_BUILD_BENCH=OFF >/dev/null
if [[ ${#targets[@]} -gt 0 ]]; then
  cmake --build "$BUILD_DIR" -j"$JOBS" --target "${targets[@]}"
  args+=(-E '_NOT_BUILT$')  # the test executables not built here
else
  cmake --build "$BUILD_DIR" -j"$JOBS"
fi

# Findings are fatal (halt_on_error, -fno-sanitize-recover) and print a stack; leaks are findings too.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
cd "$BUILD_DIR"
status=0
ctest --output-on-failure -j"$JOBS" --timeout 900 -LE "$exclude" "${args[@]}" || status=$?
# What makes the run long: the slowest tests of this and earlier runs (seconds under the sanitizers).
echo "slowest tests under $SANITIZE:"
# (awk stops printing after 15 itself: `| head` would close the pipe early, and under pipefail the
# resulting SIGPIPE of the writer made this script exit 141 on a machine where the race went that way.)
{ sort -k3 -g -r Testing/Temporary/CTestCostData.txt 2>/dev/null || true; } |
  awk 'NF == 3 && n < 15 {printf "  %8.1f s  %s\n", $3, $1; n++}'
exit $status
