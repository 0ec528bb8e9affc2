#!/usr/bin/env bash
# Issue 4's accuracy sums: frame k onto k + 15 for k = 1, 3, 5, 7, 9 at two re-samplings of the target (0.79 and
# 0.81 of its mean edge length), per model the ten ground-truth errors (% of the diagonal) and their sum, as
# docs/results.md quotes them ("ten-run sums"). Needs ../shared/data and a built tree (bash tools/build.sh).
#   bash tools/large_motion_sums.sh [Elephant Pcow Samba]
# Extra settings pass through the test's environment, e.g. TOPOTRACK_TEST_RELAX_ITERATIONS=0 (no relaxation).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BUILD_DIR:-build}/tests/kernels/registration/registration_real_data_test
[ -x "$BIN" ] || { echo "large_motion_sums: no $BIN (build first: bash tools/build.sh)" >&2; exit 2; }
models=("$@")
[ ${#models[@]} -gt 0 ] || models=(Elephant Pcow Samba)
for model in "${models[@]}"; do
  values=()
  for k in 1 3 5 7 9; do
    for factor in 0.79 0.81; do
      line=$(TOPOTRACK_TEST_FRAME=$k TOPOTRACK_TEST_EDGE_FACTOR=$factor "$BIN" \
        --gtest_filter="RealData.${model}LargeMotion" 2>/dev/null | grep -o 'median [0-9.]*' || true)
      [ -n "$line" ] || { echo "large_motion_sums: no result for $model frame $k at $factor" >&2; exit 1; }
      values+=("${line#median }")
    done
  done
  printf '%s sum %s: %s\n' "$model" "$(printf '%s\n' "${values[@]}" | awk '{s += $1} END {printf "%.4f", s}')" "${values[*]}"
done
