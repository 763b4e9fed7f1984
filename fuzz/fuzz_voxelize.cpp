// libFuzzer target: read_mesh (PLY for input starting "ply", STL for "solid" or a binary STL
// size, OBJ otherwise), then voxelize what it reads on a small grid, both fields and both fill
// rules. A model voxelize accepts must give a volume that meshes back (extract) to a closed
// 2-manifold: occupancy in {0, 255}, distances finite, and the padding keeps the surface off
// the border; NonZero fills every sample EvenOdd fills.
// Vertices no triangle uses (PLY and OBJ keep them) must change nothing: the volume equals
// that of the model without them.
#include "fuzz_common.hpp"

#include <voxmesh/voxelize.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace {

// The model without the vertices no triangle uses, renumbered in order.
voxmesh::Mesh without_unused_vertices(const voxmesh::Mesh& model) {
    std::vector<std::uint32_t> renumber(model.vertex_count(), UINT32_MAX);
    for (std::uint32_t i : model.indices) renumber[i] = 0;
    voxmesh::Mesh out;
    for (std::size_t v = 0; v < renumber.size(); ++v) {
        if (renumber[v] == UINT32_MAX) continue;
        renumber[v] = static_cast<std::uint32_t>(out.vertex_count());
        out.positions.insert(out.positions.end(), &model.positions[3 * v], &model.positions[3 * v] + 3);
    }
    for (std::uint32_t i : model.indices) out.indices.push_back(renumber[i]);
    return out;
}

// The volume, or the Error's message where voxelize refuses the model.
struct Outcome {
    voxmesh::Volume volume;
    std::string error;
};
Outcome voxelized(const voxmesh::Mesh& model, const voxmesh::VoxelizeOptions& options) {
    Outcome out;
    try {
        out.volume = voxmesh::voxelize(model, options);
    } catch (const voxmesh::Error& e) {
        out.error = e.what();
    }
    return out;
}

bool same(const Outcome& a, const Outcome& b) {
    if (!a.error.empty() || !b.error.empty()) return a.error == b.error;
    return a.volume.dims == b.volume.dims && a.volume.origin == b.volume.origin &&
           a.volume.spacing == b.volume.spacing &&
           std::memcmp(a.volume.data, b.volume.data, a.volume.byte_size()) == 0;
}

Outcome check_voxelized(const voxmesh::Mesh& model, voxmesh::VoxelField field, voxmesh::FillRule fill,
                        std::size_t resolution) {
    voxmesh::VoxelizeOptions options;
    options.resolution = resolution;
    options.padding = 2;
    options.field = field;
    options.fill = fill;
    options.threads = 1;
    Outcome outcome = voxelized(model, options);
    const voxmesh::Mesh used = without_unused_vertices(model);
    if (used.vertex_count() != model.vertex_count() && !same(outcome, voxelized(used, options))) std::abort();
    if (!outcome.error.empty()) return outcome;  // open, non-manifold, flat, beyond float, ...: refused with a message
    const voxmesh::Volume& volume = outcome.volume;
    const std::size_t n = volume.sample_count();
    if (field == voxmesh::VoxelField::Occupancy) {
        if (volume.type != voxmesh::ScalarType::U8) std::abort();
        const auto* p = static_cast<const std::uint8_t*>(volume.data);
        for (std::size_t i = 0; i < n; ++i)
            if (p[i] != 0 && p[i] != 255) std::abort();
    } else {
        if (volume.type != voxmesh::ScalarType::F32) std::abort();
        const auto* p = static_cast<const float*>(volume.data);
        for (std::size_t i = 0; i < n; ++i)
            if (!std::isfinite(p[i])) std::abort();
    }
    // voxelize promises a volume extract can mesh.
    const voxmesh::Mesh back =
        fuzz::extract_or_abort(volume.view(), field == voxmesh::VoxelField::Occupancy ? 127.5 : 0.0);
    if (back.triangle_count() == 0 || !voxmesh::analyze_topology(back).closed()) std::abort();
    return outcome;
}

// An odd winding number is a non-zero one: every sample EvenOdd fills, NonZero fills too. So
// where EvenOdd accepts the model (each edge in two triangles), NonZero refuses it only for
// its winding.
void check_fill_rules(const voxmesh::Mesh& model, std::size_t resolution) {
    const Outcome odd = check_voxelized(model, voxmesh::VoxelField::Occupancy, voxmesh::FillRule::EvenOdd, resolution);
    const Outcome nonzero = check_voxelized(model, voxmesh::VoxelField::Occupancy, voxmesh::FillRule::NonZero, resolution);
    if (!odd.error.empty()) return;
    if (!nonzero.error.empty()) {
        if (nonzero.error.find("not consistently wound") == std::string::npos) std::abort();
        return;
    }
    const auto* a = static_cast<const std::uint8_t*>(odd.volume.data);
    const auto* b = static_cast<const std::uint8_t*>(nonzero.volume.data);
    for (std::size_t i = 0; i < odd.volume.sample_count(); ++i)
        if (a[i] > b[i]) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const bool stl = text.substr(0, 5) == "solid" || (size >= 84 && (size - 84) % 50 == 0);
    const char* name = text.substr(0, 3) == "ply" ? "input.ply" : stl ? "input.stl" : "input.obj";
    const std::string path = fuzz::input_file(name, data, size);
    voxmesh::Mesh model;
    try {
        model = voxmesh::read_mesh(path);
    } catch (const voxmesh::Error&) {
        return 0;
    }
    // The resolution from the input's length: small grids, different per input.
    const std::size_t resolution = 4 + size % 13;
    check_fill_rules(model, resolution);
    check_voxelized(model, voxmesh::VoxelField::Distance, voxmesh::FillRule::EvenOdd, resolution);
    check_voxelized(model, voxmesh::VoxelField::Distance, voxmesh::FillRule::NonZero, resolution);
    return 0;
}
