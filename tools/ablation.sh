#!/usr/bin/env bash
# The ablations of the paper's §6 (Fig. 8 and 9), issue 8: the full pipeline against projection only, no fine
# alignment, no coarse alignment and no topology constraint, each tracked from the same inputs and measured by
# `topotrack eval`. Writes OUT/ablation.md (the tables of docs/results.md) and every run's track/eval output.
#   bash tools/ablation.sh [OUT]      (default out/ablation; FRAMES=100 BLOBS_RES=0 METABALL_FRAMES=60 SAMBA_FRAMES=30)
# Expects a built tree (bash tools/build.sh); takes ~1 h on 2 cores at the default sizes.
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

# run NAME INPUT GT FLAGS...: track INPUT with FLAGS into OUT/NAME, evaluate, append a table row.
table_started=0
run() {
  local name=$1 input=$2 gt=$3
  shift 3
  "$BIN" track "$input" -o "$OUT/$name" --progress lines "$@" >"$OUT/$name.log" 2>&1 || {
    echo "| $name | track failed (exit $?), see $name.log | | | | | | | |" >>"$MD.tmp"; return 0; }
  local gtflag=()
  [ -n "$gt" ] && gtflag=(--ground-truth "$gt")
  "$BIN" eval "$OUT/$name" --input "$input" "${gtflag[@]}" -o "$OUT/$name.eval.json" --quiet \
      --markdown "${*:-full pipeline}" >"$OUT/$name.row"
  if [ $table_started = 0 ]; then head -2 "$OUT/$name.row" >>"$MD.tmp"; table_started=1; fi
  tail -1 "$OUT/$name.row" >>"$MD.tmp"
}
section() { printf '\n### %s\n\n' "$1" >>"$MD.tmp"; table_started=0; }

section "Blobs, one full turn in $FRAMES frames (ground truth: the analytic rotation)"
"$BIN" gen blobs -o "$OUT/blobs" --frames "$FRAMES" --progress quiet
for flags in "" "--no-fine" "--no-coarse" "--no-topology" "--projection-only"; do
  # shellcheck disable=SC2086
  run "blobs${flags:+_${flags#--}}" "$OUT/blobs" "$OUT/blobs/ground_truth.json" $flags
done

section "Metaballs, $METABALL_FRAMES frames: blobs that split and merge (topology changes)"
"$BIN" gen metaballs -o "$OUT/metaballs" --frames "$METABALL_FRAMES" --progress quiet
for flags in "" "--no-topology" "--projection-only"; do
  # shellcheck disable=SC2086
  run "metaballs${flags:+_${flags#--}}" "$OUT/metaballs" "" $flags
done

if [ -d "$SHARED/samba" ]; then
  section "Resurfaced samba, $SAMBA_FRAMES frames (ground truth: the coherent capture)"
  "$BIN" gen resurface "$SHARED/samba" -o "$OUT/samba" --frames "$SAMBA_FRAMES" --progress quiet
  for flags in "" "--no-fine" "--projection-only"; do
    # shellcheck disable=SC2086
    run "samba${flags:+_${flags#--}}" "$OUT/samba" "$OUT/samba/ground_truth" $flags
  done
fi

{ echo "Commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $(nproc) cores, command: bash tools/ablation.sh"
  cat "$MD.tmp"; } >"$MD"
rm -f "$MD.tmp"
echo "ablation: $MD"
