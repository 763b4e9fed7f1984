// Vertex positions are floats: a grid whose origin or last sample along an axis lies beyond
// ±FLT_MAX would mesh to inf coordinates. extract(), the volume readers and voxelize refuse
// such grids, each with a message of its own, through this one test. A spacing too fine for
// floats at the grid's distance from 0 is only warned about (the mesh is right, but coarse).
#pragma once

#include <algorithm>
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

// The larger magnitude of an axis's first and last sample positions.
inline double farthest_from_zero(double origin, double spacing, std::size_t n) {
    return std::max(std::fabs(origin), std::fabs(last_sample_at(origin, spacing, n)));
}

// Float's step near `far`: an upper bound on the gap between neighbouring floats there.
inline double float_step_near(double far) { return std::max(std::fabs(far) * 0x1p-23, 0x1p-149); }

// The first axis (with 2 or more samples) whose spacing float coordinates resolve poorly:
// fewer than 256 float values between neighbouring samples somewhere on the grid, so
// vertices snap to a coarse lattice (a large origin, a tiny spacing); -1 when none.
inline int axis_too_fine_for_float(const std::array<std::size_t, 3>& dims, const std::array<double, 3>& spacing,
                                   const std::array<double, 3>& origin) {
    for (int a = 0; a < 3; ++a) {
        if (dims[a] < 2) continue;
        if (spacing[a] < 256 * float_step_near(farthest_from_zero(origin[a], spacing[a], dims[a]))) return a;
    }
    return -1;
}

}  // namespace voxmesh::detail
