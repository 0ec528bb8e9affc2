#!/usr/bin/env bash
# libFuzzer runs of the readers (tests/fuzz): builds the fuzz targets with clang-14 (fuzzer, address,
# undefined) in ./build-fuzz (or $BUILD_DIR), then runs each for SECONDS, one after the other.
#   bash tools/fuzz.sh              30 s per target (CI)
#   bash tools/fuzz.sh 300 fuzz_ply 5 minutes, one target
#   JOBS=1 bash tools/fuzz.sh 300   build one job at a time (a shared, loaded machine)
# Seeds: tests/fuzz/seeds/<kind>, tests/data (bad corpus, events, sequences), and the corpus grown by earlier
# runs in $BUILD_DIR/corpus/<target>. A finding is saved as $BUILD_DIR/artifacts/<target>/crash-* (or leak-,
# timeout-, oom-) and the script exits 1 after the remaining targets ran: reproduce with
# `$BUILD_DIR/tests/fuzz/<target> <file>` and add the file to tests/data/bad with its expected outcome.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build-fuzz}
SECONDS_PER_TARGET=${1:-30}
shift || true
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(fuzz_obj fuzz_ply fuzz_events)

CXX=${CXX:-clang++-14} cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DTOPOTRACK_FUZZ=ON -DTOPOTRACK_SANITIZE=address,undefined \
  -DTOPOTRACK_BUILD_BENCH=OFF >/dev/null
build_targets=("${targets[@]}")
[[ $# -gt 0 ]] || build_targets=(fuzz_all)  # all three side by side (tests/fuzz/CMakeLists.txt)
cmake --build "$BUILD_DIR" -j"${JOBS:-$(nproc)}" --target "${build_targets[@]}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
for t in "${targets[@]}"; do
  case "$t" in
    fuzz_obj) kind=obj; from=(tests/data/bad/*.obj tests/data/sequences/*/*.obj) ;;
    fuzz_ply) kind=ply; from=(tests/data/bad/*.ply tests/data/sequences/*/*.ply) ;;
    fuzz_events) kind=events; from=(tests/data/events/*) ;;
    *) echo "fuzz.sh: unknown target $t" >&2; exit 2 ;;
  esac
  corpus=$BUILD_DIR/corpus/$t seeds=$BUILD_DIR/seeds/$t artifacts=$BUILD_DIR/artifacts/$t
  mkdir -p "$corpus" "$seeds" "$artifacts"
  cp -f tests/fuzz/seeds/$kind/* "${from[@]}" "$seeds/"
  dict=()
  [[ -f tests/fuzz/$kind.dict ]] && dict=(-dict=tests/fuzz/$kind.dict)
  echo "== $t: ${SECONDS_PER_TARGET}s"
  if ! "$BUILD_DIR/tests/fuzz/$t" "$corpus" "$seeds" "${dict[@]}" -max_total_time="$SECONDS_PER_TARGET" \
      -timeout=10 -rss_limit_mb=2048 -max_len=16384 -artifact_prefix="$artifacts/" -print_final_stats=1 \
      2>"$BUILD_DIR/$t.log"; then
    status=1
    echo "fuzz.sh: $t found a failure, see $BUILD_DIR/$t.log and $artifacts/" >&2
    grep -E "ERROR|runtime error|broken promise|Test unit written" "$BUILD_DIR/$t.log" | head -5 >&2 || true
  fi
  # Coverage at the start and the end of the run (cov: edges covered, ft: features, corp: units/bytes).
  grep -E "^#[0-9]+[[:space:]]+(INITED|DONE)" "$BUILD_DIR/$t.log" || true
  grep -E "^stat::(number_of_executed_units|average_exec_per_sec|new_units_added|peak_rss_mb)" \
    "$BUILD_DIR/$t.log" || true
done
exit $status
