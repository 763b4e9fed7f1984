// The seam between the core and the OpenCL engine: src/cl implements these, or
// src/core/no_opencl.cpp when voxmesh is built without OpenCL.
#pragma once

#include <voxmesh/voxmesh.hpp>

namespace voxmesh::detail {

// Meshes with OpenCL devices (Backend::OpenCL) or devices plus CPU threads (Backend::Hybrid).
// Throws Error when no usable device exists.
Mesh opencl_extract(const VolumeView& volume, const Options& options, Stats& stats, bool hybrid);

// Every usable OpenCL device; empty when there is none (never throws for a missing platform).
std::vector<DeviceInfo> opencl_devices();

}  // namespace voxmesh::detail
