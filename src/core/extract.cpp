#include "cpu_engine.hpp"
#include "opencl_hook.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>

namespace voxmesh {

namespace {
void warn(const Options& options, Stats& stats, const std::string& message) {
    stats.warnings.push_back(message);
    if (options.log) options.log(message);
}

bool is_discrete(const DeviceInfo& d) { return d.type == DeviceType::Gpu || d.type == DeviceType::Accelerator; }
}  // namespace

Mesh extract(const VolumeView& volume, const Options& options) {
    Stats stats;
    return extract(volume, options, stats);
}

Mesh extract(const VolumeView& volume, const Options& options, Stats& stats) {
    stats = Stats{};
    detail::validate_volume(volume);
    switch (options.backend) {
        case Backend::Cpu:
            return detail::cpu_extract(volume, options, stats);
        case Backend::OpenCL:
            return detail::opencl_extract(volume, options, stats, false);
        case Backend::Hybrid:
        case Backend::Auto: {
            const auto devices = detail::opencl_devices();
            if (devices.empty()) {
                warn(options, stats, std::string("no usable OpenCL device (no OpenCL platform found); ") +
                                         backend_name(options.backend) + " backend runs the CPU engine");
                return detail::cpu_extract(volume, options, stats);
            }
            if (options.backend == Backend::Hybrid) return detail::opencl_extract(volume, options, stats, true);
            // Auto with devices chosen explicitly: those devices.
            if (!options.devices.empty() || options.device_type != DeviceType::Any)
                return detail::opencl_extract(volume, options, stats, false);
            // Auto: a GPU or accelerator meshes faster than the CPU's threads; an OpenCL device
            // that is the CPU itself (PoCL) is slower than the CPU engine, so that one is not used.
            if (std::any_of(devices.begin(), devices.end(), is_discrete)) {
                Options gpu = options;
                gpu.device_type = std::find_if(devices.begin(), devices.end(), [](const DeviceInfo& d) {
                                      return d.type == DeviceType::Gpu;
                                  }) != devices.end()
                                      ? DeviceType::Gpu
                                      : DeviceType::Accelerator;
                return detail::opencl_extract(volume, gpu, stats, false);
            }
            return detail::cpu_extract(volume, options, stats);
        }
    }
    throw Error("unknown backend");
}

std::vector<DeviceInfo> list_devices() { return detail::opencl_devices(); }
bool opencl_available() { return !detail::opencl_devices().empty(); }

}  // namespace voxmesh
