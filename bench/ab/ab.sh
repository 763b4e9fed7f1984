#!/bin/bash
# In-process A/B timing of voxmesh builds (see ab_main.cpp for why).
#   bench/ab/ab.sh FIELD TYPE SIZE THREADS ROUNDS REV...
# REV is a git revision or "." for the working tree. Each is built position-independent in
# $AB_DIR (default /tmp/voxmesh-ab; revisions are git worktrees there: `rm -rf` it, then
# `git worktree prune`) and wrapped as a shared object; then voxmesh-ab runs.
# AB_BACKEND=opencl times the OpenCL engine, AB_BACKEND=cpu,opencl both (default: cpu);
# AB_REUSE=1 meshes into one kept Mesh per build (extract_into), AB_NORMALS=0 without normals,
# AB_PAUSE_MS=N sleeps after calls.
set -euo pipefail
if [ $# -lt 6 ]; then sed -n 2,7p "$0"; exit 2; fi
field=$1 type=$2 size=$3 threads=$4 rounds=$5; shift 5
repo=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
work=${AB_DIR:-/tmp/voxmesh-ab}
mkdir -p "$work"
libs=()
for rev in "$@"; do
  if [ "$rev" = . ]; then src=$repo name=worktree
  else
    name=$(git -C "$repo" rev-parse --short "$rev")
    src=$work/src-$name
    [ -d "$src" ] || git -C "$repo" worktree add -f --detach "$src" "$rev" >/dev/null
  fi
  cmake -S "$src" -B "$work/build-$name" -DCMAKE_BUILD_TYPE=Release -DCMAKE_POSITION_INDEPENDENT_CODE=ON \
        -DVOXMESH_BUILD_TESTS=OFF >/dev/null
  cmake --build "$work/build-$name" -j"$(nproc)" --target voxmesh >/dev/null
  lib=$(find "$work/build-$name" -name libvoxmesh.a | head -1)
  libs+=("$work/$name.so")
  extra=()
  if grep -q 'VOXMESH_WITH_OPENCL:BOOL=ON' "$work/build-$name/CMakeCache.txt" 2>/dev/null; then extra=(-lOpenCL); fi
  g++ -shared -o "$work/$name.so" -Wl,--whole-archive "$lib" -Wl,--no-whole-archive "${extra[@]}" -lz -lpthread
done
cmake -S "$repo" -B "$work/build-tool" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/build-tool" --target voxmesh_ab >/dev/null
"$work/build-tool/bench/voxmesh-ab" "$field" "$type" "$size" "$threads" "$rounds" "${libs[@]}"
