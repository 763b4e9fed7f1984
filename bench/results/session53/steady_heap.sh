#!/bin/bash
# measure_targets.sh's scaling_steady (each thread count in a process of its own, extract(),
# 9 calls after 2 warm-up calls) in three rounds, each volume and thread count run twice in a
# row: as glibc comes, and with glibc keeping what is freed (no trimming, no mmap'd blocks), so
# that extract()'s output does not come back from the kernel as fresh pages on every call.
set -euo pipefail
keep=GLIBC_TUNABLES=glibc.malloc.trim_threshold=4294967295:glibc.malloc.mmap_threshold=4294967295
for field in sphere gyroid; do for type in f32 u8; do for size in 256 512; do
  for round in 1 2 3; do for threads in 1 2; do for heap in default keep; do
    env=(X=1); [[ $heap == keep ]] && env=("$keep")
    env "${env[@]}" build/bench/voxmesh-bench --field $field --type $type --sizes $size --threads $threads \
      --repeat 9 --warmup 2 --no-floor -q | grep -E "^$field " | sed "s/\$/  round $round heap $heap/"
  done; done; done
done; done; done
