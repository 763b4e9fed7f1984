// The fault layer (tests/cl_fault_layer), which ocl-icd loads from OPENCL_LAYERS in the ctest
// test voxmesh_opencl_faults: the [.clfault] tests say through it which OpenCL calls fail.
#pragma once

#include <catch2/catch.hpp>
#include <voxmesh/voxmesh.hpp>

#include <CL/cl.h>  // the error codes to give
#include <cstdlib>
#include <dlfcn.h>

namespace vmtest {

struct FaultLayer {
    // Launches of `kernel` (or calls of clEnqueueReadBuffer, clEnqueueWriteBuffer,
    // clEnqueueCopyBuffer, clEnqueueMapBuffer, named so) fail with `error`, buffers over `buffer_over` bytes as out of
    // memory: `times` faults (negative: no end) after `skip` matching calls went through.
    void (*set)(const char* kernel, int error, unsigned long long buffer_over, unsigned long long skip,
                long long times) = nullptr;
    unsigned long long (*given)() = nullptr;  // faults given since the last set

    bool loaded() const { return set != nullptr && given != nullptr; }
    void clear() const {
        if (loaded()) set("", 0, 0, 0, 0);
    }
};

// Whether OPENCL_LAYERS names a layer; else a warning that the calling test is skipped (it runs
// under ctest's voxmesh_opencl_faults; by name, a hidden test runs without the layer).
inline bool fault_layer_named() {
    if (std::getenv("OPENCL_LAYERS") != nullptr) return true;
    WARN("this test needs the fault layer (ctest runs it as voxmesh_opencl_faults): SKIPPED");
    return false;
}

// Null functions where the layer is not loaded.
inline FaultLayer fault_layer() {
    FaultLayer layer;
    const char* path = std::getenv("OPENCL_LAYERS");
    if (path == nullptr) return layer;
    (void)voxmesh::list_devices();  // the loader loads its layers at the first OpenCL call
    void* handle = dlopen(path, RTLD_NOW | RTLD_NOLOAD);
    if (handle == nullptr) return layer;
    layer.set = reinterpret_cast<decltype(layer.set)>(dlsym(handle, "voxmesh_cl_fault_set"));
    layer.given = reinterpret_cast<decltype(layer.given)>(dlsym(handle, "voxmesh_cl_fault_given"));
    return layer;
}

struct ClearFaults {  // no faults after the scope, however it ends
    const FaultLayer& layer;
    ~ClearFaults() { layer.clear(); }
};

}  // namespace vmtest
