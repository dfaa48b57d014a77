#!/usr/bin/env bash
# Installs the already-built library from BUILD_DIR into a temporary prefix and builds
# examples/consumer against it with find_package(slam_mms), as a user would (ctest consumer_build):
#  1. the SDK alone: find_package(slam_mms) must not look for the components' dependencies (OpenCV,
#     Embree, PROJ, yaml-cpp, nlohmann-json are disabled for the configure), the consumer must not
#     load them at run time, and it runs MappingSystem on synthetic frames;
#  2. the io and eval components: find_package(slam_mms COMPONENTS io eval).
set -euo pipefail
build_dir=$1
src_dir=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build_dir" --prefix "$tmp/prefix" > "$tmp/install.log"

disabled=()
for p in OpenCV embree PROJ yaml-cpp nlohmann_json; do disabled+=("-DCMAKE_DISABLE_FIND_PACKAGE_$p=ON"); done
if ! cmake -S "$src_dir/examples/consumer" -B "$tmp/sdk" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  -DCMAKE_BUILD_TYPE=Release "${disabled[@]}" > "$tmp/sdk_configure.log" 2>&1; then
  cat "$tmp/sdk_configure.log"
  echo "test_consumer: find_package(slam_mms) (the SDK alone) failed to configure" >&2
  exit 1
fi
cmake --build "$tmp/sdk" -j2 > "$tmp/sdk_build.log" 2>&1 || { cat "$tmp/sdk_build.log"; exit 1; }
if ldd "$tmp/sdk/consumer" | grep -E 'opencv|embree|libproj|yaml-cpp|gdal'; then
  echo "test_consumer: the SDK consumer loads a component's library (above)" >&2
  exit 1
fi
"$tmp/sdk/consumer"

cmake -S "$src_dir/examples/consumer" -B "$tmp/components" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  -DCMAKE_BUILD_TYPE=Release -DSLAM_MMS_CONSUMER_COMPONENTS=ON > "$tmp/components_configure.log" 2>&1 \
  || { cat "$tmp/components_configure.log"; exit 1; }
cmake --build "$tmp/components" -j2 --target consumer_components > "$tmp/components_build.log" 2>&1 \
  || { cat "$tmp/components_build.log"; exit 1; }
"$tmp/components/consumer_components"
