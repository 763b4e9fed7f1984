#include "opencl_hook.hpp"

namespace voxmesh::detail {

Mesh opencl_extract(const VolumeView&, const Options&, Stats&, bool, Mesh) {
    throw Error("voxmesh was built without OpenCL (VOXMESH_WITH_OPENCL=OFF); use the cpu backend");
}

std::vector<DeviceInfo> opencl_devices() { return {}; }

void opencl_release_memory() {}

}  // namespace voxmesh::detail
