// Sculpt::from_stl: an STL model voxelized into a signed distance field (its own translation
// unit, so programs that never load STL models do not pull in the reader and voxelizer).
#include <voxmesh/io.hpp>
#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxelize.hpp>

namespace voxmesh {

Sculpt Sculpt::from_stl(const std::string& path, std::size_t resolution, const SculptOptions& options) {
    const Mesh model = read_stl(path);
    VoxelizeOptions vo;
    vo.resolution = resolution;
    vo.field = VoxelField::Distance;
    vo.band = 4;  // a little wider than the default, so brushes have a smooth field to work on
    vo.threads = options.threads;
    const Volume volume = voxelize(model, vo);
    SculptOptions so = options;
    if (so.strength_scale == 0) so.strength_scale = volume.spacing[0];
    return Sculpt(volume.view(), so);
}

}  // namespace voxmesh
