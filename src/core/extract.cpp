#include "cpu_engine.hpp"
#include "dims_text.hpp"
#include "float_extent.hpp"
#include "opencl_hook.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cstdio>
#include <new>
#include <string>
#include <utility>

namespace voxmesh {

namespace {
void warn(const Options& options, Stats& stats, const std::string& message) {
    stats.warnings.push_back(message);
    if (options.log) options.log(message);
}

bool is_discrete(const DeviceInfo& d) { return d.type == DeviceType::Gpu || d.type == DeviceType::Accelerator; }

std::string number_text(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", value);
    return text;
}

// Vertices are floats: far from 0 a tiny spacing leaves them few positions between samples.
void warn_if_too_fine(const VolumeView& volume, const Options& options, Stats& stats) {
    const int a = detail::axis_too_fine_for_float(volume.dims, volume.spacing, volume.origin);
    if (a < 0) return;
    const auto au = static_cast<std::size_t>(a);
    const double far = detail::farthest_from_zero(volume.origin[au], volume.spacing[au], volume.dims[au]);
    warn(options, stats,
         std::string("spacing ") + number_text(volume.spacing[au]) + " along " + "xyz"[a] +
             " is too fine for float vertex coordinates as far from 0 as " + number_text(far) +
             ": vertices snap to steps of up to " + number_text(detail::float_step_near(far)) +
             " (an origin nearer 0, or larger units, keeps their precision)");
}

// The engine options.backend picks; the result reuses `storage`'s arrays.
Mesh pick_engine(const VolumeView& volume, const Options& options, Stats& stats, Mesh storage) {
    detail::validate_volume(volume);
    warn_if_too_fine(volume, options, stats);
    switch (options.backend) {
        case Backend::Cpu:
            return detail::cpu_extract(volume, options, stats, std::move(storage));
        case Backend::OpenCL:
            return detail::opencl_extract(volume, options, stats, false, std::move(storage));
        case Backend::Hybrid:
        case Backend::Auto: {
            const auto devices = detail::opencl_devices();
            if (devices.empty()) {
                warn(options, stats, std::string("no usable OpenCL device (no OpenCL platform found); ") +
                                         backend_name(options.backend) + " backend runs the CPU engine");
                return detail::cpu_extract(volume, options, stats, std::move(storage));
            }
            if (options.backend == Backend::Hybrid)
                return detail::opencl_extract(volume, options, stats, true, std::move(storage));
            // Auto with devices chosen explicitly: those devices.
            if (!options.devices.empty() || options.device_type != DeviceType::Any)
                return detail::opencl_extract(volume, options, stats, false, std::move(storage));
            // Auto: a GPU or accelerator meshes faster than the CPU's threads; an OpenCL device
            // that is the CPU itself (PoCL) is slower than the CPU engine, so that one is not used.
            if (std::any_of(devices.begin(), devices.end(), is_discrete)) {
                Options gpu = options;
                gpu.device_type = std::find_if(devices.begin(), devices.end(), [](const DeviceInfo& d) {
                                      return d.type == DeviceType::Gpu;
                                  }) != devices.end()
                                      ? DeviceType::Gpu
                                      : DeviceType::Accelerator;
                return detail::opencl_extract(volume, gpu, stats, false, std::move(storage));
            }
            return detail::cpu_extract(volume, options, stats, std::move(storage));
        }
    }
    throw Error("unknown backend");
}

// Every failure is an Error: out of memory (the mesh, an engine's scratch) included.
Mesh run_engine(const VolumeView& volume, const Options& options, Stats& stats, Mesh storage) {
    stats = Stats{};
    try {
        return pick_engine(volume, options, stats, std::move(storage));
    } catch (const detail::NonFiniteSamples& e) {
        // The slab, chunk or device that saw one first depends on the schedule; the volume's
        // first such plane does not.
        const std::size_t first = detail::first_non_finite_plane(volume);
        if (first < e.plane) detail::throw_non_finite(first);
        throw;
    } catch (const std::bad_alloc&) {
        throw OutOfMemoryError("out of memory meshing a " + detail::dims_text(volume.dims) +
                    " volume (the mesh and the engine's working memory)");
    }
}

}  // namespace

Mesh extract(const VolumeView& volume, const Options& options) {
    Stats stats;
    return extract(volume, options, stats);
}

Mesh extract(const VolumeView& volume, const Options& options, Stats& stats) {
    return run_engine(volume, options, stats, Mesh{});
}

void extract_into(const VolumeView& volume, const Options& options, Mesh& mesh, Stats& stats) {
    Mesh storage = std::move(mesh);
    mesh = Mesh{};  // left empty if meshing throws
    mesh = run_engine(volume, options, stats, std::move(storage));
}

void release_scratch_memory() {
    detail::release_scratch();
    detail::opencl_release_memory();
}

std::vector<DeviceInfo> list_devices() { return detail::opencl_devices(); }
bool opencl_available() { return !detail::opencl_devices().empty(); }

}  // namespace voxmesh
