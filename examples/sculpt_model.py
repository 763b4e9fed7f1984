"""The paper's loop from Python: a closed STL model voxelized into a sculpt, brush dabs along a
path across its surface, each followed by an update that re-meshes only the blocks it reached.

    PYTHONPATH=<prefix>/lib/python3.N/dist-packages python3 examples/sculpt_model.py model.stl [out.ply]

Prints each update's latency and blocks, then checks that the sculpted surface is still closed
with the model's Euler characteristic and that the welded mesh is extract()'s of the edited
samples; exits 0 only when it is."""
import sys

import numpy as np

import voxmesh

if len(sys.argv) < 2:
    sys.exit("usage: sculpt_model.py model.stl [out.ply]")
model = voxmesh.read_mesh(sys.argv[1])
# padding: room around the model for material added on top (past it the volume's border would
# cut the surface open).
sculpt = voxmesh.Sculpt.from_mesh(model, resolution=96, padding=6, block_size=16)
first = sculpt.update()
before = sculpt.mesh()
print(f"{sculpt.array.shape[::-1]} samples in {sculpt.block_count} blocks; first update "
      f"{first.seconds * 1e3:.1f} ms, {before.triangle_count} triangles")

# Dabs along a line over the model's top, in model units: a ridge raised, then smoothed.
low, high = before.positions.min(axis=0), before.positions.max(axis=0)
radius = 0.08 * float((high - low).max())
latencies = []
for t in np.linspace(0.1, 0.9, 12):
    x = low[0] + t * (high[0] - low[0])
    top = before.positions[np.abs(before.positions[:, 0] - x) < radius]
    if len(top) == 0:
        continue
    peak = top[np.argmax(top[:, 2])]
    sculpt.add(peak, radius, strength=2, units="world")
    sculpt.smooth(peak, radius, strength=0.5, units="world")
    result = sculpt.update()
    latencies.append(result.seconds * 1e3)
    print(f"dab at x={x:7.3f}: {result.remeshed:3d} blocks re-meshed, {len(result.changed):3d} changed, "
          f"{result.seconds * 1e3:6.2f} ms")

after = sculpt.mesh()
topology = after.topology()
same = voxmesh.extract(sculpt.array, spacing=sculpt.spacing, origin=sculpt.origin, backend="cpu")
identical = np.array_equal(same.indices, after.indices) and np.array_equal(same.positions, after.positions)
print(f"after {len(latencies)} dabs: {after.triangle_count} triangles, median update "
      f"{np.median(latencies) if latencies else 0:.2f} ms; {topology}; extract's mesh: {identical}")
if len(sys.argv) > 2:
    after.write(sys.argv[2])
before_topology = before.topology()
ok = latencies and topology.closed and topology.euler == before_topology.euler and identical
sys.exit(0 if ok else 1)
