#!/bin/bash
# Issue 6's measurements on the 2-core machine, in this order: floor_runs,
# backends, scaling (extract(), then extract_into(), then one process per thread count),
# peers. Run from the repository root with a Release build in build/ and nothing else
# running; outputs go to the directory given. SCALING_FLOOR=0 skips the streaming floor (and
# so fl_sp) in the two interleaved thread runs, as the thirteenth session ran them;
# BACKENDS_WARMUP=1 gives the CPU vs OpenCL run one warm-up call, as the thirteenth to
# fifteenth sessions ran it (default 3).
set -euo pipefail
out=${1:?usage: bench/measure_targets.sh OUTDIR}
scaling_floor=()
[[ "${SCALING_FLOOR:-1}" == 0 ]] && scaling_floor=(--no-floor)
backends_warmup=${BACKENDS_WARMUP:-3}
mkdir -p "$out"
bench=build/bench/voxmesh-bench
git rev-parse --short HEAD > "$out/commit.txt"
uptime > "$out/uptime.txt"
: > "$out/floor_runs.txt"
for run in 1 2 3; do
  echo "### run $run extract()" >> "$out/floor_runs.txt"
  $bench --field sphere --type f32,u8 --sizes 512 --threads 2 --repeat 9 --warmup 1 -q >> "$out/floor_runs.txt"
  echo "### run $run extract_into()" >> "$out/floor_runs.txt"
  $bench --field sphere --type f32,u8 --sizes 512 --threads 2 --repeat 9 --warmup 1 --reuse-mesh -q >> "$out/floor_runs.txt"
done
# Three warm-up calls by default: on PoCL a process's first few calls can take twice the
# steady time (bench/NOTES.md, fifteenth session).
$bench --field sphere,gyroid --type f32,u8 --sizes 256,512 --threads 2 --backends cpu,opencl,hybrid --interleave \
  --repeat 7 --warmup "$backends_warmup" -q > "$out/backends.txt"
# With the streaming floor on, its fl_sp column (and ceil, a compute-only loop) give what the
# machine itself gains from each thread count, beside the engine's speed-up.
$bench --field sphere,gyroid --type f32,u8 --sizes 256,512 --threads 1,2,4,6,16 --interleave --repeat 7 \
  "${scaling_floor[@]}" -q > "$out/scaling.txt"
$bench --field sphere,gyroid --type f32,u8 --sizes 256,512 --threads 1,2,4,6,16 --interleave --repeat 7 \
  "${scaling_floor[@]}" --reuse-mesh -q > "$out/scaling_into.txt"
# Each thread count in its own process, alternating 1 and 2 five times per volume: every call
# follows a call with the same thread count (in --interleave, the first multi-threaded call
# after a one-thread call pays for the output pages glibc gave back in between).
: > "$out/scaling_steady.txt"
for field in sphere gyroid; do for type in f32 u8; do for size in 256 512; do
  for round in 1 2 3 4 5; do for threads in 1 2; do
    $bench --field $field --type $type --sizes $size --threads $threads --repeat 9 --warmup 2 --no-floor -q \
      | grep -E "^$field " | sed "s/\$/  round $round/" >> "$out/scaling_steady.txt"
  done; done
done; done; done
: > "$out/peers.txt"
for spec in sphere:f32:256 sphere:f32:512 gyroid:f32:256 gyroid:f32:512 sphere:u8:256 sphere:u8:512 \
            gyroid:u8:256 gyroid:u8:512 ct:i16:256 ct:i16:512; do
  field=${spec%%:*}; rest=${spec#*:}; type=${rest%%:*}; size=${rest#*:}
  $bench --field "$field" --type "$type" --sizes "$size" --write-volume /tmp/v.nrrd > /dev/null
  /usr/bin/python3 bench/peers/peers.py /tmp/v.nrrd --threads 2 --repeat 5 --bench $bench --tools voxmesh,py,fe \
    --fe-scaling >> "$out/peers.txt"
done
rm -f /tmp/v.nrrd
uptime >> "$out/uptime.txt"
echo finished >> "$out/uptime.txt"
