#!/usr/bin/env bash
# Installs the already-built library from BUILD_DIR into a temporary prefix and builds
# examples/consumer against it with find_package(slam_mms). Called by ctest (test consumer_build).
set -euo pipefail
build_dir=$1
src_dir=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build_dir" --prefix "$tmp/prefix" > "$tmp/install.log"
cmake -S "$src_dir/examples/consumer" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  -DCMAKE_BUILD_TYPE=Release > "$tmp/configure.log"
cmake --build "$tmp/build" -j2 > "$tmp/build.log"
"$tmp/build/consumer"
