// Triangle mesh -> volume: surface and interior, threaded over rows.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstddef>

namespace voxmesh {

enum class VoxelField {
    Occupancy,  // u8: 255 inside, 0 outside; mesh it back at iso 127.5
    Distance,   // f32 signed distance, positive inside, negative outside; mesh it back at iso 0
};

struct VoxelizeOptions {
    std::size_t resolution = 128;  // samples along the longest side of the bounding box
    std::size_t padding = 2;       // extra samples outside the box on every side
    VoxelField field = VoxelField::Distance;
    unsigned threads = 0;          // 0 = all cores
};

// `mesh` must be closed (every edge in two triangles); open input is rejected with Error.
Volume voxelize(const Mesh& mesh, const VoxelizeOptions& options);

}  // namespace voxmesh
