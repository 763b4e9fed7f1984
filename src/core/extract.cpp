#include "cpu_engine.hpp"
#include "opencl_hook.hpp"

#include <voxmesh/voxmesh.hpp>

namespace voxmesh {

namespace {
void warn(const Options& options, Stats& stats, const std::string& message) {
    stats.warnings.push_back(message);
    if (options.log) options.log(message);
}
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
        case Backend::Auto:
            if (detail::opencl_devices().empty()) {
                warn(options, stats, std::string("no usable OpenCL device; ") + backend_name(options.backend) +
                                         " backend runs the CPU engine");
                return detail::cpu_extract(volume, options, stats);
            }
            if (options.backend == Backend::Hybrid) return detail::opencl_extract(volume, options, stats, true);
            // Auto: on a machine whose only OpenCL device is the CPU itself, the CPU engine is faster.
            return detail::cpu_extract(volume, options, stats);
    }
    throw Error("unknown backend");
}

std::vector<DeviceInfo> list_devices() { return detail::opencl_devices(); }
bool opencl_available() { return !detail::opencl_devices().empty(); }

}  // namespace voxmesh
