// Sculpt::from_mesh and from_stl: a model voxelized into a signed distance field (their own
// translation unit, so programs that never load models do not pull in the reader and
// voxelizer).
#include <voxmesh/io.hpp>
#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxelize.hpp>

#include "sculpt_options.hpp"

namespace voxmesh {

VoxelizeOptions Sculpt::model_voxelization(std::size_t resolution, const SculptOptions& options) {
    VoxelizeOptions vo;
    vo.resolution = resolution;
    vo.band = 4;  // a little wider than the default, so brushes have a smooth field to work on
    vo.threads = options.threads;
    return vo;
}

Sculpt Sculpt::from_mesh(const Mesh& model, std::size_t resolution, const SculptOptions& options) {
    return from_mesh(model, model_voxelization(resolution, options), options);
}

Sculpt Sculpt::from_mesh(const Mesh& model, const VoxelizeOptions& voxelize_options, const SculptOptions& options) {
    // Brush strengths and the iso value 0 are in distance units; occupancy has neither.
    if (voxelize_options.field != VoxelField::Distance)
        throw Error("sculpt: a model is sculpted as a distance field; voxelize it with field Distance");
    detail::sculpt::check_options(options);  // before the voxelizer's seconds, not after
    Volume volume = voxelize(model, voxelize_options);
    SculptOptions so = options;
    if (so.strength_scale == 0) so.strength_scale = volume.spacing[0];
    return adopting(std::move(volume), so);
}

Sculpt Sculpt::from_stl(const std::string& path, std::size_t resolution, const SculptOptions& options) {
    return from_mesh(read_stl(path), resolution, options);
}

}  // namespace voxmesh
