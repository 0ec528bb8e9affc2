#!/usr/bin/env bash
# A checker stuck to a splash (§5, Fig. 5): a drop falls into a pool, merges, throws up a crown whose rim sheds
# droplets that fall back, then a jet that sheds a drop (`topotrack gen splash`: a dozen splits and merges),
# tracked (Algorithm 1), a 3D checker applied in frame 1 and carried forward through the event lists (§4.6),
# rendered as one strip of frames from the drop's fall to the jet: docs/images/splash_checker.png.
#
#   bash tools/splash.sh            # after tools/build.sh (or BUILD_DIR=... / BIN=path/to/topotrack)
#   OUT=out/splash FRAMES=60 TILES=6 TILE=200 IMAGE=docs/images/splash_checker.png bash tools/splash.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-${BUILD_DIR:-build}/tools/topotrack}
OUT=${OUT:-out/splash}
FRAMES=${FRAMES:-60}
TILES=${TILES:-6}
TILE=${TILE:-200}
IMAGE=${IMAGE:-docs/images/splash_checker.png}
if [[ ! -x "$BIN" ]]; then
  echo "splash.sh: no topotrack binary at $BIN (run tools/build.sh, or set BIN)" >&2
  exit 1
fi
"$BIN" gen splash -o "$OUT/input" --frames "$FRAMES" --progress quiet
"$BIN" track "$OUT/input" -o "$OUT/tracked" --progress lines
"$BIN" propagate "$OUT/tracked" --source checker -o "$OUT/textured" --quiet
"$BIN" render "$OUT/textured" -o "$OUT/pictures" --sheet "$TILES" --sheet-columns "$TILES" --sheet-size "$TILE" \
  --up z --elevation 25 --no-frames --quiet
mkdir -p "$(dirname "$IMAGE")"
cp "$OUT/pictures/contact_sheet.png" "$IMAGE"
echo "splash.sh: $IMAGE ($(stat -c %s "$IMAGE") bytes); frames in $OUT/textured, track statistics in $OUT/tracked/track.json"
