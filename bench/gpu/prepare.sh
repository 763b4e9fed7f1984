#!/bin/bash
# Puts what a lent GPU machine needs into .gpu/ (ignored by git; pass it to the device tool's
# `carry`): the Release binaries built here and Debian's OpenCL ICD loader, since nothing can
# be installed there. Then, on the GPU machine, from the repository root:
#   bash bench/gpu/run.sh            (results under $OUT, or bench/gpu/out when $OUT is unset)
set -euo pipefail
repo=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
cd "$repo"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j"$(nproc)" --target voxmesh_tests voxmesh_bench voxmesh_cli voxmesh_cl_bandwidth \
  voxmesh_array_sizing > /dev/null
rm -rf .gpu && mkdir -p .gpu/lib
cp build/tests/voxmesh_tests build/bench/voxmesh-bench build/bench/voxmesh-cl-bandwidth build/bench/voxmesh-array-sizing \
  build/src/cli/voxmesh .gpu/
cp -P /usr/lib/x86_64-linux-gnu/libOpenCL.so.1* build/src/capi/libvoxmesh_c.so.0.1* .gpu/lib/  # the tests link the C API
grep -qx '/.gpu/' .git/info/exclude 2>/dev/null || echo '/.gpu/' >> .git/info/exclude
git rev-parse --short HEAD > .gpu/commit.txt
du -sh .gpu
