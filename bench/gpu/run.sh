#!/bin/bash
# Runs on a lent GPU machine (see prepare.sh), from the repository root: finds the NVIDIA
# OpenCL driver, measures the copy bandwidth and CPU / OpenCL / Hybrid (each engine at the SAME
# thread counts: Options::threads also sets how many host threads fill and empty the pinned
# copy blocks), with fresh meshes and with one reused, then thread scaling, then runs the whole
# test suite there. Each step runs under a timeout (SIGINT makes voxmesh-bench print what it
# finished); the limits add up to 570 s, one device call (the forty-third session's run took
# 170 s, 110 of them the suite). Outputs go to $OUT (or bench/gpu/out): eight files, the most
# the device tool brings back.
set -uo pipefail
out=${OUT:-bench/gpu/out}
mkdir -p "$out"
export LD_LIBRARY_PATH=$PWD/.gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
driver=$(ls /usr/local/nvidia/lib64/libnvidia-opencl.so* /usr/lib/x86_64-linux-gnu/libnvidia-opencl.so* 2>/dev/null | head -1)
if [ -n "$driver" ]; then
  mkdir -p /tmp/vendors && echo "$driver" > /tmp/vendors/nvidia.icd
  export OCL_ICD_VENDORS=/tmp/vendors
fi
# The tests find their data under /work/main, the CLI under build/src/cli and the benchmark under build/bench.
mkdir -p /work && [ -e /work/main ] || ln -s "$PWD" /work/main
mkdir -p build/src/cli build/bench && cp .gpu/voxmesh build/src/cli/ && cp .gpu/voxmesh-bench build/bench/
bench=.gpu/voxmesh-bench
{
  cat .gpu/commit.txt; nproc; grep -m1 'model name' /proc/cpuinfo; nvidia-smi -L 2>&1 | head -3
  # Whether CPUs 0 and 1 share a core (2-thread scaling read 1.45-1.73 there, forty-third session).
  lscpu 2>&1 | grep -iE 'thread|core|socket|numa|mhz'; grep . /sys/devices/system/cpu/cpu[01]/topology/thread_siblings_list
  $bench --list-devices
} > "$out/machine.txt" 2>&1
timeout 30 .gpu/voxmesh-cl-bandwidth > "$out/cl_bandwidth.txt" 2>&1
# Sizing fresh and reused result arrays on one thread and on all (array_sizing.hpp), beside the
# copies: both are what a fresh mesh costs on this machine.
timeout 30 .gpu/voxmesh-array-sizing --repeat 9 40 240 >> "$out/cl_bandwidth.txt" 2>&1
threads=$(nproc)
timeout -s INT -k 10 120 $bench --field sphere,gyroid,ct --type f32,u8 --sizes 256,512 --threads 2,"$threads" --backends cpu,opencl,hybrid \
  --interleave --repeat 7 --warmup 1 --setup-first --save "$out/backends.jsonl" > "$out/backends.txt" 2>&1
# The same with one Mesh per combination (extract_into), as a sculpting loop: a fresh mesh's pages
# cost the H200 machine about half of a dense call (thirty-sixth session).
timeout -s INT -k 10 90 $bench --field sphere,gyroid,ct --type f32,u8 --sizes 256,512 --threads 2,"$threads" --backends cpu,opencl,hybrid \
  --interleave --repeat 7 --warmup 1 --setup-first --reuse-mesh --save "$out/backends_reuse.jsonl" > "$out/backends_reuse.txt" 2>&1
timeout -s INT -k 10 60 $bench --field sphere,gyroid --type f32,u8 --sizes 256,512 --threads 1,2,"$threads" --interleave --repeat 7 \
  --no-floor --reuse-mesh > "$out/scaling_into.txt" 2>&1
# Two threads on two chosen CPUs: beside ceil (a dependent chain, which hyperthreads of one core
# hide) and ceil_w (a core's full issue width, which they share), whether CPUs 0 and 1 are one
# core's two threads and whether another pair scales better.
for cpus in 0,1 0,$((threads / 2)); do
  echo "### taskset -c $cpus" >> "$out/scaling_into.txt"
  timeout -s INT -k 10 25 taskset -c "$cpus" $bench --field sphere,gyroid --type u8 --sizes 512 --threads 1,2 --interleave \
    --repeat 7 --no-floor --reuse-mesh >> "$out/scaling_into.txt" 2>&1
done
# The whole suite last: the comparisons matter most when device time runs short.
timeout 190 .gpu/voxmesh_tests > "$out/tests.txt" 2>&1; echo "voxmesh_tests exit $?" >> "$out/tests.txt"
tail -2 "$out/tests.txt"
