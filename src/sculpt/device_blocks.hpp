// Re-meshing sculpt blocks on an OpenCL device: the seam between src/sculpt (no OpenCL types)
// and src/cl/cl_blocks.cpp, or src/sculpt/no_opencl_blocks.cpp in a build without OpenCL.
// Every block mesh it produces equals the CPU block mesher's (same vertex and triangle order,
// same local indices; positions and normals bit-identical on devices with fp64, within a few
// ulps without).
#pragma once

#include "block_mesher.hpp"

#include <voxmesh/voxmesh.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>

namespace voxmesh::detail::sculpt {

struct DeviceBlockSetup {
    VolumeView volume;  // the sculpt's samples (u8, u16 or f32); read at every mesh() call
    double iso = 0;
    bool inside_below = false;
    bool normals = true;
};

// One block's mesh, viewing the mesher's host buffers (valid until the next mesh() call).
struct DeviceBlockMesh {
    std::span<const float> positions, normals;
    std::span<const std::uint32_t> indices;
};

class DeviceBlockMesher {
public:
    virtual ~DeviceBlockMesher() = default;
    virtual const std::string& device_name() const = 0;
    // Meshes every box (in batches that fit the device) and calls store(i, mesh of boxes[i]).
    // Throws Error on an OpenCL failure; blocks already stored stay valid.
    virtual void mesh(std::span<const BlockBox> boxes,
                      const std::function<void(std::size_t, const DeviceBlockMesh&)>& store) = 0;
    // True in a child forked after the device was opened: its OpenCL objects belong to the
    // parent's runtime, whose threads the child lacks. Neither meshing nor releasing them
    // returns there (PoCL waits for its workers), so the mesher is dropped without its
    // destructor.
    virtual bool left_in_parent() const = 0;
};

// Test hooks: a smaller batch (staged samples per batch; 0 = the default) so that one
// update runs several batches, float vertex math on fp64 devices (the path of most GPUs), and
// the row scans in GPU work-groups (256 items of 8, where a CPU device's are 1 of 1024). Read
// when a mesher is opened (no_fp64, gpu_scans) and at every mesh() call (batch_samples).
struct DeviceBlockTuning {
    std::size_t batch_samples = 0;
    bool no_fp64 = false;
    bool gpu_scans = false;
};
void set_device_block_tuning(const DeviceBlockTuning& tuning);

// Opens OpenCL device `device` (an index into list_devices(); -1: the first GPU or
// accelerator, else the first device) and builds the kernels. Returns null with `why` set
// when no OpenCL device exists (the caller falls back to the CPU); throws Error for an
// index that does not exist or a failed build.
std::unique_ptr<DeviceBlockMesher> open_opencl_block_mesher(const DeviceBlockSetup& setup, int device,
                                                            std::string& why);

}  // namespace voxmesh::detail::sculpt
