// Volumes the sculpting tests (CPU and OpenCL) edit: two balls, high inside, and the sample
// types with the scale, offset and iso that put the balls' surface inside each type's range;
// and the random brush ops and strengths of their dabs.
#pragma once

#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <random>

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

// A random brush op: add 40 %, subtract 30 %, smooth 20 %, set 10 %.
inline voxmesh::BrushOp random_op(std::mt19937& rng) {
    using voxmesh::BrushOp;
    const int op = static_cast<int>(std::uniform_real_distribution<double>(0, 1)(rng) * 10);
    return op < 4 ? BrushOp::Add : op < 7 ? BrushOp::Subtract : op < 9 ? BrushOp::Smooth : BrushOp::Set;
}

// A random strength for dab.op; a set dab gets a value around the surface (scale, offset of
// the type) and a radius of at most set_radius.
inline void random_strength(voxmesh::Dab& dab, std::mt19937& rng, double scale, double offset, double set_radius) {
    using voxmesh::BrushOp;
    std::uniform_real_distribution<double> u01(0, 1);
    switch (dab.op) {
        case BrushOp::Add:
        case BrushOp::Subtract: dab.strength = 0.3 + 2.5 * u01(rng); break;
        case BrushOp::Smooth: dab.strength = 0.2 + 0.8 * u01(rng); break;
        case BrushOp::Set:
            dab.radius = std::min(dab.radius, set_radius);
            dab.strength = offset + scale * (u01(rng) * 6 - 3.1);
            break;
    }
}

}  // namespace sculpt_test
