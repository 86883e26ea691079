#!/usr/bin/env bash
# Packs the CUDA build's test and benchmark binaries with every shared library they need
# except the C library's, and the peer packing, into one archive for a GPU machine that has
# CUDA's driver but no package registry (README, "GPU builds"):
#
#   perf/gpu_pack_build.sh ARCHIVE.tar.xz        (about 19 MB)
#
# On the GPU machine: tar -xJf ARCHIVE -C DIR; export LD_LIBRARY_PATH=DIR/lib; then
# perf/gpu_walls_and_suite.sh DIR OUT_DIR from the repository's root.
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
archive=$(realpath -m "$1")
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/bin" "$stage/lib" "$stage/data"
cp "$repo"/build-cuda/bin/{granular_tests,bench_dem_throughput} "$stage/bin/"
strip --strip-debug "$stage"/bin/*
for b in "$stage"/bin/*; do ldd "$b" | awk '/=> \// {print $3}'; done | sort -u |
  grep -v -E '/(libc|libm|libdl|librt|libpthread|ld-linux[^/]*)\.so' |
  while read -r l; do cp -L "$l" "$stage/lib/"; done
cp "$repo/perf/peer/data/packing_32768.data" "$stage/data/"
tar -C "$stage" -cJf "$archive" bin lib data
ls -la "$archive"
