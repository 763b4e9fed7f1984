"""Times each of N voxmesh.extract() calls (2 threads) on one volume file in one process, in ms.

    PYTHONPATH=build/python /usr/bin/python3 py_calls.py /tmp/ct512.nrrd 12
"""
import sys
import time

import voxmesh

volume = voxmesh.read_volume(sys.argv[1])
times = []
for _ in range(int(sys.argv[2])):
    start = time.perf_counter()
    voxmesh.extract(volume, 400.5, threads=2)
    times.append(time.perf_counter() - start)
print(" ".join(f"{t * 1000:.1f}" for t in times))
