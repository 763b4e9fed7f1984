#include "cl_runtime.hpp"
#include "pinned_staging.hpp"

#include "core/case_tables.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <new>
#include <thread>

#include <pthread.h>
#include <unistd.h>

namespace voxmesh::detail::cl_engine {

static_assert(sizeof(CaseEntry) == 16, "kernels read the case table as 16 bytes per case");
static_assert(sizeof(kColumnPairToCase) == 256, "kernels read the column-pair table as 256 bytes");

namespace {

constexpr std::size_t kStagingBlockBytes = std::size_t{8} << 20;  // two of them per discrete device
std::atomic<std::size_t> g_staging_block_bytes{kStagingBlockBytes};  // test hook: smaller blocks

cl::Buffer constant_buffer(const cl::Context& context, const void* data, std::size_t bytes) {
    // CL_MEM_COPY_HOST_PTR only reads the host memory.
    return cl::Buffer(context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(data));
}

DeviceType device_type_of(cl_device_type type) {
    if (type & CL_DEVICE_TYPE_GPU) return DeviceType::Gpu;
    if (type & CL_DEVICE_TYPE_ACCELERATOR) return DeviceType::Accelerator;
    return DeviceType::Cpu;
}

DeviceInfo describe(const cl::Device& device, const std::string& platform, const std::string& suffix) {
    DeviceInfo info;
    info.platform = platform;
    info.name = device.getInfo<CL_DEVICE_NAME>() + suffix;
    info.version = device.getInfo<CL_DEVICE_VERSION>();
    info.type = device_type_of(device.getInfo<CL_DEVICE_TYPE>());
    info.compute_units = device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
    info.global_memory = device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
    info.max_allocation = device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
    info.fp64 = device.getInfo<CL_DEVICE_EXTENSIONS>().find("cl_khr_fp64") != std::string::npos;
    info.host_memory = device.getInfo<CL_DEVICE_HOST_UNIFIED_MEMORY>() == CL_TRUE;
    return info;
}

struct Registry {
    std::mutex mutex;
    std::atomic<std::thread::id> holder{};  // who holds `mutex` (for the fork handlers)
    bool discovered = false;
    pid_t discovered_in = 0;  // the process that discovered them; another one is a forked child
    bool discovering = false;  // `devices` is being rebuilt (under the lock)
    bool forked_while_discovering = false;  // in a child: `devices` may be half built, unusable
    bool split = false;
    std::vector<std::shared_ptr<Device>> devices;
};

Registry& registry();

// The registry's lock with its holder recorded.
class RegistryLock {
public:
    explicit RegistryLock(Registry& r) : r_(r) {
        r_.mutex.lock();
        r_.holder.store(std::this_thread::get_id());
    }
    ~RegistryLock() {
        r_.holder.store(std::thread::id{});
        r_.mutex.unlock();
    }
    RegistryLock(const RegistryLock&) = delete;
    RegistryLock& operator=(const RegistryLock&) = delete;

private:
    Registry& r_;
};

// fork(): unlike the thread cache's and the scratch pool's, this lock is not simply held across
// the fork, because discovery holds it through driver calls that may fork themselves (a GPU
// driver starting a helper) and would then wait on it for ever. It is taken only when free;
// where another thread held it, the child makes a fresh one (that thread is not in the child),
// and a discovery caught half done leaves the child no devices.
thread_local bool g_locked_for_fork = false;  // per forking thread: two may fork at once

void registry_before_fork() {
    Registry& r = registry();
    // try_lock on a mutex this thread holds is undefined: a fork from inside discovery skips it.
    g_locked_for_fork = r.holder.load() != std::this_thread::get_id() && r.mutex.try_lock();
}

void registry_after_fork_in_parent() {
    if (g_locked_for_fork) registry().mutex.unlock();
}

void registry_after_fork_in_child() {
    Registry& r = registry();
    if (g_locked_for_fork) {
        r.mutex.unlock();
        return;
    }
    if (r.holder.load() == std::this_thread::get_id()) return;  // forked under its own lock
    // The holder is not in this process. Its lock and, if it was discovering, the device list
    // are left as they were (leaked, never used) and replaced.
    new (&r.mutex) std::mutex;
    r.holder.store(std::thread::id{});
    if (r.discovering) {
        new (&r.devices) std::vector<std::shared_ptr<Device>>;
        r.discovering = false;
        r.forked_while_discovering = true;
    }
}

Registry& registry() {
    static Registry* r = [] {
        auto* created = new Registry;  // never destroyed: a forked child may have leaked parts of it
        pthread_atfork(registry_before_fork, registry_after_fork_in_parent, registry_after_fork_in_child);
        return created;
    }();
    return *r;
}

// Sub-devices of one compute unit each (at most two), or none when the device cannot split.
std::vector<cl::Device> sub_devices(const cl::Device& device) {
    std::vector<cl::Device> subs;
    try {
        if (device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>() < 2) return {};
        const auto types = device.getInfo<CL_DEVICE_PARTITION_PROPERTIES>();
        if (std::find(types.begin(), types.end(), CL_DEVICE_PARTITION_EQUALLY) == types.end()) return {};
        const cl_device_partition_property props[] = {CL_DEVICE_PARTITION_EQUALLY, 1, 0};
        cl::Device parent = device;
        parent.createSubDevices(props, &subs);
    } catch (const cl::Error&) {
        return {};
    }
    if (subs.size() > 2) subs.resize(2);
    return subs;
}

void discover(Registry& r) {
    r.devices.clear();
    std::vector<cl::Platform> platforms;
    try {
        cl::Platform::get(&platforms);
    } catch (const cl::Error&) {
        return;  // no ICD, no platform: no devices
    }
    for (const cl::Platform& platform : platforms) {
        std::vector<cl::Device> found;
        std::string platform_name;
        try {
            platform_name = platform.getInfo<CL_PLATFORM_NAME>();
            platform.getDevices(CL_DEVICE_TYPE_ALL, &found);
        } catch (const cl::Error&) {
            continue;
        }
        for (const cl::Device& device : found) {
            try {
                if (!device.getInfo<CL_DEVICE_AVAILABLE>() || !device.getInfo<CL_DEVICE_COMPILER_AVAILABLE>()) continue;
                std::vector<cl::Device> subs = r.split ? sub_devices(device) : std::vector<cl::Device>{};
                if (subs.empty()) {
                    r.devices.push_back(std::make_shared<Device>(device, describe(device, platform_name, "")));
                } else {
                    for (std::size_t i = 0; i < subs.size(); ++i)
                        r.devices.push_back(std::make_shared<Device>(
                            subs[i], describe(subs[i], platform_name,
                                              " [sub-device " + std::to_string(i + 1) + "/" +
                                                  std::to_string(subs.size()) + "]")));
                }
            } catch (const cl::Error&) {
                continue;  // a device we cannot open is not usable
            }
        }
    }
    for (std::size_t i = 0; i < r.devices.size(); ++i) r.devices[i]->info.index = static_cast<int>(i);
}

// Per case, 16 bytes: the triangle count, then each triangle corner's edge as one byte
// dx | dy << 1 | dz << 2 | axis << 3 (kCellEdge of the case table's edge number), so that a
// kernel finds a corner's sample and axis with one load instead of two dependent ones.
std::array<std::uint8_t, 256 * 16> case_corner_table() {
    std::array<std::uint8_t, 256 * 16> table{};
    for (std::size_t c = 0; c < 256; ++c) {
        const CaseEntry& entry = kCaseTable[c];
        table[16 * c] = entry.count;
        for (std::size_t i = 0; i < 3u * entry.count; ++i) {
            const CellEdge& e = kCellEdge[entry.edges[i]];
            table[16 * c + 1 + i] = static_cast<std::uint8_t>(e.dx | e.dy << 1 | e.dz << 2 | e.axis << 3);
        }
    }
    return table;
}

// case_corner_table() by row-pair index (kRowPairsToCase): a kernel reads a cell's entry with
// its four rows' 2-bit pairs as the index, without assembling the case bit by bit.
std::array<std::uint8_t, 256 * 16> pair_corner_table() {
    const std::array<std::uint8_t, 256 * 16> by_case = case_corner_table();
    std::array<std::uint8_t, 256 * 16> table{};
    for (std::size_t pairs = 0; pairs < 256; ++pairs)
        std::copy_n(by_case.begin() + 16 * kRowPairsToCase[pairs], 16, table.begin() + 16 * pairs);
    return table;
}

std::size_t round_up(std::size_t n, std::size_t m) { return (n + m - 1) / m * m; }

}  // namespace

Device::Device(const cl::Device& dev, DeviceInfo description)
    : info(std::move(description)), device(dev), context(dev), queue(context, dev, CL_QUEUE_PROFILING_ENABLE) {
    case_table = constant_buffer(context, kCaseTable, sizeof(kCaseTable));
    pair_to_case = constant_buffer(context, kColumnPairToCase.data(), kColumnPairToCase.size());
    static const std::array<std::uint8_t, 256 * 16> corners = case_corner_table();
    case_corners = constant_buffer(context, corners.data(), corners.size());
    static const std::array<std::uint8_t, 256 * 16> by_pairs = pair_corner_table();
    pair_corners = constant_buffer(context, by_pairs.data(), by_pairs.size());
}

Device::~Device() = default;

PinnedStaging& Device::staging() {
    const std::size_t block = g_staging_block_bytes;
    if (!staging_ || staging_->block_bytes() != block) {
        staging_.reset();
        staging_ = std::make_unique<PinnedStaging>(context, queue, block);
        ++allocations;
    }
    return *staging_;
}

void set_staging_block_bytes(std::size_t bytes) { g_staging_block_bytes = bytes > 0 ? bytes : kStagingBlockBytes; }

cl::Program Device::build(const std::string& source, const std::string& options) {
    ++programs_built;
    cl::Program program(context, source);
    try {
        program.build(std::vector<cl::Device>{device}, options.c_str());
    } catch (const cl::Error& e) {
        std::string log;
        try {
            log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device);
        } catch (const cl::Error&) {
            log = "(no build log)";
        }
        throw Error("OpenCL program build failed on device '" + info.name + "' (options \"" + options + "\", " +
                    error_name(e.err()) + "); build log:\n" + log);
    }
    return program;
}

cl::Kernel& Device::kernel(const unsigned char* source, const std::string& options, const char* name) {
    const char* file = source == kKernel_scan ? "scan " : source == kKernel_sculpt_blocks ? "sculpt " : "mc ";
    const std::string key = file + options;
    auto it = programs_.find(key);
    if (it == programs_.end()) {
        // The marching-cubes programs share the types and the vertex formula of edge_vertex.cl.
        std::string text = source == kKernel_scan ? "" : reinterpret_cast<const char*>(kKernel_edge_vertex);
        text += reinterpret_cast<const char*>(source);
        it = programs_.emplace(key, Program{build(text, options), {}}).first;
    }
    auto& kernels = it->second.kernels;
    auto k = kernels.find(name);
    if (k == kernels.end()) k = kernels.emplace(name, cl::Kernel(it->second.program, name)).first;
    return k->second;
}

cl::Kernel& Device::mc_kernel(const std::string& options, const char* name) {
    return kernel(kKernel_marching_cubes, options, name);
}

// On CPU devices a work-item per block, each summing 1024 elements in a loop: PoCL runs a
// work-group's up- and down-sweeps as loops over all its work-items between barriers, and
// the scans of 256-item groups took ~1.5 ms of device time per extract of sphere u8 512³.
// Elsewhere 256-item groups of 8 each, the usual shape on GPUs.
constexpr std::size_t kCpuScanItems = 1024, kScanItems = 8;

cl::Kernel& Device::scan_kernel(const char* name, std::size_t items) {
    return kernel(kKernel_scan, "-DSCAN_ITEMS=" + std::to_string(items), name);
}

cl::Kernel& Device::sculpt_kernel(const std::string& options, const char* name) {
    return kernel(kKernel_sculpt_blocks, options, name);
}

Device::ScanShape Device::scan_shape(bool gpu_shape) {
    const bool cpu = info.type == DeviceType::Cpu && !gpu_shape;
    ScanShape& shape = scan_shapes_[cpu ? 0 : 1];
    if (shape.local == 0) {
        const std::size_t items = cpu ? kCpuScanItems : kScanItems;
        std::size_t limit = std::min<std::size_t>(cpu ? 1 : 256, device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>());
        for (const char* name : {"scan_blocks", "scan_add"})
            limit = std::min<std::size_t>(
                limit, scan_kernel(name, items).getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(device));
        const std::size_t local_mem = device.getInfo<CL_DEVICE_LOCAL_MEM_SIZE>();
        while (limit * sizeof(cl_uint) > local_mem / 2 && limit > 1) limit /= 2;
        std::size_t pow2 = 1;
        while (pow2 * 2 <= limit) pow2 *= 2;
        shape = {pow2, items};
    }
    return shape;
}

cl::Buffer& Device::buffer(unsigned id, std::size_t bytes) {
    bytes = std::max<std::size_t>(bytes, 16);
    auto it = buffers_.find(id);
    if (it != buffers_.end() && it->second.second >= bytes) return it->second.first;
    if (it != buffers_.end()) buffers_.erase(it);  // release the old one before allocating
    // Some headroom so that slightly larger chunks reuse the buffer, within the device limit.
    std::size_t size = std::min<std::size_t>(round_up(bytes + bytes / 8, 4096), info.max_allocation);
    size = std::max(size, bytes);
    cl::Buffer buffer(context, CL_MEM_READ_WRITE, size);
    ++allocations;
    return buffers_.emplace(id, std::make_pair(buffer, size)).first->second.first;
}

void Device::drop_buffers() { buffers_.clear(); }

void Device::release_memory() {
    drop_buffers();
    staging_.reset();
}

std::size_t Device::kept_bytes() const {
    std::size_t bytes = staging_ ? 2 * staging_->block_bytes() : 0;
    for (const auto& [id, buffer] : buffers_) bytes += buffer.second;
    return bytes;
}

// Devices discovered (and perhaps opened) by the process this one was forked from.
bool forked_since_discovery(const Registry& r) {
    return r.forked_while_discovering || (r.discovered && r.discovered_in != getpid() && !r.devices.empty());
}

// discover(r) under the lock, marked as under way for the fork handlers.
void rediscover(Registry& r) {
    r.discovering = true;
    discover(r);
    r.discovering = false;
    r.discovered = true;
    r.discovered_in = getpid();
}

std::vector<std::shared_ptr<Device>> devices() {
    Registry& r = registry();
    const RegistryLock lock(r);
    if (forked_since_discovery(r)) return {};
    if (!r.discovered) rediscover(r);
    return r.devices;
}

bool devices_left_in_parent() {
    Registry& r = registry();
    const RegistryLock lock(r);
    return forked_since_discovery(r);
}

// The devices discovered so far, without discovering any (none in a forked child).
std::vector<std::shared_ptr<Device>> discovered_devices() {
    Registry& r = registry();
    const RegistryLock lock(r);
    if (!r.discovered || forked_since_discovery(r)) return {};
    return r.devices;
}

void release_kept_memory() {
    for (const auto& d : discovered_devices()) {
        // try_lock, not lock: a log callback runs while its extract holds the device, and
        // POSIX's trylock fails (defined) on a mutex the calling thread holds.
        std::unique_lock<std::mutex> device_lock(d->mutex, std::try_to_lock);
        if (device_lock.owns_lock()) d->release_memory();
    }
}

std::size_t kept_bytes() {
    std::size_t bytes = 0;
    for (const auto& d : discovered_devices()) {
        const std::lock_guard<std::mutex> device_lock(d->mutex);
        bytes += d->kept_bytes();
    }
    return bytes;
}

void with_device_registry_locked_for_testing(bool as_discovery, const std::function<void()>& f) {
    Registry& r = registry();
    const RegistryLock lock(r);
    const bool was = r.discovering;
    r.discovering = as_discovery;
    f();
    r.discovering = was;
}

std::string why_no_devices() {
    if (devices_left_in_parent())
        return "the OpenCL devices were opened before this process was forked, and a forked child cannot use "
               "them (the OpenCL runtime's threads stay in the parent)";
    return "no OpenCL platform or usable device was found";
}

void split_devices(bool split) {
    Registry& r = registry();
    const RegistryLock lock(r);
    if (r.discovered && r.split == split) return;
    // PoCL 3.1 releasing a sub-device's context soon after meshing on it crashes later, in a
    // worker thread (POclReleaseEvent), while other devices build and run; finishing its queue
    // first does not help. This test hook keeps the sub-devices it retires alive, their memory
    // freed, past the end of the process too (never destroyed: not at exit either).
    static auto* retired_sub_devices = new std::vector<std::shared_ptr<Device>>;
    if (r.split)
        for (const auto& d : r.devices) {
            d->release_memory();
            retired_sub_devices->push_back(d);
        }
    r.split = split;
    rediscover(r);
}

double event_seconds(const cl::Event& event) {
    const cl_ulong start = event.getProfilingInfo<CL_PROFILING_COMMAND_START>();
    const cl_ulong end = event.getProfilingInfo<CL_PROFILING_COMMAND_END>();
    return end > start ? static_cast<double>(end - start) * 1e-9 : 0.0;
}

void scan_into(Device& d, const cl::Buffer& data, std::size_t n, const cl::Buffer& totals, std::size_t total_at,
               EventLog& log, bool gpu_shape, unsigned level) {
    if (n == 0) {
        const cl_uint zero = 0;
        d.queue.enqueueFillBuffer(totals, zero, total_at * sizeof(cl_uint), sizeof(cl_uint), nullptr,
                                  &log.add(Pass::Transfer));
        return;
    }
    const auto [local, items] = d.scan_shape(gpu_shape);
    const std::size_t block = local * items;
    const std::size_t blocks = (n + block - 1) / block;
    cl::Buffer& sums = d.buffer(kScanBufferBase + level, blocks * sizeof(cl_uint));

    cl::Kernel& scan_blocks = d.scan_kernel("scan_blocks", items);
    set_args(scan_blocks, data, static_cast<cl_uint>(n), sums, cl::Local(local * sizeof(cl_uint)));
    d.queue.enqueueNDRangeKernel(scan_blocks, cl::NullRange, cl::NDRange(blocks * local), cl::NDRange(local),
                                 nullptr, &log.add(Pass::Scan));
    if (blocks == 1) {  // the one block's sum is the total
        d.queue.enqueueCopyBuffer(sums, totals, 0, total_at * sizeof(cl_uint), sizeof(cl_uint), nullptr,
                                  &log.add(Pass::Transfer));
        return;
    }
    scan_into(d, sums, blocks, totals, total_at, log, gpu_shape, level + 1);
    cl::Kernel& add = d.scan_kernel("scan_add", items);
    set_args(add, data, static_cast<cl_uint>(n), sums);
    d.queue.enqueueNDRangeKernel(add, cl::NullRange, cl::NDRange(blocks * local), cl::NDRange(local), nullptr,
                                 &log.add(Pass::Scan));
}

std::uint64_t scan(Device& d, const cl::Buffer& data, std::size_t n, EventLog& log, bool gpu_shape) {
    if (n == 0) return 0;
    cl::Buffer& total = d.buffer(kScanTotal, sizeof(cl_uint));
    scan_into(d, data, n, total, 0, log, gpu_shape);
    cl_uint value = 0;
    d.queue.enqueueReadBuffer(total, CL_TRUE, 0, sizeof(value), &value, nullptr, &log.add(Pass::Transfer));
    return value;
}

cl_uint set_arg(cl::Kernel& k, cl_uint i, const ArgVertexFormula& a) {
    const auto real = [&](double value) {
        if (a.fp64) k.setArg(i++, value);
        else k.setArg(i++, static_cast<cl_float>(value));
    };
    real(a.iso);
    // iso - v without fp64: integer samples subtract from iso's integer part exactly (in
    // range: only a threshold some sample crosses reaches the kernels); float samples from iso
    // rounded to float, adding back what the rounding left.
    const double whole = std::floor(a.iso);
    const double left = a.fp64 ? 0 : a.integer_samples ? a.iso - whole : a.iso - static_cast<float>(a.iso);
    k.setArg(i++, static_cast<cl_long>(a.integer_samples ? whole : 0));
    k.setArg(i++, static_cast<cl_float>(left));
    for (const auto* values : {&a.origin, &a.spacing})
        for (double v : *values) real(v);
    for (double v : a.spacing) real(1 / v);
    return i;
}

bool is_out_of_memory(cl_int code) {
    return code == CL_MEM_OBJECT_ALLOCATION_FAILURE || code == CL_OUT_OF_RESOURCES ||
           code == CL_OUT_OF_HOST_MEMORY || code == CL_INVALID_BUFFER_SIZE;
}

std::string error_name(cl_int code) {
    const char* name = nullptr;
    switch (code) {
        case CL_DEVICE_NOT_FOUND: name = "CL_DEVICE_NOT_FOUND"; break;
        case CL_DEVICE_NOT_AVAILABLE: name = "CL_DEVICE_NOT_AVAILABLE"; break;
        case CL_COMPILER_NOT_AVAILABLE: name = "CL_COMPILER_NOT_AVAILABLE"; break;
        case CL_MEM_OBJECT_ALLOCATION_FAILURE: name = "CL_MEM_OBJECT_ALLOCATION_FAILURE"; break;
        case CL_OUT_OF_RESOURCES: name = "CL_OUT_OF_RESOURCES"; break;
        case CL_OUT_OF_HOST_MEMORY: name = "CL_OUT_OF_HOST_MEMORY"; break;
        case CL_BUILD_PROGRAM_FAILURE: name = "CL_BUILD_PROGRAM_FAILURE"; break;
        case CL_INVALID_VALUE: name = "CL_INVALID_VALUE"; break;
        case CL_INVALID_BUFFER_SIZE: name = "CL_INVALID_BUFFER_SIZE"; break;
        case CL_INVALID_BUILD_OPTIONS: name = "CL_INVALID_BUILD_OPTIONS"; break;
        case CL_INVALID_KERNEL_NAME: name = "CL_INVALID_KERNEL_NAME"; break;
        case CL_INVALID_KERNEL_ARGS: name = "CL_INVALID_KERNEL_ARGS"; break;
        case CL_INVALID_ARG_SIZE: name = "CL_INVALID_ARG_SIZE"; break;
        case CL_INVALID_WORK_GROUP_SIZE: name = "CL_INVALID_WORK_GROUP_SIZE"; break;
        case CL_INVALID_GLOBAL_WORK_SIZE: name = "CL_INVALID_GLOBAL_WORK_SIZE"; break;
        case CL_INVALID_OPERATION: name = "CL_INVALID_OPERATION"; break;
        // What a failing or reset device gives at any call (seen from GPU drivers).
        case CL_MAP_FAILURE: name = "CL_MAP_FAILURE"; break;
        case CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST: name = "CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST"; break;
        case CL_INVALID_DEVICE: name = "CL_INVALID_DEVICE"; break;
        case CL_INVALID_CONTEXT: name = "CL_INVALID_CONTEXT"; break;
        case CL_INVALID_COMMAND_QUEUE: name = "CL_INVALID_COMMAND_QUEUE"; break;
        case CL_INVALID_HOST_PTR: name = "CL_INVALID_HOST_PTR"; break;
        case CL_INVALID_MEM_OBJECT: name = "CL_INVALID_MEM_OBJECT"; break;
        case CL_INVALID_PROGRAM_EXECUTABLE: name = "CL_INVALID_PROGRAM_EXECUTABLE"; break;
        case CL_INVALID_KERNEL: name = "CL_INVALID_KERNEL"; break;
        case CL_INVALID_WORK_ITEM_SIZE: name = "CL_INVALID_WORK_ITEM_SIZE"; break;
        case CL_INVALID_EVENT_WAIT_LIST: name = "CL_INVALID_EVENT_WAIT_LIST"; break;
        case CL_INVALID_EVENT: name = "CL_INVALID_EVENT"; break;
        default: break;
    }
    return std::string(name ? name : "OpenCL error") + " (" + std::to_string(code) + ")";
}

}  // namespace voxmesh::detail::cl_engine
