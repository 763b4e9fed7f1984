#!/usr/bin/python3
"""Times voxmesh.edge_cell_ranges over every crossed edge of a float32 gyroid (period 64
samples; 1.27 M edges at 256³), median of 9 calls, three rounds: the thirty-fifth session's A/B
of NaN checks in that pass (bench/NOTES.md). For an A/B, run it against two builds of the
library in turn (VOXMESH_LIBRARY names the libvoxmesh_c to load):

    PYTHONPATH=build/python /usr/bin/python3 bench/peers/edge_ranges.py 256 --threads 2
"""

import argparse
import statistics
import time

import numpy as np
import voxmesh


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("size", type=int, nargs="?", default=256, help="cube size (default 256)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    n = args.size
    z, y, x = np.mgrid[:n, :n, :n].astype(np.float32) * np.float32(2 * np.pi / 64)
    gyroid = (np.sin(x) * np.cos(y) + np.sin(y) * np.cos(z) + np.sin(z) * np.cos(x)).astype(np.float32)
    edges = voxmesh.vertex_edges(gyroid, 0.0)
    for _ in range(args.rounds):
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            voxmesh.edge_cell_ranges(gyroid, edges, offset=0.0, threads=args.threads)
            times.append(time.perf_counter() - t0)
        print(f"gyroid f32 {n}³ edge_cell_ranges {len(edges):9d} edges  median {statistics.median(times) * 1e3:6.2f} ms")


if __name__ == "__main__":
    main()
