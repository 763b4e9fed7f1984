"""Data kept per sample carried onto the mesh: each vertex takes the label of the sample at the
inside end of its edge (voxmesh.vertex_edges), and the surface splits into one piece per label.

    PYTHONPATH=<prefix>/lib/python3.N/dist-packages python3 examples/label_vertices.py [out-prefix]

Two overlapping balls are meshed as one surface; a label volume says which ball each sample is
nearer the inside of. Exits 0 only when each label's triangles have the area of its ball's
outside part (the sphere less the cap inside the other) to within 1 %; with out-prefix, writes
out-prefix-1.ply and out-prefix-2.ply."""
import sys

import numpy as np

import voxmesh

n, radius, half_gap = 96, 20.0, 15.0
z, y, x = np.mgrid[:n, :n, :n].astype(np.float64)  # arrays are indexed [z, y, x]
first = radius - np.sqrt((x - 47.5 + half_gap) ** 2 + (y - 47.3) ** 2 + (z - 47.6) ** 2)
second = radius - np.sqrt((x - 47.5 - half_gap) ** 2 + (y - 47.3) ** 2 + (z - 47.6) ** 2)
volume = np.maximum(first, second).astype(np.float32)  # the union, positive inside
labels = np.where(first >= second, 1, 2).astype(np.uint8)

mesh = voxmesh.extract(volume, iso=0.0)
sample, axis = np.divmod(voxmesh.vertex_edges(volume, 0.0, count=mesh.vertex_count), 3)
far = sample + np.array([1, n, n * n], dtype=np.uint64)[axis]  # the edge's other end
flat = volume.ravel()
inside = np.where(flat[sample] >= 0.0, sample, far)  # the end inside the surface
vertex_label = labels.ravel()[inside]

corners = mesh.positions.astype(np.float64)[mesh.indices]
areas = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
triangle_label = np.where((vertex_label[mesh.indices] == 2).sum(axis=1) >= 2, 2, 1)  # its corners' majority
cap = 2 * np.pi * radius * (radius - half_gap)  # each ball's part inside the other
expected = 4 * np.pi * radius ** 2 - cap
ok = True
for label in (1, 2):
    chosen = triangle_label == label
    area = areas[chosen].sum()
    ok &= abs(area / expected - 1) < 0.01
    print(f"label {label}: {np.count_nonzero(vertex_label == label)} vertices, {np.count_nonzero(chosen)} "
          f"triangles, area {area:.1f} (analytic {expected:.1f})")
    if len(sys.argv) > 1:
        used = np.unique(mesh.indices[chosen])
        renumber = np.zeros(mesh.vertex_count, dtype=np.uint32)
        renumber[used] = np.arange(len(used), dtype=np.uint32)
        piece = voxmesh.Mesh.from_arrays(mesh.positions[used], renumber[mesh.indices[chosen]])
        piece.write(f"{sys.argv[1]}-{label}.ply")
sys.exit(0 if ok else 1)
