// voxmesh devices: every OpenCL platform/device with its key limits, and the CPU.
#include "common.hpp"
#include "core/parallel.hpp"

#include <fstream>
#include <iostream>
#include <thread>

namespace voxmesh::cli {

namespace {

std::string cpu_model() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) {
            const auto colon = line.find(':');
            if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
        }
    return "unknown CPU";
}

int run_devices() {
    const unsigned threads = std::thread::hardware_concurrency();
    const unsigned usable = voxmesh::detail::resolve_threads(0);
    std::cout << "CPU: " << cpu_model() << ", " << (threads ? std::to_string(threads) : "unknown")
              << " hardware threads, " << usable
              << " of them usable by this process (its affinity and CPU quota): the cpu backend's default thread "
                 "count\n";
    const std::vector<DeviceInfo> devices = list_devices();
    if (devices.empty()) {
        std::cout << "OpenCL: no usable device (no platform found, or voxmesh built without OpenCL); the "
                     "opencl and hybrid backends are unavailable, auto uses the CPU\n";
        return kExitOk;
    }
    std::string platform;
    for (const DeviceInfo& d : devices) {
        if (d.platform != platform) {
            platform = d.platform;
            std::cout << "OpenCL platform: " << platform << "\n";
        }
        std::cout << "  [" << d.index << "] " << d.name << " (" << device_type_name(d.type) << ", " << d.version
                  << "): " << d.compute_units << " compute units, " << format_bytes(d.global_memory)
                  << " global memory, " << format_bytes(d.max_allocation) << " max allocation, fp64 "
                  << (d.fp64 ? "yes" : "no") << (d.host_memory ? ", shares host memory (zero-copy input)" : "")
                  << "\n";
    }
    return kExitOk;
}

}  // namespace

Command add_devices(CLI::App& app) {
    CLI::App* sub = app.add_subcommand("devices", "List the OpenCL devices (use the index with mesh --device) and the CPU");
    return {sub, [] { return run_devices(); }};
}

}  // namespace voxmesh::cli
