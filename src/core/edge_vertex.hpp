// The position and normal of the vertex on a crossed edge: the one formula every CPU-side
// mesher uses, so their vertices agree bit for bit.
//   position = origin + (index + t * axis) * spacing,  t = (iso - v0) / (v1 - v0)
//   normal   = -gradient interpolated with t, normalised (gradient: central differences,
//              one-sided at the border, divided by spacing); +gradient when inside_below.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace voxmesh::detail {

// Asks for the cache line holding p ahead of its use (a hint; nothing where unsupported).
inline void prefetch(const void* p) {
#if defined(__GNUC__)
    __builtin_prefetch(p);
#else
    (void)p;
#endif
}

// A vertex normal's fallback for a flat gradient: the axis of its edge (bits 0-1), plus
// kFlatPositive where it points along +axis.
constexpr unsigned kFlatPositive = 4;

// n / |n| where |n|^2 overflowed or lost its precision (gradients of samples near the ends of
// double's range, 1e160 or 1e-160): n scaled by its largest component has the same direction.
// The fallback where n is 0 or not finite. Out of line: the usual path stays small.
[[gnu::cold, gnu::noinline]] inline void normalise_scaled(const double n[3], unsigned flat, float* out) {
    const double m = std::max({std::abs(n[0]), std::abs(n[1]), std::abs(n[2])});
    if (m > 0 && m <= DBL_MAX) {
        const double s[3] = {n[0] / m, n[1] / m, n[2] / m};
        const double scaled2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];  // 1..3, or NaN
        if (std::isfinite(scaled2)) {
            const double inv = 1 / std::sqrt(scaled2);
            for (unsigned d = 0; d < 3; ++d) out[d] = static_cast<float>(s[d] * inv);
            return;
        }
    }
    for (unsigned d = 0; d < 3; ++d) out[d] = d == (flat & 3) ? (flat & kFlatPositive ? 1.f : -1.f) : 0.f;
}

// n / |n| in float (normalise_scaled where |n|^2 is not a normal finite number). Batched code
// (normal_batch.hpp) does the same operations lane by lane, and edge_vertex.cl the same in
// double, so every path gives the same bits.
inline void normalise_normal(const double n[3], unsigned flat, float* out) {
    const double len2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (len2 >= DBL_MIN && len2 <= DBL_MAX) [[likely]] {
        const double inv = 1 / std::sqrt(len2);
        for (unsigned d = 0; d < 3; ++d) out[d] = static_cast<float>(n[d] * inv);
        return;
    }
    normalise_scaled(n, flat, out);
}

// Normals written as they come, normalised one by one.
struct DirectNormals {
    float* next;
    void push(const double n[3], unsigned flat) {
        normalise_normal(n, flat, next);
        next += 3;
    }
};

template <class T>
class EdgeVertex {
public:
    EdgeVertex(const VolumeView& volume, double iso, bool inside_below)
        : data_(static_cast<const T*>(volume.data)),
          n_{volume.dims[0], volume.dims[1], volume.dims[2]},
          stride_{1, volume.dims[0], volume.dims[0] * volume.dims[1]},
          half_inv_spacing_{0.5 / volume.spacing[0], 0.5 / volume.spacing[1], 0.5 / volume.spacing[2]},
          inv_spacing_{1 / volume.spacing[0], 1 / volume.spacing[1], 1 / volume.spacing[2]},
          spacing_(volume.spacing),
          origin_(volume.origin),
          iso_(iso),
          sign_(inside_below ? 1.0 : -1.0),
          inside_below_(inside_below) {}

    // What the samples of row (j, k) share, computed once per row.
    struct Row {
        std::size_t j, k, base;  // base: the index of sample (0, j, k)
        double index_y, index_z;
        float on_y, on_z;        // the coordinates its vertices keep off their edge's axis
        bool interior;           // j and k away from the border (see away_from_border)
        bool ahead3, ahead2;     // planes k + 3 and k + 2 (with rows j -/+ 1) exist: prefetch them
    };

    Row row(std::size_t j, std::size_t k) const {
        Row r;
        r.j = j;
        r.k = k;
        r.base = j * stride_[1] + k * stride_[2];
        r.index_y = to_double(j);
        r.index_z = to_double(k);
        r.on_y = static_cast<float>(origin_[1] + r.index_y * spacing_[1]);
        r.on_z = static_cast<float>(origin_[2] + r.index_z * spacing_[2]);
        r.interior = away_from_border(j, n_[1]) && away_from_border(k, n_[2]);
        r.ahead3 = k + 3 < n_[2];
        r.ahead2 = k + 2 < n_[2] && j >= 1 && j + 1 < n_[1];
        return r;
    }

    // Writes the vertices of the crossed edges sample (i, j, k) owns, in axis order x, y, z:
    // bit a of `axes` set for a crossed edge along axis a, vertex v at position[3v] and
    // normal[3v]; normal may be null. The sample's own value and gradient are shared by its
    // edges.
    void sample(std::size_t i, std::size_t j, std::size_t k, unsigned axes, float* position, float* normal) const {
        DirectNormals direct{normal};
        sample(i, j, k, axes, position, normal ? &direct : nullptr);
    }

    // The same, handing each vertex's normal, not yet normalised, to normals->push(n, flat)
    // (see normalise_normal) in vertex order; normals may be null.
    template <class Normals>
    void sample(std::size_t i, std::size_t j, std::size_t k, unsigned axes, float* position, Normals* normal) const {
        sample(row(j, k), i, axes, position, normal);
    }

    // The same for sample i of a row from row(j, k): what only depends on the row is not
    // computed again per sample (the same operations, so the same bits).
    template <class Normals>
    void sample(const Row& r, std::size_t i, unsigned axes, float* position, Normals* normal) const {
        const std::size_t at0[3] = {i, r.j, r.k};
        const std::size_t idx0 = i + r.base;
        const double v0 = static_cast<double>(data_[idx0]);
        // Gradients here read neighbours one and two planes up; the first reads of a line there
        // come one plane from now (the sample three planes up, the rows beside the one two
        // planes up), long after classify evicted it: ask for them now (-20 % generate time,
        // one thread, sphere f32 512³).
        if (r.ahead3) prefetch(data_ + idx0 + 3 * stride_[2]);
        if (r.ahead2) {
            prefetch(data_ + idx0 + 2 * stride_[2] - stride_[1]);
            prefetch(data_ + idx0 + 2 * stride_[2] + stride_[1]);
        }
        // Coordinates off the edge's axis are the sample's own (index + 0 * t: the same bits).
        // Indices convert through int64_t: one instruction, where size_t takes several.
        const double index[3] = {to_double(i), r.index_y, r.index_z};
        const float on_sample[3] = {static_cast<float>(origin_[0] + index[0] * spacing_[0]), r.on_y, r.on_z};
        // Away from the border (both ends of every edge at least one sample in) the gradients
        // are plain central differences, computed without the per-axis border tests.
        const bool interior = r.interior && away_from_border(i, n_[0]);
        double g0[3] = {0, 0, 0};
        if (normal) {
            if (interior) central_gradient(idx0, g0);
            else gradient(idx0, at0, g0);
        }
        for (unsigned axis = 0; axis < 3; ++axis) {
            if (!(axes >> axis & 1)) continue;
            const std::size_t idx1 = idx0 + stride_[axis];
            const double v1 = static_cast<double>(data_[idx1]);
            const double t = on_edge(edge_t(v0, v1));
            if (normal) {
                double g1[3];
                if (interior) {
                    central_gradient(idx1, g1);
                } else {
                    std::size_t at1[3] = {i, r.j, r.k};
                    ++at1[axis];
                    gradient(idx1, at1, g1);
                }
                double n[3];
                interpolated_normal(g0, g1, t, n);
                normal->push(n, flat_normal(axis, v0 >= iso_));
            }
            for (unsigned d = 0; d < 3; ++d) position[d] = on_sample[d];
            position[axis] = static_cast<float>(origin_[axis] + (index[axis] + t) * spacing_[axis]);
            position += 3;
        }
    }

private:
    static double to_double(std::size_t p) { return static_cast<double>(static_cast<std::int64_t>(p)); }

    // (iso - v0) / (v1 - v0). Only double samples can overflow the difference (near ±DBL_MAX,
    // where it gave inf / inf = NaN): there it is taken on halves (the kernels do the same).
    double edge_t(double v0, double v1) const {
        if constexpr (std::is_same_v<T, double>) {
            const double d = v1 - v0;
            if (!std::isfinite(d)) [[unlikely]]
                return (0.5 * iso_ - 0.5 * v0) / (0.5 * v1 - 0.5 * v0);
            return (iso_ - v0) / d;
        } else {
            return (iso_ - v0) / (v1 - v0);
        }
    }

    // t kept on the edge (-0 kept), NaN to 0: only a volume written to since classify (the API
    // allows a mix of old and new samples) gives another t, e.g. 0 / 0 where both ends became
    // iso, and its vertex stays finite and on its edge. The same bits for every other t.
    static double on_edge(double t) { return t >= 0 ? (t <= 1 ? t : 1.0) : 0.0; }

    // 1 <= p and p + 1 <= n - 2: p and its +1 neighbour both have two neighbours along the axis.
    static bool away_from_border(std::size_t p, std::size_t n) { return p >= 1 && p + 3 <= n; }

    // Outward is toward decreasing values: the negated gradient (flipped for inside_below).
    void interpolated_normal(const double g0[3], const double g1[3], double t, double n[3]) const {
        for (unsigned d = 0; d < 3; ++d) n[d] = sign_ * (g0[d] + t * (g1[d] - g0[d]));
    }

    // Where the gradient is flat the normal points along the edge, from its inside end to its
    // outside end.
    unsigned flat_normal(unsigned axis, bool first_above) const {
        const bool first_inside = first_above != inside_below_;
        return axis | (first_inside ? kFlatPositive : 0u);
    }

    void central_gradient(std::size_t idx, double g[3]) const {
        for (unsigned d = 0; d < 3; ++d) {
            const std::size_t s = stride_[d];
            g[d] = (static_cast<double>(data_[idx + s]) - static_cast<double>(data_[idx - s])) * half_inv_spacing_[d];
        }
    }

    void gradient(std::size_t idx, const std::size_t at[3], double g[3]) const {
        for (unsigned d = 0; d < 3; ++d) {
            const std::size_t pos = at[d], s = stride_[d];
            const double hi = static_cast<double>(data_[pos + 1 < n_[d] ? idx + s : idx]);
            const double lo = static_cast<double>(data_[pos > 0 ? idx - s : idx]);
            g[d] = (hi - lo) * ((pos > 0 && pos + 1 < n_[d]) ? half_inv_spacing_[d] : inv_spacing_[d]);
        }
    }

    const T* data_;
    std::size_t n_[3], stride_[3];
    double half_inv_spacing_[3], inv_spacing_[3];
    std::array<double, 3> spacing_, origin_;
    double iso_, sign_;
    bool inside_below_;
};

}  // namespace voxmesh::detail
