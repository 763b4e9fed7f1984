// Vertex positions are floats: a grid whose origin or last sample along an axis lies beyond
// ±FLT_MAX would mesh to inf coordinates. extract(), the volume readers and voxelize refuse
// such grids, each with a message of its own, through this one test.
#pragma once

#include <array>
#include <cfloat>
#include <cmath>
#include <cstddef>

namespace voxmesh::detail {

// The position of sample n - 1 along one axis (the origin for n <= 1).
inline double last_sample_at(double origin, double spacing, std::size_t n) {
    return origin + static_cast<double>(n > 1 ? n - 1 : 0) * spacing;
}

// The first axis whose origin or last sample lies beyond ±FLT_MAX (or is not finite); -1 when
// every sample's position fits a float.
inline int axis_beyond_float(const std::array<std::size_t, 3>& dims, const std::array<double, 3>& spacing,
                             const std::array<double, 3>& origin) {
    for (int a = 0; a < 3; ++a)
        if (!(std::fabs(origin[a]) <= FLT_MAX && std::fabs(last_sample_at(origin[a], spacing[a], dims[a])) <= FLT_MAX))
            return a;
    return -1;
}

}  // namespace voxmesh::detail
