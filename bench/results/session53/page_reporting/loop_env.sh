#!/bin/bash
# extract() again and again in one process (voxmesh-bench, 2 threads, 15 calls after 2 warm-up
# calls), with VOXMESH_HUGE_PAGES on and off in turn, twice: what the knob costs a program that
# meshes repeatedly, whose output pages the heap hands back to it hot.
set -euo pipefail
for round in 1 2; do
  for pages in on off; do
    for field in "sphere --type u8" "ct --type i16"; do
      printf 'round %d huge pages %-3s ' "$round" "$pages"
      # shellcheck disable=SC2086
      VOXMESH_HUGE_PAGES=$pages build/bench/voxmesh-bench --field $field --sizes 512 --threads 2 --repeat 15 \
        --warmup 2 --no-floor -q | grep -E '^(sphere|ct) '
    done
  done
done
