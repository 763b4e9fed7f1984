// Volumes the sculpting tests (CPU and OpenCL) edit: two balls, high inside, and the sample
// types with the scale, offset and iso that put the balls' surface inside each type's range.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>

namespace sculpt_test {

using Dims = std::array<std::size_t, 3>;

// value = radius - distance (in samples) to the nearer of two balls, scaled and offset.
inline std::function<double(double, double, double)> balls(Dims d, double scale, double offset) {
    const double cx = 0.5 * double(d[0] - 1), cy = 0.5 * double(d[1] - 1), cz = 0.5 * double(d[2] - 1);
    const double r = 0.3 * double(std::min({d[0], d[1], d[2]}));
    return [=](double x, double y, double z) {
        const double a = r - std::sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz));
        const double b = 0.4 * r - std::sqrt((x - cx - 0.8 * r) * (x - cx - 0.8 * r) + (y - cy) * (y - cy) +
                                             (z - cz + 0.7 * r) * (z - cz + 0.7 * r));
        return offset + scale * std::max(a, b);
    };
}

struct TypeSetup {
    voxmesh::ScalarType type;
    double scale, offset, iso;
};
inline constexpr TypeSetup kTypes[] = {
    {voxmesh::ScalarType::F32, 1.0, 0.0, 0.0},
    {voxmesh::ScalarType::U8, 20.0, 128.0, 127.5},
    {voxmesh::ScalarType::U16, 900.0, 30000.0, 30000.5},
};

}  // namespace sculpt_test
