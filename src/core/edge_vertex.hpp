// The position and normal of the vertex on a crossed edge: the one formula every CPU-side
// mesher uses, so their vertices agree bit for bit.
//   position = origin + (index + t * axis) * spacing,  t = (iso - v0) / (v1 - v0)
//   normal   = -gradient interpolated with t, normalised (gradient: central differences,
//              one-sided at the border, divided by spacing); +gradient when inside_below.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cmath>
#include <cstddef>

namespace voxmesh::detail {

template <class T>
class EdgeVertex {
public:
    EdgeVertex(const VolumeView& volume, double iso, bool inside_below)
        : data_(static_cast<const T*>(volume.data)),
          n_{volume.dims[0], volume.dims[1], volume.dims[2]},
          stride_{1, volume.dims[0], volume.dims[0] * volume.dims[1]},
          inv_spacing_{1 / volume.spacing[0], 1 / volume.spacing[1], 1 / volume.spacing[2]},
          spacing_(volume.spacing),
          origin_(volume.origin),
          iso_(iso),
          inside_below_(inside_below) {}

    // Writes the vertex of the edge from sample (i, j, k) along `axis`; normal may be null.
    void operator()(std::size_t i, std::size_t j, std::size_t k, unsigned axis, float* position, float* normal) const {
        const std::size_t idx0 = i + j * stride_[1] + k * stride_[2];
        const std::size_t idx1 = idx0 + stride_[axis];
        const double v0 = static_cast<double>(data_[idx0]), v1 = static_cast<double>(data_[idx1]);
        const double t = (iso_ - v0) / (v1 - v0);
        const double index[3] = {static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)};
        for (unsigned d = 0; d < 3; ++d)
            position[d] = static_cast<float>(origin_[d] + (index[d] + (d == axis ? t : 0.0)) * spacing_[d]);
        if (!normal) return;

        const std::size_t at0[3] = {i, j, k};
        std::size_t at1[3] = {i, j, k};
        ++at1[axis];
        double g0[3], g1[3];
        // Most vertices lie away from the border: there both gradients are plain central
        // differences, computed without the per-axis border tests (same arithmetic).
        if (interior(at0) && at1[axis] + 1 < n_[axis]) {
            central_gradient(idx0, g0);
            central_gradient(idx1, g1);
        } else {
            gradient(idx0, at0, g0);
            gradient(idx1, at1, g1);
        }
        // Outward is toward decreasing values: the negated gradient (flipped for inside_below).
        const double sign = inside_below_ ? 1.0 : -1.0;
        double n[3], len2 = 0;
        for (unsigned d = 0; d < 3; ++d) {
            n[d] = sign * (g0[d] + t * (g1[d] - g0[d]));
            len2 += n[d] * n[d];
        }
        if (len2 > 0 && std::isfinite(len2)) {
            const double inv = 1 / std::sqrt(len2);
            for (unsigned d = 0; d < 3; ++d) normal[d] = static_cast<float>(n[d] * inv);
        } else {
            // Flat gradient: point along the edge, from its inside end to its outside end.
            const bool first_inside = (v0 >= iso_) != inside_below_;
            for (unsigned d = 0; d < 3; ++d) normal[d] = d == axis ? (first_inside ? 1.f : -1.f) : 0.f;
        }
    }

private:
    bool interior(const std::size_t at[3]) const {
        return at[0] - 1 < n_[0] - 2 && at[1] - 1 < n_[1] - 2 && at[2] - 1 < n_[2] - 2;  // 1 <= at < n-1
    }

    void central_gradient(std::size_t idx, double g[3]) const {
        for (unsigned d = 0; d < 3; ++d) {
            const std::size_t s = stride_[d];
            g[d] = (static_cast<double>(data_[idx + s]) - static_cast<double>(data_[idx - s])) * 0.5 * inv_spacing_[d];
        }
    }

    void gradient(std::size_t idx, const std::size_t at[3], double g[3]) const {
        for (unsigned d = 0; d < 3; ++d) {
            const std::size_t pos = at[d], s = stride_[d];
            const double hi = static_cast<double>(data_[pos + 1 < n_[d] ? idx + s : idx]);
            const double lo = static_cast<double>(data_[pos > 0 ? idx - s : idx]);
            const double step = (pos > 0 && pos + 1 < n_[d]) ? 0.5 : 1.0;
            g[d] = (hi - lo) * step * inv_spacing_[d];
        }
    }

    const T* data_;
    std::size_t n_[3], stride_[3];
    double inv_spacing_[3];
    std::array<double, 3> spacing_, origin_;
    double iso_;
    bool inside_below_;
};

}  // namespace voxmesh::detail
