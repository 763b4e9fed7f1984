// The checks on SculptOptions that need no volume, shared by make_impl and Sculpt::from_mesh,
// which runs them before it voxelizes (seconds to minutes at a high resolution).
#pragma once

#include <voxmesh/sculpt.hpp>

namespace voxmesh::detail::sculpt {

// Throws Error for a block size outside 2..256, a device index below -1 or past
// list_devices() (when OpenCL devices exist; with none the CPU re-meshes, with a warning), the
// hybrid backend, or a non-finite iso value or strength scale.
void check_options(const SculptOptions& options);

}  // namespace voxmesh::detail::sculpt
