// libFuzzer target: extract() on small volumes of every scalar type, whatever their samples
// and iso (NaN, infinities, the ends of each type's range). The input is a header (type,
// dims, options, iso) and then the samples (zero-padded). Findings:
//   * the CPU engine on 1, 2 and 5 threads must give the same result: the same mesh, bit for
//     bit, or the same Error;
//   * the mesh's index buffer must be the naive oracle's (tests/support/reference_mc), and
//     every vertex must lie on its own grid edge, finite;
//   * an Error only for what the API documents (NaN or infinite samples, a NaN iso, samples
//     placed beyond the float range by origin and spacing).
// Some inputs pick an origin and spacing far from 0 and 1, where float vertices round.
#include "core/float_extent.hpp"
#include "support/reference_mc.hpp"

#include <voxmesh/voxmesh.hpp>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <string>
#include <vector>

namespace {

using voxmesh::ScalarType;

constexpr ScalarType kTypes[] = {ScalarType::U8,  ScalarType::I8,  ScalarType::U16, ScalarType::I16,
                                 ScalarType::U32, ScalarType::I32, ScalarType::F32, ScalarType::F64};

template <typename T>
std::vector<double> as_doubles(const unsigned char* bytes, std::size_t count) {
    std::vector<double> out(count);
    for (std::size_t i = 0; i < count; ++i) {
        T v;
        std::memcpy(&v, bytes + i * sizeof(T), sizeof(T));
        out[i] = static_cast<double>(v);
    }
    return out;
}

std::vector<double> samples_as_doubles(ScalarType type, const unsigned char* bytes, std::size_t count) {
    switch (type) {
        case ScalarType::U8: return as_doubles<std::uint8_t>(bytes, count);
        case ScalarType::I8: return as_doubles<std::int8_t>(bytes, count);
        case ScalarType::U16: return as_doubles<std::uint16_t>(bytes, count);
        case ScalarType::I16: return as_doubles<std::int16_t>(bytes, count);
        case ScalarType::U32: return as_doubles<std::uint32_t>(bytes, count);
        case ScalarType::I32: return as_doubles<std::int32_t>(bytes, count);
        case ScalarType::F32: return as_doubles<float>(bytes, count);
        case ScalarType::F64: return as_doubles<double>(bytes, count);
    }
    std::abort();
}

struct Outcome {
    bool error = false;
    std::string message;
    voxmesh::Mesh mesh;
};

Outcome run(const voxmesh::VolumeView& view, voxmesh::Options options, unsigned threads) {
    options.threads = threads;
    Outcome out;
    try {
        out.mesh = voxmesh::extract(view, options);
    } catch (const voxmesh::Error& e) {
        out.error = true;
        out.message = e.what();
    }
    return out;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    constexpr std::size_t kHeader = 13;  // type, nx, ny, nz, flags, iso (8 bytes)
    if (size < kHeader) return 0;
    const ScalarType type = kTypes[data[0] % 8];
    const vmtest::Dims dims{2 + data[1] % 11u, 2 + data[2] % 11u, 2 + data[3] % 11u};
    const std::uint8_t flags = data[4];
    double iso = 0;
    std::memcpy(&iso, data + 5, sizeof iso);
    if (flags & 4) iso = static_cast<double>(static_cast<std::int16_t>(data[5] | data[6] << 8)) + 0.5;  // a plain iso

    const std::size_t count = dims[0] * dims[1] * dims[2];
    std::vector<unsigned char> bytes(count * voxmesh::scalar_size(type), 0);
    std::memcpy(bytes.data(), data + kHeader, std::min(bytes.size(), size - kHeader));

    voxmesh::VolumeView view{bytes.data(), type, dims};
    // Geometry presets (flags bits 3-5): tiny and huge spacings, origins far from 0, and
    // grids that end past FLT_MAX on their larger sizes.
    struct Geometry {
        std::array<double, 3> spacing, origin;
    };
    constexpr Geometry kGeometries[] = {{{0.5, 2, 1e-3}, {-10, 5, 1e3}},
                                        {{1e-30, 1e30, 1}, {0, 0, 0}},
                                        {{1, 1, 1}, {1e7, -1e7, 3e38}},
                                        {{4e37, 1, 1}, {0, 0, -1}},
                                        {{1, 0.25, 1}, {-3.4e38, 0, 0}}};
    const unsigned preset = (flags >> 3) & 7u;
    const bool unit_grid = preset >= std::size(kGeometries);
    if (!unit_grid) {
        view.spacing = kGeometries[preset].spacing;
        view.origin = kGeometries[preset].origin;
    }
    const bool beyond_float = voxmesh::detail::axis_beyond_float(dims, view.spacing, view.origin) >= 0;
    voxmesh::Options options;
    options.iso = iso;
    options.backend = voxmesh::Backend::Cpu;
    options.normals = (flags & 1) == 0;
    options.inside_below = (flags & 2) != 0;

    const Outcome one = run(view, options, 1);
    for (const unsigned threads : {2u, 5u}) {
        const Outcome many = run(view, options, threads);
        if (many.error != one.error || many.message != one.message) std::abort();
        if (many.mesh.indices != one.mesh.indices || !same_bits(many.mesh.positions, one.mesh.positions) ||
            !same_bits(many.mesh.normals, one.mesh.normals))
            std::abort();
    }

    const std::vector<double> values = samples_as_doubles(type, bytes.data(), count);
    bool finite = true;
    for (const double v : values) finite = finite && std::isfinite(v);
    if (one.error) {
        if (finite && !std::isnan(iso) && !beyond_float) std::abort();  // refused a volume the API takes
        return 0;
    }
    if (!finite || std::isnan(iso) || beyond_float) std::abort();  // took what the API refuses

    vmtest::RefOptions ro;
    ro.iso = iso;
    ro.inside_below = options.inside_below;
    const vmtest::RefMesh ref = vmtest::reference_mc(values, dims, ro);
    if (one.mesh.indices != ref.indices || one.mesh.vertex_count() != ref.vertex_count()) std::abort();
    if (options.normals != !one.mesh.normals.empty() && one.mesh.vertex_count() != 0) std::abort();
    for (std::size_t v = 0; v < ref.vertex_count(); ++v) {
        const std::uint64_t sample = ref.edge_ids[v] / 3;
        const unsigned axis = static_cast<unsigned>(ref.edge_ids[v] % 3);
        const double at[3] = {double(sample % dims[0]), double(sample / dims[0] % dims[1]),
                              double(sample / dims[0] / dims[1])};
        for (unsigned d = 0; d < 3; ++d) {
            const double p = one.mesh.positions[3 * v + d];
            if (!std::isfinite(p)) std::abort();
            if (unit_grid) {
                if (d == axis ? (p < at[d] || p > at[d] + 1) : p != at[d]) std::abort();
                continue;
            }
            // On its edge (or at its sample, across it), within float rounding of the ends.
            const double a = view.origin[d] + at[d] * view.spacing[d];
            const double b = d == axis ? view.origin[d] + (at[d] + 1) * view.spacing[d] : a;
            const double slack = 2 * voxmesh::detail::float_step_near(std::max(std::fabs(a), std::fabs(b)));
            if (p < std::min(a, b) - slack || p > std::max(a, b) + slack) std::abort();
        }
    }
    for (const float n : one.mesh.normals)
        if (!std::isfinite(n)) std::abort();
    return 0;
}
