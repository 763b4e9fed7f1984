#!/usr/bin/env bash
# The main job: installs dependencies, builds, and meshes a built-in volume on CPU threads
# and on OpenCL, printing the comparison. Extra arguments go to `voxmesh demo`, which takes none
# but --help.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j"$(nproc)" --target voxmesh_cli > /dev/null
./build/src/cli/voxmesh demo "$@"
