// Small volumes for the per-vertex and per-triangle queries' tests (vertex_edges,
// triangle_cells): random samples of every type whose iso values fall on samples and between
// them, and a sphere that 8-bit samples keep.
#pragma once

#include "support/mesh_checks.hpp"

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace vmtest {

// Random values for type T: small integers for integer types, quarters and tenths for floats
// so that iso values can fall both between samples and exactly on them.
template <class T>
std::vector<T> random_volume(const Dims& dims, std::uint32_t seed) {
    if constexpr (std::is_integral_v<T>) {
        const int lo = std::is_signed_v<T> ? -6 : 0;
        return vmtest::random_field<T>(dims, seed, lo, lo + 12);
    } else {
        const std::vector<double> d = vmtest::random_doubles(dims, seed, -20, 20);
        std::vector<T> out(d.size());
        for (std::size_t i = 0; i < d.size(); ++i) out[i] = static_cast<T>(d[i] * 0.25 + ((i % 5 == 0) ? 0.1 : 0.0));
        return out;
    }
}

// A sphere of radius 8 in 24^3, scaled and shifted so that 8-bit samples keep its shape.
template <class T>
std::vector<T> sphere_volume(const Dims& dims) {
    const vmtest::FieldFn f = vmtest::sphere({11.3, 12.1, 11.7}, 8.0);
    return vmtest::sample_field<T>(dims, [f](double x, double y, double z) { return 100.0 + 10.0 * f(x, y, z); });
}

// iso values for a volume: exactly some samples' values, and between samples.
template <class T>
std::vector<double> iso_values(const std::vector<T>& data) {
    std::vector<double> isos;
    for (std::size_t k : {std::size_t{3}, data.size() / 2, data.size() - 1}) {
        const double v = static_cast<double>(data[k]);
        isos.push_back(v);          // exactly a sample's value
        isos.push_back(v + 0.5);    // between samples
        isos.push_back(v - 0.125);  // between samples
    }
    return isos;
}

}  // namespace vmtest
