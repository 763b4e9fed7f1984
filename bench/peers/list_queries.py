#!/usr/bin/python3
"""Times voxmesh.vertex_edges and voxmesh.triangle_cells (count given, as the scikit-image
drop-in calls them) on a sparse sphere and a dense gyroid, float32, median of 5 calls each.
The gyroid here is denser than voxmesh-bench's (2.6 M vertices at 256³). Run with the build's
package on the path:

    PYTHONPATH=build/python /usr/bin/python3 bench/peers/list_queries.py 256 --threads 2
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
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    n = args.size
    z, y, x = np.mgrid[:n, :n, :n].astype(np.float32)
    gyroid = (np.sin(x * 0.2) * np.cos(y * 0.2) + np.sin(y * 0.2) * np.cos(z * 0.2) +
              np.sin(z * 0.2) * np.cos(x * 0.2)).astype(np.float32)
    c = (n - 1) / 2
    sphere = (0.4 * n - np.sqrt((x - c) ** 2 + (y - c) ** 2 + (z - c) ** 2)).astype(np.float32)
    for name, volume in (("gyroid", gyroid), ("sphere", sphere)):
        mesh = voxmesh.extract(volume, 0.0, threads=args.threads)
        for query, count in ((voxmesh.vertex_edges, mesh.vertex_count), (voxmesh.triangle_cells, mesh.triangle_count)):
            times = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                query(volume, 0.0, threads=args.threads, count=count)
                times.append(time.perf_counter() - t0)
            print(f"{name} f32 {n}³ {query.__name__:15} {count:9d} entries  median {statistics.median(times) * 1e3:6.1f} ms")


if __name__ == "__main__":
    main()
