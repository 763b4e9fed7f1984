#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan) in their own build directory and runs
# each for a bounded time on a scratch copy of its seed corpus (tests/fuzz_corpus/<target>).
# Exits non-zero when any target finds a crash, sanitizer report, leak or timeout; the
# reproducer is left in $BUILD/artifacts/.
#
#   fuzz/run.sh                 # every target, 30 s each
#   FUZZ_SECONDS=300 fuzz/run.sh nifti stl
# Environment: FUZZ_SECONDS (default 30), FUZZ_BUILD_DIR (default build-fuzz),
# FUZZ_JOBS (build parallelism, default 2), CXX_FUZZ (default clang++).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${FUZZ_BUILD_DIR:-$root/build-fuzz}
seconds=${FUZZ_SECONDS:-30}
jobs=${FUZZ_JOBS:-2}
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(nrrd metaimage nifti vtk npy stl ply obj strokes voxelize extract nrrd_roundtrip mesh_roundtrip components)

cmake -S "$root/fuzz" -B "$build" -DCMAKE_CXX_COMPILER="${CXX_FUZZ:-clang++}" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" -j"$jobs" --target $(printf 'fuzz_%s ' "${targets[@]}")

status=0
mkdir -p "$build/artifacts"
for t in "${targets[@]}"; do
  work="$build/corpus/$t"
  mkdir -p "$work"
  dict=()
  [ -f "$root/fuzz/$t.dict" ] && dict=(-dict="$root/fuzz/$t.dict")
  echo "== fuzz_$t for ${seconds}s"
  # New inputs go to the scratch corpus (first dir); the seeds in tests/ are only read.
  if ! "$build/fuzz_$t" "${dict[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
        -max_len=65536 -print_final_stats=1 -artifact_prefix="$build/artifacts/$t-" \
        "$work" "$root/tests/fuzz_corpus/$t" 2>"$build/fuzz_$t.log"; then
    echo "fuzz_$t FAILED; log: $build/fuzz_$t.log" >&2
    tail -n 40 "$build/fuzz_$t.log" >&2
    status=1
  else
    grep -E '^stat::number_of_executed_units|^Done' "$build/fuzz_$t.log" || true
  fi
done
exit $status
