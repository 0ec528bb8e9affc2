#!/usr/bin/env bash
# The ablations of the paper's §6 (Fig. 8 and 9), issue 8: the full pipeline against projection only, no fine
# alignment and no topology constraint, each tracked from the same inputs and measured by
# `topotrack eval`. Writes OUT/ablation.md (the tables of docs/results.md) and every run's track/eval output.
#   bash tools/ablation.sh [OUT]      (default out/ablation; sizes: FRAMES=100 METABALL_FRAMES=60 SAMBA_FRAMES=30)
# Expects a built tree (bash tools/build.sh); takes ~5 min on 2 idle cores at the default sizes (3878a88).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BUILD_DIR:-build}/tools/topotrack
OUT=${1:-out/ablation}
FRAMES=${FRAMES:-100}
METABALL_FRAMES=${METABALL_FRAMES:-60}
SAMBA_FRAMES=${SAMBA_FRAMES:-30}
SHARED=${SHARED:-../shared/data}
mkdir -p "$OUT"
MD="$OUT/ablation.md"
: > "$MD.tmp"

# run NAME INPUT GT VARIANT: track INPUT with VARIANT into OUT/NAME (never the input folder: the tracked frames
# carry the input's name), evaluate, append a table row.
table_started=0
# VARIANT is full or a `track` flag without its dashes (no-fine, no-topology, projection-only).
run() {
  local name=$1 input=$2 gt=$3 variant=$4 flags=()
  [ "$variant" = full ] || flags=("--$variant")
  "$BIN" track "$input" -o "$OUT/$name" --progress lines "${flags[@]}" >"$OUT/$name.log" 2>&1 || {
    echo "| $name | track failed (exit $?), see $name.log | | | | | | | |" >>"$MD.tmp"; return 0; }
  local gtflag=()
  [ -n "$gt" ] && gtflag=(--ground-truth "$gt")
  "$BIN" eval "$OUT/$name" --input "$input" "${gtflag[@]}" -o "$OUT/$name.eval.json" --quiet \
      --markdown "$variant" >"$OUT/$name.row"
  if [ $table_started = 0 ]; then head -2 "$OUT/$name.row" >>"$MD.tmp"; table_started=1; fi
  tail -1 "$OUT/$name.row" >>"$MD.tmp"
}
section() { printf '\n### %s\n\n' "$1" >>"$MD.tmp"; table_started=0; }

section "Blobs, one full turn in $FRAMES frames (ground truth: the analytic rotation)"
"$BIN" gen blobs -o "$OUT/input_blobs" --frames "$FRAMES" --progress quiet
for variant in full no-fine no-topology projection-only; do
  run "blobs_$variant" "$OUT/input_blobs" "$OUT/input_blobs/ground_truth.json" $variant
done

section "Metaballs, $METABALL_FRAMES frames: blobs that split and merge (topology changes)"
"$BIN" gen metaballs -o "$OUT/input_metaballs" --frames "$METABALL_FRAMES" --progress quiet
for variant in full no-topology; do
  run "metaballs_$variant" "$OUT/input_metaballs" "" $variant
done

if [ -d "$SHARED/samba" ]; then
  section "Resurfaced samba, $SAMBA_FRAMES frames (ground truth: the coherent capture)"
  "$BIN" gen resurface "$SHARED/samba" -o "$OUT/input_samba" --frames "$SAMBA_FRAMES" --progress quiet
  for variant in full projection-only; do
    run "samba_$variant" "$OUT/input_samba" "$OUT/input_samba/ground_truth" $variant
  done
fi

{ echo "Commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(nproc) cores, command: bash tools/ablation.sh"
  cat "$MD.tmp"; } >"$MD"
rm -f "$MD.tmp"
echo "ablation: $MD"
