// A build without OpenCL: sculpting always meshes on the CPU.
#include "device_blocks.hpp"

namespace voxmesh::detail::sculpt {

void set_device_block_tuning(const DeviceBlockTuning&) {}

std::unique_ptr<DeviceBlockMesher> open_opencl_block_mesher(const DeviceBlockSetup&, int, std::string& why) {
    why = "voxmesh was built without OpenCL (VOXMESH_WITH_OPENCL=OFF)";
    return nullptr;
}

}  // namespace voxmesh::detail::sculpt
