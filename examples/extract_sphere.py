"""The Python package: a numpy sphere meshed on every core, checked closed, written as PLY.

    PYTHONPATH=<prefix>/lib/python3.N/dist-packages python3 examples/extract_sphere.py [out.ply]

Exits 0 only when the mesh is a closed surface with Euler characteristic 2 whose enclosed
volume is within 1 % of the sphere's."""
import sys
import time

import numpy as np

import voxmesh

n, radius = 128, 40.0
z, y, x = np.mgrid[:n, :n, :n]  # arrays are indexed [z, y, x]; x varies fastest
volume = (radius - np.sqrt((x - 63.5) ** 2 + (y - 63.5) ** 2 + (z - 63.5) ** 2)).astype(np.float32)

start = time.perf_counter()
mesh = voxmesh.extract(volume, iso=0.0, spacing=(0.5, 0.5, 0.5))
seconds = time.perf_counter() - start

edges = np.sort(np.concatenate([mesh.indices[:, [0, 1]], mesh.indices[:, [1, 2]], mesh.indices[:, [2, 0]]]), axis=1)
_, uses = np.unique(edges[:, 0].astype(np.uint64) << np.uint64(32) | edges[:, 1], return_counts=True)
euler = mesh.vertex_count - len(uses) + mesh.triangle_count
corners = mesh.positions.astype(np.float64)[mesh.indices]
enclosed = np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum() / 6
expected = 4 / 3 * np.pi * (radius * 0.5) ** 3
print(f"voxmesh {voxmesh.version()}: {mesh.vertex_count} vertices, {mesh.triangle_count} triangles "
      f"in {seconds * 1e3:.1f} ms; closed {bool(np.all(uses == 2))}, euler {euler}, "
      f"volume {enclosed:.1f} (sphere {expected:.1f})")
if len(sys.argv) > 1:
    mesh.write(sys.argv[1])
sys.exit(0 if np.all(uses == 2) and euler == 2 and abs(enclosed / expected - 1) < 0.01 else 1)
