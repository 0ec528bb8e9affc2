#!/usr/bin/env bash
# The README's main command: install dependencies, build in Release, then run the main job on the bundled
# default: generate the Stam-Schmidt blobs sequence (one full turn), track it, stick a checker texture to
# frame 1, carry it through the sequence and render a contact sheet of the result.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
BIN=${BUILD_DIR:-build}/tools/topotrack
OUT=${OUT:-out/demo}
FRAMES=${FRAMES:-100}
"$BIN" gen blobs -o "$OUT/input" --frames "$FRAMES"
"$BIN" info "$OUT/input/blobs.0001.ply"
"$BIN" track "$OUT/input" -o "$OUT/tracked" --progress lines
"$BIN" eval "$OUT/tracked" --input "$OUT/input" --ground-truth "$OUT/input/ground_truth.json" -o "$OUT/eval.json" --plots "$OUT/plots"
"$BIN" propagate "$OUT/tracked" --source checker -o "$OUT/textured" --quiet
"$BIN" render "$OUT/textured" -o "$OUT/pictures" --sheet 6 --no-frames --quiet
echo "demo: pictures in $OUT/pictures, tracked frames in $OUT/tracked, evaluation in $OUT/eval.json"
