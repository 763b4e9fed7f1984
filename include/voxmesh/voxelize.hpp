// Triangle mesh -> volume: surface and interior, threaded over rows.
//
// Grid: the longest side of the mesh's bounding box gets `resolution` cubic voxels (spacing
// h = longest side / resolution) with one sample at each voxel centre; the other axes get
// as many voxels as cover their side, centred on the box. `padding` samples are added on
// every side. origin and spacing of the result are set so that meshing it back
// (voxmesh::extract) lands in the model's own coordinates.
//
// Inside test (the documented rule): even-odd parity of the crossings of a ray along +x.
// The mesh is snapped to a fixed-point lattice of 2^-16 voxel (vertices move by at most
// 2^-17 voxel) and crossings are decided with exact integer predicates and symbolic
// perturbation of the ray, so rays that pass exactly through vertices or along edges
// count every surface crossing exactly once: no streaks. Parity does not depend on the
// triangles' orientation, so inconsistently wound meshes voxelize correctly.
//
// Input rules: the mesh is welded by exact position first (unwelded STL soup is fine);
// triangles with a repeated vertex are ignored; then every edge must belong to exactly two
// triangles. Open meshes (holes) and non-manifold edges are rejected with voxmesh::Error.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstddef>

namespace voxmesh {

enum class VoxelField {
    Occupancy,  // u8: 255 where the sample is inside, 0 outside; mesh it back at iso 127.5
    Distance,   // f32 signed Euclidean distance in model units, positive inside, negative
                // outside; mesh it back at iso 0 (the default inside = value >= iso gives
                // outward normals). Exact within `band` voxels of the surface, clamped to
                // +-band*h farther away, and to +-FLT_MAX (models spanning most of the float range).
};

struct VoxelizeOptions {
    std::size_t resolution = 128;  // voxels along the longest side of the bounding box (2..4096)
    std::size_t padding = 2;       // extra samples outside the box on every side (0..256); 0 lets
                                   // the surface touch the border, so its mesh is open there
    VoxelField field = VoxelField::Distance;
    double band = 3;               // Distance: exact within this many voxels (>= 2)
    unsigned threads = 0;          // 0 = all cores; the result does not depend on it
};

// `mesh` must be closed (every edge in two triangles); open or non-manifold input, an empty
// mesh, non-finite positions or out-of-range indices are rejected with Error. So are, before
// anything large is allocated, a grid whose bytes exceed the machine's physical memory
// (sysconf(_SC_PHYS_PAGES) * page size) and a grid with samples beyond the range of float
// (a model near +-3.4e38 plus padding), which extract() could not mesh, and triangle row
// lists (each triangle once per z row it spans) that would not fit beside the grid. A model
// with no sample inside it (flat, or thinner than a voxel everywhere) is an Error too: its
// volume would mesh back to nothing.
Volume voxelize(const Mesh& mesh, const VoxelizeOptions& options);

}  // namespace voxmesh
