#!/bin/bash
# Why extract() on 2 threads had a slow mode on this VM (bench/NOTES.md, fifty-fourth session).
#   LIB=path/to/libvoxmesh.a built with one_sizer.patch applied (AB_ONE_SIZER=1: the output
#   arrays are sized by the calling thread alone; unset: as the library does, on 2 workers)
#   bash run.sh > run.txt
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(git -C "$here" rev-parse --show-toplevel)
g++ -O2 -std=c++20 -I"$repo/include" "$here/calls.cpp" "$LIB" -lOpenCL -lz -lpthread -o /tmp/voxmesh-calls
g++ -O2 -pthread "$here/pcp.cpp" -o /tmp/voxmesh-pcp
echo "# fresh huge pages faulted on one CPU after being freed on the same or the other (ms per round)"
for i in 1 2 3; do for c in "0 0" "1 1" "1 0" "0 1"; do /tmp/voxmesh-pcp $c; done; done
echo "# extract() calls on 2 threads: seconds per call (calls 2..12 sorted), two sizers then one"
for vol in "s f" "s u" "g f"; do for round in 1 2 3; do for m in two one; do
  if [ $m = one ]; then export AB_ONE_SIZER=1; else unset AB_ONE_SIZER; fi
  echo "$vol round $round $m: $(/tmp/voxmesh-calls 2 12 x $vol | awk '{print $3}' | tail -11 | sort -n | tr '\n' ' ')"
done; done; done
unset AB_ONE_SIZER
echo "# one process, per call (2 threads, sphere f32 512^3, two sizers)"
/tmp/voxmesh-calls 2 14 x s f
echo "# the same, one thread"
/tmp/voxmesh-calls 1 10 x s f
echo "# the same into one kept mesh (extract_into), 2 threads"
/tmp/voxmesh-calls 2 10 r s f
