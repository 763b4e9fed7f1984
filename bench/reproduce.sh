#!/bin/sh
# Reruns every measurement in bench/RESULTS.md and writes the raw outputs and plots to OUT.
#   cmake -S . -B build-bench -DVOXMESH_WERROR=ON && cmake --build build-bench -j2
#   bench/reproduce.sh [BUILD_DIR] [OUT]        (defaults: build-bench, bench-out)
# Takes ~25 minutes on 2 cores and ~2 GB of /tmp for the 512^3 volume files.
set -eu
BUILD=${1:-build-bench}
OUT=${2:-bench-out}
REPEAT=${REPEAT:-5}
THREADS=${THREADS:-2}
TOOLS=${TOOLS:-voxmesh,fe,mc,skimage}   # peers to time; TOOLS=voxmesh,fe skips the slow ones
BENCH="$BUILD/bench/voxmesh-bench"
HERE=$(dirname "$0")
TMP=${TMPDIR:-/tmp}/voxmesh-peers.$$
mkdir -p "$OUT" "$TMP"
trap 'rm -rf "$TMP"' EXIT

# 1. Table 1 of the paper (sphere f32, 64..512 x 1,2,4,6,16 threads).
"$BENCH" --paper --repeat "$REPEAT" --save "$OUT/paper.jsonl" > "$OUT/paper.txt"

# 2. CPU vs OpenCL (PoCL on this CPU) vs hybrid, and thread scaling; --interleave: an
#    input's combinations take turns run by run, so their ratios see the same phases.
"$BENCH" --field sphere,gyroid --type f32,u8 --sizes 256,512 --threads "$THREADS" --backends cpu,opencl,hybrid \
    --repeat "$REPEAT" --interleave --save "$OUT/backends.jsonl" > "$OUT/backends.txt"
"$BENCH" --field sphere,gyroid --type f32,u8 --sizes 256,512 --threads 1,2,4,6,16 --repeat "$REPEAT" \
    --interleave --no-floor --save "$OUT/scaling.jsonl" > "$OUT/scaling.txt"

# 2b. Memory: one extract per fresh process (over%: beyond the mesh, in % of volume + mesh),
#     set-up included (memory.txt) and after set-up (--setup-first: one untimed extract loads
#     the OpenCL runtime and compiles every kernel launch, then what the engines keep is freed;
#     memory_after_setup.txt).
: > "$OUT/memory.txt"
: > "$OUT/memory_after_setup.txt"
for field in sphere gyroid; do for type in f32 u8; do for backend in cpu opencl; do
    "$BENCH" --field "$field" --type "$type" --sizes 512 --threads "$THREADS" --backends "$backend" \
        --repeat 1 --warmup 0 --no-floor -q >> "$OUT/memory.txt"
    "$BENCH" --field "$field" --type "$type" --sizes 512 --threads "$THREADS" --backends "$backend" \
        --repeat 1 --warmup 0 --no-floor -q --setup-first >> "$OUT/memory_after_setup.txt"
done; done; done

# 3. Peers on the very same samples: vtkFlyingEdges3D, vtkMarchingCubes, scikit-image.
: > "$OUT/peers.txt"
for spec in sphere:f32:256 sphere:f32:512 gyroid:f32:256 gyroid:f32:512 sphere:u8:256 sphere:u8:512 \
            gyroid:u8:256 gyroid:u8:512 ct:i16:256 ct:i16:512; do
    field=${spec%%:*}; rest=${spec#*:}; type=${rest%%:*}; size=${rest#*:}
    file="$TMP/${field}_${type}_${size}.nrrd"
    "$BENCH" --field "$field" --type "$type" --sizes "$size" --write-volume "$file"
    /usr/bin/python3 "$HERE/peers/peers.py" "$file" --threads "$THREADS" --repeat "$REPEAT" --bench "$BENCH" \
        --tools "$TOOLS" --fe-scaling >> "$OUT/peers.txt" || echo "(peers reported a mismatch for $spec)" >> "$OUT/peers.txt"
    echo >> "$OUT/peers.txt"
    rm -f "$file"
done

# 4. Plots.
/usr/bin/python3 "$HERE/plot.py" "$OUT/paper.jsonl" --out "$OUT/plots" --prefix paper_
/usr/bin/python3 "$HERE/plot.py" "$OUT/backends.jsonl" --out "$OUT/plots" --prefix backends_
