// libFuzzer target: read_stl, then voxelize what it reads on a small grid, both fields. A
// model voxelize accepts must give a volume that meshes back (extract) to a closed
// 2-manifold: occupancy in {0, 255}, distances finite, and the padding keeps the surface
// off the border.
#include "fuzz_common.hpp"

#include <voxmesh/voxelize.hpp>

#include <cmath>
#include <cstdlib>

namespace {

void check_voxelized(const voxmesh::Mesh& model, voxmesh::VoxelField field, std::size_t resolution) {
    voxmesh::VoxelizeOptions options;
    options.resolution = resolution;
    options.padding = 2;
    options.field = field;
    options.threads = 1;
    voxmesh::Volume volume;
    try {
        volume = voxmesh::voxelize(model, options);
    } catch (const voxmesh::Error&) {
        return;  // open, non-manifold, flat, beyond float, ...: refused with a message
    }
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
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string path = fuzz::input_file("input.stl", data, size);
    voxmesh::Mesh model;
    try {
        model = voxmesh::read_stl(path);
    } catch (const voxmesh::Error&) {
        return 0;
    }
    // The resolution from the input's length: small grids, different per input.
    const std::size_t resolution = 4 + size % 13;
    check_voxelized(model, voxmesh::VoxelField::Occupancy, resolution);
    check_voxelized(model, voxmesh::VoxelField::Distance, resolution);
    return 0;
}
