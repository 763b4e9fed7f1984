#!/bin/bash
# The thread cache's placement and spin (src/core/parallel.cpp, nineteenth session) against
# the same tree with parallel.cpp as it was before them (413ad4e), with and without a pause
# before each call (voxmesh-bench --pause, as a program meshing once a frame). Run from the
# repository root with a Release build in build/ and nothing else running:
#   bash bench/results/session19/pause_ab.sh OUTDIR
set -euo pipefail
out=${1:?usage: pause_ab.sh OUTDIR}
mkdir -p "$out"
old=${PAUSE_AB_OLD:-/tmp/voxmesh-pause-old}
if [ ! -x "$old/build/bench/voxmesh-bench" ]; then
  rm -rf "$old"
  git worktree prune
  git worktree add -f --detach "$old" HEAD >/dev/null
  git -C "$old" checkout 413ad4e -- src/core/parallel.cpp
  cmake -S "$old" -B "$old/build" -DCMAKE_BUILD_TYPE=Release -DVOXMESH_BUILD_TESTS=OFF >/dev/null
  cmake --build "$old/build" --target voxmesh_bench -j"$(nproc)" >/dev/null
fi
declare -A bench=([old]="$old/build/bench/voxmesh-bench" [new]=build/bench/voxmesh-bench)
git rev-parse --short HEAD > "$out/commit.txt"
uptime > "$out/uptime.txt"
for pause in 0 10; do
  for build in old new new old; do
    "${bench[$build]}" --field sphere,gyroid --type f32,u8 --sizes 256,512 --threads 1,2 --interleave --repeat 9 \
      --warmup 2 --pause "$pause" --reuse-mesh -q --json >> "$out/scaling_pause${pause}_$build.jsonl"
  done
done
for pause in 0 16; do
  for build in old new new old; do
    "${bench[$build]}" --sculpt --sizes 256,512 --threads 2 --dabs 200 --pause "$pause" -q --json \
      >> "$out/sculpt_pause${pause}_$build.jsonl"
  done
done
