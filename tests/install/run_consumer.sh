#!/usr/bin/env bash
# Installs the built project into a temporary prefix, then configures, builds and runs the embedding example
# (docs/examples/embed) against it.
set -euo pipefail
build_dir=$1; source_dir=$2; work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
cmake -S "$source_dir/docs/examples/embed" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/build" -j2 >/dev/null
"$work/build/consumer"
