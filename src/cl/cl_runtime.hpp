// The OpenCL runtime of the engine: device discovery, one context + profiling queue per
// device, programs built once per device and options, reusable buffers, the scan.
// Process-wide and created lazily; a Device is used by one thread at a time (its mutex).
#pragma once

#include <CL/opencl.hpp>
#include <voxmesh/voxmesh.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace voxmesh::detail {

extern const unsigned char kKernel_edge_vertex[];  // put in front of marching_cubes and sculpt_blocks
extern const unsigned char kKernel_marching_cubes[];
extern const unsigned char kKernel_scan[];
extern const unsigned char kKernel_sculpt_blocks[];  // sculpting's batched block mesher

namespace cl_engine {

enum class Pass { Classify, Scan, Generate, Transfer };

// Events of one chunk, summed into seconds per pass after the queue finished.
struct EventLog {
    std::vector<std::pair<Pass, cl::Event>> events;
    cl::Event& add(Pass pass) {
        events.emplace_back(pass, cl::Event());
        return events.back().second;
    }
};
double event_seconds(const cl::Event& event);

class PinnedStaging;
// The size of each of a device's two pinned blocks (0: the default, 8 MiB); a test hook.
void set_staging_block_bytes(std::size_t bytes);

class Device {
public:
    Device(const cl::Device& device, DeviceInfo info);
    ~Device();

    DeviceInfo info;
    cl::Device device;
    cl::Context context;
    cl::CommandQueue queue;
    cl::Buffer case_table, pair_to_case;  // from src/core/case_tables.cpp
    cl::Buffer case_corners;              // case_corner_table(): case_table's corners as (dx, dy, dz, axis)
    cl::Buffer pair_corners;              // the same by row-pair index (kRowPairsToCase)
    std::mutex mutex;  // whoever uses queue, kernels or buffers holds it
    std::size_t programs_built = 0;  // by build(): programs are cached, so this stops growing
    // Kept buffers and pinned blocks made (buffer(), staging()): these also stop growing once
    // the largest chunk and mesh piece have come, and a call that made any timed that set-up
    // too (Hybrid's choice).
    std::size_t allocations = 0;

    // Kernels of marching_cubes.cl built with `options`, and of scan.cl. Build failures
    // throw Error with the device name and the build log.
    cl::Kernel& mc_kernel(const std::string& options, const char* name);
    cl::Kernel& scan_kernel(const char* name, std::size_t items);
    // Kernels of sculpt_blocks.cl built with `options` (src/cl/cl_blocks.cpp).
    cl::Kernel& sculpt_kernel(const std::string& options, const char* name);
    // scan.cl's launch shape on this device (or, with gpu_shape, the shape GPUs get, on any
    // device; for tests): work-group size and elements per work-item (SCAN_ITEMS), a block of
    // local * items elements per work-group.
    struct ScanShape {
        std::size_t local = 0, items = 0;
    };
    ScanShape scan_shape(bool gpu_shape = false);

    // A buffer of at least `bytes` for slot `id`, kept for the next chunk and call.
    cl::Buffer& buffer(unsigned id, std::size_t bytes);
    void drop_buffers();
    // Frees the buffers and the pinned blocks, keeping the context, queue and programs.
    void release_memory();
    // What buffer() and staging() keep now, in bytes.
    std::size_t kept_bytes() const;
    // Pinned blocks for copies to and from host memory (pinned_staging.hpp), made on first use.
    PinnedStaging& staging();

    // Builds `source` with `options`; on failure throws Error naming the device, with the log.
    cl::Program build(const std::string& source, const std::string& options);

private:
    struct Program {
        cl::Program program;
        std::map<std::string, cl::Kernel> kernels;
    };
    cl::Kernel& kernel(const unsigned char* source, const std::string& options, const char* name);
    std::map<std::string, Program> programs_;
    std::map<unsigned, std::pair<cl::Buffer, std::size_t>> buffers_;
    std::unique_ptr<PinnedStaging> staging_;
    ScanShape scan_shapes_[2];  // the device's own, the GPU shape
};

// Every usable device (available, with a compiler), discovered once per process. None in a
// child forked after the parent discovered them: the OpenCL runtime's threads and contexts
// stay behind in the parent (PoCL's kernels would wait for ever on workers the child lacks).
std::vector<std::shared_ptr<Device>> devices();
// Whether devices() is empty because this process is such a child.
bool devices_left_in_parent();
// release_memory() on every device this process has discovered, discovering none; a device
// another thread is meshing on (or this one, from a log callback) keeps its memory.
void release_kept_memory();
// The bytes kept by the devices discovered so far (0 before discovery); waits for busy ones.
std::size_t kept_bytes();
// Why devices() is empty, for an error or warning.
std::string why_no_devices();
// Test hook: present each partitionable device as sub-devices of 1 compute unit each (at
// most 2), i.e. several OpenCL devices on a machine that has one.
void split_devices(bool split);
// Test hook: runs f holding the registry's lock, marked as discovering if `as_discovery`.
void with_device_registry_locked_for_testing(bool as_discovery, const std::function<void()>& f);

// Exclusive prefix sum of n uints in `data`, in place, on d's queue (in order), and its
// total copied to uint `total_at` of `totals` on the device: enqueued only, so that a caller
// reads several totals back at once. Buffer ids >= kScanBufferBase hold block sums, and
// kScanTotal the total that scan() reads back.
constexpr unsigned kScanBufferBase = 100, kScanTotal = kScanBufferBase - 1;
// gpu_shape: launched as on GPUs whatever the device (Device::scan_shape).
void scan_into(Device& d, const cl::Buffer& data, std::size_t n, const cl::Buffer& totals, std::size_t total_at,
               EventLog& log, bool gpu_shape = false, unsigned level = 0);
// The same, blocking: reads the total back and returns it.
std::uint64_t scan(Device& d, const cl::Buffer& data, std::size_t n, EventLog& log, bool gpu_shape = false);

// Kernel arguments in declaration order from index 0, so that no call site numbers them:
//   set_args(kernel, buffer, cl_uint{n}, ArgBytes{threshold}, ArgVertexFormula{...}, ...)
// ArgBytes: a value passed as raw bytes (a sample-typed threshold).
struct ArgBytes {
    const std::vector<unsigned char>& bytes;
};
// The scalar arguments of edge_vertex.cl's formula, in its order: iso (real), iso's integer
// part (long) and fraction (float) for integer samples without fp64 (for float samples, what
// rounding iso to float left), then origin, spacing and
// 1 / spacing (real) per axis. real is double where the kernels interpolate in double.
struct ArgVertexFormula {
    double iso;
    bool integer_samples, fp64;
    std::array<double, 3> origin, spacing;
};

inline cl_uint set_arg(cl::Kernel& k, cl_uint i, const ArgBytes& a) {
    k.setArg(i, a.bytes.size(), a.bytes.data());
    return i + 1;
}
cl_uint set_arg(cl::Kernel& k, cl_uint i, const ArgVertexFormula& a);
template <class T>
cl_uint set_arg(cl::Kernel& k, cl_uint i, const T& value) {
    k.setArg(i, value);
    return i + 1;
}
template <class... Args>
void set_args(cl::Kernel& k, const Args&... args) {
    cl_uint i = 0;
    ((i = set_arg(k, i, args)), ...);
}

// True for errors that mean "this did not fit" (allocation failures, out of resources).
bool is_out_of_memory(cl_int code);
// "CL_OUT_OF_RESOURCES (-5)" etc.
std::string error_name(cl_int code);

}  // namespace cl_engine
}  // namespace voxmesh::detail
