// The C API (include/voxmesh/voxmesh.h): thin wrappers that turn arguments into the C++ API's
// types and every exception into a status plus a per-thread message.
#include <voxmesh/io.hpp>
#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxelize.hpp>
#include <voxmesh/voxmesh.h>
#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <array>
#include <cstring>
#include <functional>
#include <istream>
#include <iterator>
#include <memory>
#include <new>
#include <optional>
#include <streambuf>
#include <string>
#include <utility>
#include <vector>

struct voxmesh_mesh {
    voxmesh::Mesh mesh;
    voxmesh::Stats stats{};  // of the extract that made it
    std::string warnings{};  // stats.warnings, one a line
    bool extracted = false;  // made by voxmesh_extract: stats and warnings are its
};

struct voxmesh_volume {
    voxmesh::Volume volume;
    voxmesh::VolumeInfo info{};  // what the file said; format "" when not read from one
};

struct voxmesh_bytes {
    std::vector<unsigned char> bytes;
};

struct voxmesh_sculpt {
    voxmesh::Sculpt sculpt;
    std::shared_ptr<std::string> warnings;  // what SculptOptions::log was told, one a line
    voxmesh::UpdateResult last_update{};    // keeps voxmesh_update_result::changed alive
    mutable std::string device_name{};      // keeps voxmesh_sculpt_device_name's text alive
};

namespace {

thread_local std::string g_last_error;

// const char*, not std::string: a string made in guarded()'s catch handler could throw there.
voxmesh_status fail(voxmesh_status status, const char* message) noexcept {
    try {
        g_last_error = message;
    } catch (...) {
        g_last_error.clear();  // no memory even for the message: the status still tells
    }
    return status;
}

// Runs `body`, mapping what it throws to a status and the calling thread's message.
template <class Body>
voxmesh_status guarded(Body&& body) noexcept {
    try {
        body();
        return VOXMESH_OK;
    } catch (const voxmesh::OutOfMemoryError& e) {
        return fail(VOXMESH_OUT_OF_MEMORY, e.what());
    } catch (const voxmesh::Error& e) {
        return fail(VOXMESH_ERROR, e.what());
    } catch (const std::bad_alloc&) {
        return fail(VOXMESH_OUT_OF_MEMORY, "out of memory");
    } catch (const std::exception& e) {
        return fail(VOXMESH_INTERNAL, e.what());
    } catch (...) {
        return fail(VOXMESH_INTERNAL, "unknown exception");
    }
}

void require(const void* pointer, const char* who, const char* what) {
    if (!pointer) throw voxmesh::Error(std::string(who) + ": " + what + " is NULL");
}

voxmesh::ScalarType scalar_type(int type, const char* who) {
    using voxmesh::ScalarType;
    static constexpr ScalarType kTypes[] = {ScalarType::U8,  ScalarType::I8,  ScalarType::U16, ScalarType::I16,
                                            ScalarType::U32, ScalarType::I32, ScalarType::F32, ScalarType::F64};
    if (type < 0 || type >= static_cast<int>(std::size(kTypes)))
        throw voxmesh::Error(std::string(who) + ": unknown scalar type " + std::to_string(type) +
                             " (VOXMESH_U8 .. VOXMESH_F64)");
    return kTypes[type];
}

int scalar_code(voxmesh::ScalarType type) {
    using voxmesh::ScalarType;
    switch (type) {
        case ScalarType::U8: return VOXMESH_U8;
        case ScalarType::I8: return VOXMESH_I8;
        case ScalarType::U16: return VOXMESH_U16;
        case ScalarType::I16: return VOXMESH_I16;
        case ScalarType::U32: return VOXMESH_U32;
        case ScalarType::I32: return VOXMESH_I32;
        case ScalarType::F32: return VOXMESH_F32;
        case ScalarType::F64: return VOXMESH_F64;
    }
    return -1;
}

voxmesh::Backend backend(int code, const char* who) {
    using voxmesh::Backend;
    switch (code) {
        case VOXMESH_BACKEND_AUTO: return Backend::Auto;
        case VOXMESH_BACKEND_CPU: return Backend::Cpu;
        case VOXMESH_BACKEND_OPENCL: return Backend::OpenCL;
        case VOXMESH_BACKEND_HYBRID: return Backend::Hybrid;
        default:
            throw voxmesh::Error(std::string(who) + ": unknown backend " + std::to_string(code) +
                                 " (VOXMESH_BACKEND_AUTO, _CPU, _OPENCL or _HYBRID)");
    }
}

int backend_code(voxmesh::Backend backend) {
    using voxmesh::Backend;
    switch (backend) {
        case Backend::Auto: return VOXMESH_BACKEND_AUTO;
        case Backend::Cpu: return VOXMESH_BACKEND_CPU;
        case Backend::OpenCL: return VOXMESH_BACKEND_OPENCL;
        case Backend::Hybrid: return VOXMESH_BACKEND_HYBRID;
    }
    return VOXMESH_BACKEND_AUTO;
}

voxmesh::DeviceType device_type(int code, const char* who) {
    using voxmesh::DeviceType;
    switch (code) {
        case VOXMESH_DEVICE_ANY: return DeviceType::Any;
        case VOXMESH_DEVICE_CPU: return DeviceType::Cpu;
        case VOXMESH_DEVICE_GPU: return DeviceType::Gpu;
        case VOXMESH_DEVICE_ACCELERATOR: return DeviceType::Accelerator;
        default:
            throw voxmesh::Error(std::string(who) + ": unknown device type " + std::to_string(code) +
                                 " (VOXMESH_DEVICE_ANY, _CPU, _GPU or _ACCELERATOR)");
    }
}

int device_type_code(voxmesh::DeviceType type) {
    using voxmesh::DeviceType;
    switch (type) {
        case DeviceType::Any: return VOXMESH_DEVICE_ANY;
        case DeviceType::Cpu: return VOXMESH_DEVICE_CPU;
        case DeviceType::Gpu: return VOXMESH_DEVICE_GPU;
        case DeviceType::Accelerator: return VOXMESH_DEVICE_ACCELERATOR;
    }
    return VOXMESH_DEVICE_ANY;
}

// Copies `text` into a fixed field, cut to fit and always terminated.
template <std::size_t N>
void copy_text(char (&field)[N], const std::string& text) {
    const std::size_t n = std::min(text.size(), N - 1);
    std::memcpy(field, text.data(), n);
    field[n] = '\0';
}

// dims, spacing and origin between a C view and a C++ volume or view (same field names).
template <class From, class To>
void copy_geometry(const From& from, To& to) {
    for (int a = 0; a < 3; ++a) {
        to.dims[a] = from.dims[a];
        to.spacing[a] = from.spacing[a];
        to.origin[a] = from.origin[a];
    }
}

// A vector's or span's first element; NULL when it is empty (the C API's "no array").
template <class Array>
auto data_or_null(const Array& array) -> decltype(array.data()) {
    return array.empty() ? nullptr : array.data();
}

// A C view as the C++ one (the type checked).
voxmesh::VolumeView cpp_view(const voxmesh_volume_view& volume, const char* who) {
    voxmesh::VolumeView view;
    view.data = volume.data;
    view.type = scalar_type(volume.type, who);
    copy_geometry(volume, view);
    return view;
}

// A C++ view as the C one (volume_get_view, sculpt_get_view).
voxmesh_volume_view c_view(const voxmesh::VolumeView& v) {
    voxmesh_volume_view view{};
    view.data = v.data;
    view.type = scalar_code(v.type);
    copy_geometry(v, view);
    return view;
}

// voxmesh::extract_into behind voxmesh_extract and voxmesh_extract_into: `mesh` gets the
// canonical mesh, what the extract did and its warnings; on an exception it is left empty.
void extract_into(const voxmesh_volume_view* volume, const voxmesh_options* options, voxmesh_mesh& mesh,
                  const char* who) {
    mesh.extracted = false;
    mesh.stats = voxmesh::Stats{};
    mesh.warnings.clear();
    mesh.mesh.positions.clear();  // left empty if a check below throws, as extract_into leaves it
    mesh.mesh.normals.clear();
    mesh.mesh.indices.clear();
    require(volume, who, "the volume");
    const voxmesh_options given = options ? *options : voxmesh_default_options();
    const voxmesh::VolumeView view = cpp_view(*volume, who);
    voxmesh::Options cpp;
    cpp.iso = given.iso;
    cpp.backend = backend(given.backend, who);
    cpp.threads = given.threads;
    cpp.normals = given.normals != 0;
    cpp.inside_below = given.inside_below != 0;
    if (given.device_count) require(given.devices, who, "options->devices");
    cpp.devices.assign(given.devices, given.devices + given.device_count);
    cpp.device_type = device_type(given.device_type, who);
    cpp.chunk_planes = given.chunk_planes;
    cpp.memory_budget = given.memory_budget;
    voxmesh::extract_into(view, cpp, mesh.mesh, mesh.stats);
    for (const std::string& w : mesh.stats.warnings) mesh.warnings += w + "\n";
    mesh.extracted = true;
}

// C sculpt options to the C++ ones, with a log that keeps the warnings for the C caller.
voxmesh::SculptOptions sculpt_options(const voxmesh_sculpt_options& given, const std::shared_ptr<std::string>& warnings,
                                      const char* who) {
    voxmesh::SculptOptions cpp;
    cpp.iso = given.iso;
    cpp.threads = given.threads;
    cpp.block_size = given.block_size;
    cpp.normals = given.normals != 0;
    cpp.inside_below = given.inside_below != 0;
    cpp.strength_scale = given.strength_scale;
    cpp.backend = backend(given.backend, who);
    cpp.device = given.device;
    cpp.log = [warnings](const std::string& message) { *warnings += message + "\n"; };
    return cpp;
}

// *sculpt := the sculpt make(C++ options) builds from the C options (NULL: the defaults), with a
// log that keeps its warnings for the C caller.
template <class Make>
void new_sculpt(voxmesh_sculpt** sculpt, const voxmesh_sculpt_options* options, const char* who, const Make& make) {
    auto warnings = std::make_shared<std::string>();
    const voxmesh_sculpt_options given = options ? *options : voxmesh_default_sculpt_options();
    voxmesh::Sculpt made = make(sculpt_options(given, warnings, who));
    *sculpt = new voxmesh_sculpt{std::move(made), std::move(warnings)};
}

voxmesh::Units units(int code, const char* who) {
    if (code == VOXMESH_UNITS_SAMPLES) return voxmesh::Units::Samples;
    if (code == VOXMESH_UNITS_WORLD) return voxmesh::Units::World;
    throw voxmesh::Error(std::string(who) + ": unknown units " + std::to_string(code) +
                         " (VOXMESH_UNITS_SAMPLES or VOXMESH_UNITS_WORLD)");
}

std::array<double, 3> point(const double* xyz) { return {xyz[0], xyz[1], xyz[2]}; }

// The caller's bytes as a stream's buffer, read in place (no copy of a long script).
struct MemoryBuffer : std::streambuf {
    MemoryBuffer(const char* data, std::size_t size) {
        char* begin = const_cast<char*>(data);  // only read: a get area is char*
        setg(begin, begin, begin + (data ? size : 0));
    }
};

// The brushes in voxmesh_brush's order: a code is an index.
constexpr voxmesh::BrushOp kBrushes[] = {voxmesh::BrushOp::Add, voxmesh::BrushOp::Subtract, voxmesh::BrushOp::Smooth,
                                         voxmesh::BrushOp::Set};
static_assert(VOXMESH_BRUSH_ADD == 0 && VOXMESH_BRUSH_SUBTRACT == 1 && VOXMESH_BRUSH_SMOOTH == 2 && VOXMESH_BRUSH_SET == 3);

voxmesh::BrushOp brush(int code, const char* who) {
    if (code < 0 || code >= static_cast<int>(std::size(kBrushes)))
        throw voxmesh::Error(std::string(who) + ": unknown brush " + std::to_string(code) +
                             " (VOXMESH_BRUSH_ADD, _SUBTRACT, _SMOOTH or _SET)");
    return kBrushes[code];
}

int code_of(voxmesh::BrushOp op) {
    return static_cast<int>(std::find(std::begin(kBrushes), std::end(kBrushes), op) - std::begin(kBrushes));
}

// run_strokes with each frame told to the C callback; a nonzero answer stops the run as an Error.
void run_script(voxmesh_sculpt& sculpt, const std::vector<voxmesh::ScriptDab>& dabs, voxmesh_stroke_callback on_frame,
                void* user, const char* who) {
    std::function<void(const voxmesh::StrokeFrame&)> tell;
    if (on_frame)
        tell = [&](const voxmesh::StrokeFrame& f) {
            voxmesh_stroke_frame c{};
            c.frame = f.frame;
            c.line = f.dab.line;
            c.brush = code_of(f.dab.dab.op);
            c.units = f.dab.units == voxmesh::Units::World ? VOXMESH_UNITS_WORLD : VOXMESH_UNITS_SAMPLES;
            for (int a = 0; a < 3; ++a) c.center[a] = f.dab.dab.center[a];
            c.radius = f.dab.dab.radius;
            c.strength = f.dab.dab.strength;
            c.edit_seconds = f.edit_seconds;
            c.update_seconds = f.update_seconds;
            c.blocks_changed = f.blocks_changed;
            c.blocks_remeshed = f.blocks_remeshed;
            if (on_frame(&c, user) != 0)
                throw voxmesh::Error(std::string(who) + ": on_frame stopped the strokes after frame " +
                                     std::to_string(f.frame) + " (line " + std::to_string(f.dab.line) + ")");
        };
    voxmesh::run_strokes(sculpt.sculpt, dabs, tell);
}

voxmesh::VoxelizeOptions voxelize_options(const voxmesh_voxelize_options& given, const char* who) {
    voxmesh::VoxelizeOptions cpp;
    cpp.resolution = given.resolution;
    cpp.padding = given.padding;
    if (given.field == VOXMESH_FIELD_OCCUPANCY) cpp.field = voxmesh::VoxelField::Occupancy;
    else if (given.field == VOXMESH_FIELD_DISTANCE) cpp.field = voxmesh::VoxelField::Distance;
    else
        throw voxmesh::Error(std::string(who) + ": unknown field " + std::to_string(given.field) +
                             " (VOXMESH_FIELD_OCCUPANCY or VOXMESH_FIELD_DISTANCE)");
    cpp.band = given.band;
    cpp.threads = given.threads;
    if (given.fill == VOXMESH_FILL_EVENODD) cpp.fill = voxmesh::FillRule::EvenOdd;
    else if (given.fill == VOXMESH_FILL_NONZERO) cpp.fill = voxmesh::FillRule::NonZero;
    else
        throw voxmesh::Error(std::string(who) + ": unknown fill rule " + std::to_string(given.fill) +
                             " (VOXMESH_FILL_EVENODD or VOXMESH_FILL_NONZERO)");
    return cpp;
}

// A list query of a volume (query(view, room): voxmesh::vertex_edges_into, triangle_cells_into)
// as the C calls promise: *count always, the entries only where `capacity` holds them all, else
// an error naming both.
template <class Query>
void list_out(const voxmesh_volume_view* volume, const char* who, const char* what, const char* of_what, uint64_t* out,
              size_t capacity, size_t* count, const Query& query) {
    require(count, who, "the count pointer");
    require(volume, who, "the volume");
    *count = query(cpp_view(*volume, who), std::span<std::uint64_t>(out, out ? capacity : 0));
    if (out && capacity < *count)
        throw voxmesh::Error(std::string(who) + ": room for " + std::to_string(capacity) + " " + what + ", but the volume has " +
                             std::to_string(*count) + " " + of_what);
}

}  // namespace

extern "C" {

voxmesh_options voxmesh_default_options(void) {
    const voxmesh::Options defaults;
    voxmesh_options options{};
    options.iso = defaults.iso;
    options.backend = backend_code(defaults.backend);
    options.threads = defaults.threads;
    options.normals = defaults.normals;
    options.inside_below = defaults.inside_below;
    options.devices = nullptr;
    options.device_count = 0;
    options.device_type = device_type_code(defaults.device_type);
    options.chunk_planes = defaults.chunk_planes;
    options.memory_budget = defaults.memory_budget;
    return options;
}

void voxmesh_release_scratch_memory(void) {
    try {
        voxmesh::release_scratch_memory();
    } catch (...) {
        // Nothing to report: whatever was not freed stays kept, as before the call.
    }
}

size_t voxmesh_device_count(void) {
    try {
        return voxmesh::list_devices().size();
    } catch (...) {
        return 0;
    }
}

voxmesh_status voxmesh_get_device(size_t index, voxmesh_device* device) {
    return guarded([&] {
        require(device, "voxmesh_get_device", "the device pointer");
        const std::vector<voxmesh::DeviceInfo> devices = voxmesh::list_devices();
        if (index >= devices.size())
            throw voxmesh::Error("voxmesh_get_device: device " + std::to_string(index) + " does not exist (" +
                                 std::to_string(devices.size()) + " OpenCL device(s))");
        const voxmesh::DeviceInfo& d = devices[index];
        *device = voxmesh_device{};
        device->index = d.index;
        device->type = device_type_code(d.type);
        device->compute_units = d.compute_units;
        device->global_memory = d.global_memory;
        device->max_allocation = d.max_allocation;
        device->fp64 = d.fp64;
        device->host_memory = d.host_memory;
        copy_text(device->platform, d.platform);
        copy_text(device->name, d.name);
        copy_text(device->version, d.version);
    });
}

voxmesh_status voxmesh_extract(const voxmesh_volume_view* volume, const voxmesh_options* options,
                               voxmesh_mesh** mesh) {
    if (mesh) *mesh = nullptr;
    return guarded([&] {
        require(mesh, "voxmesh_extract", "the mesh pointer");
        auto made = std::make_unique<voxmesh_mesh>();
        extract_into(volume, options, *made, "voxmesh_extract");
        *mesh = made.release();
    });
}

voxmesh_status voxmesh_extract_into(const voxmesh_volume_view* volume, const voxmesh_options* options,
                                    voxmesh_mesh* mesh) {
    return guarded([&] {
        require(mesh, "voxmesh_extract_into", "the mesh");
        extract_into(volume, options, *mesh, "voxmesh_extract_into");
    });
}

size_t voxmesh_mesh_vertex_count(const voxmesh_mesh* mesh) { return mesh ? mesh->mesh.vertex_count() : 0; }
size_t voxmesh_mesh_triangle_count(const voxmesh_mesh* mesh) { return mesh ? mesh->mesh.triangle_count() : 0; }
const float* voxmesh_mesh_positions(const voxmesh_mesh* mesh) {
    return mesh ? data_or_null(mesh->mesh.positions) : nullptr;
}
const float* voxmesh_mesh_normals(const voxmesh_mesh* mesh) {
    return mesh ? data_or_null(mesh->mesh.normals) : nullptr;
}
const uint32_t* voxmesh_mesh_indices(const voxmesh_mesh* mesh) {
    return mesh ? data_or_null(mesh->mesh.indices) : nullptr;
}
void voxmesh_mesh_free(voxmesh_mesh* mesh) { delete mesh; }

voxmesh_stats voxmesh_mesh_stats(const voxmesh_mesh* mesh) {
    voxmesh_stats out{};
    out.backend = VOXMESH_BACKEND_AUTO;
    if (!mesh || !mesh->extracted) return out;
    const voxmesh::Stats& s = mesh->stats;
    out.backend = backend_code(s.backend);
    out.threads = s.threads;
    out.workers = s.workers;
    out.classify_s = s.times.classify;
    out.scan_s = s.times.scan;
    out.generate_s = s.times.generate;
    out.total_s = s.times.total;
    return out;
}

const char* voxmesh_mesh_warnings(const voxmesh_mesh* mesh) { return mesh ? mesh->warnings.c_str() : ""; }

size_t voxmesh_mesh_device_stats_count(const voxmesh_mesh* mesh) {
    return mesh && mesh->extracted ? mesh->stats.devices.size() : 0;
}

voxmesh_status voxmesh_mesh_get_device_stats(const voxmesh_mesh* mesh, size_t index, voxmesh_device_stats* stats) {
    return guarded([&] {
        require(mesh, "voxmesh_mesh_get_device_stats", "the mesh");
        require(stats, "voxmesh_mesh_get_device_stats", "the stats pointer");
        const std::size_t count = voxmesh_mesh_device_stats_count(mesh);
        if (index >= count)
            throw voxmesh::Error("voxmesh_mesh_get_device_stats: device " + std::to_string(index) +
                                 " did not take part (" + std::to_string(count) + " device(s) in the extract)");
        const voxmesh::DeviceStats& d = mesh->stats.devices[index];
        *stats = voxmesh_device_stats{};
        copy_text(stats->name, d.name);
        stats->chunks = d.chunks;
        stats->voxels = d.voxels;
        stats->kernel_s = d.kernel_s;
        stats->transfer_s = d.transfer_s;
        stats->wall_s = d.wall_s;
        stats->setup_s = d.setup_s;
        stats->programs_built = d.programs_built;
        stats->chunks_handed_over = d.chunks_handed_over;
    });
}

const unsigned char* voxmesh_bytes_data(const voxmesh_bytes* bytes) {
    return bytes ? data_or_null(bytes->bytes) : nullptr;
}
size_t voxmesh_bytes_size(const voxmesh_bytes* bytes) { return bytes ? bytes->bytes.size() : 0; }
void voxmesh_bytes_free(voxmesh_bytes* bytes) { delete bytes; }

voxmesh_status voxmesh_write_mesh_to_memory(const voxmesh_mesh* mesh, const char* name, voxmesh_bytes** bytes) {
    if (bytes) *bytes = nullptr;
    return guarded([&] {
        require(bytes, "voxmesh_write_mesh_to_memory", "the bytes pointer");
        require(mesh, "voxmesh_write_mesh_to_memory", "the mesh");
        require(name, "voxmesh_write_mesh_to_memory", "the name");
        *bytes = new voxmesh_bytes{voxmesh::write_mesh_to_memory(mesh->mesh, name)};
    });
}

voxmesh_status voxmesh_read_mesh_from_memory(const void* data, size_t size, const char* name, voxmesh_mesh** mesh) {
    if (mesh) *mesh = nullptr;
    return guarded([&] {
        require(mesh, "voxmesh_read_mesh_from_memory", "the mesh pointer");
        require(name, "voxmesh_read_mesh_from_memory", "the name");
        if (size) require(data, "voxmesh_read_mesh_from_memory", "the data");
        *mesh = new voxmesh_mesh{voxmesh::read_mesh_from_memory(data, size, name)};
    });
}

voxmesh_status voxmesh_keep_largest_components(const voxmesh_mesh* mesh, size_t count, voxmesh_mesh** kept) {
    if (kept) *kept = nullptr;
    return guarded([&] {
        require(kept, "voxmesh_keep_largest_components", "the result pointer");
        require(mesh, "voxmesh_keep_largest_components", "the mesh");
        *kept = new voxmesh_mesh{voxmesh::keep_largest_components(mesh->mesh, count)};
    });
}

voxmesh_status voxmesh_compute_value_range(const voxmesh_volume_view* volume, const double* equal_to, unsigned threads,
                                           voxmesh_value_range* range) {
    if (range) *range = voxmesh_value_range{};
    return guarded([&] {
        const char* who = "voxmesh_compute_value_range";
        require(range, who, "the result pointer");
        require(volume, who, "the volume");
        const voxmesh::ValueRange r = voxmesh::value_range(
            cpp_view(*volume, who), equal_to ? std::optional<double>(*equal_to) : std::nullopt, threads);
        range->min = r.min;
        range->max = r.max;
        range->nonfinite = r.nonfinite;
        std::copy(r.first_nonfinite.begin(), r.first_nonfinite.end(), range->first_nonfinite);
        range->equal = r.equal;
    });
}

voxmesh_status voxmesh_vertex_edges(const voxmesh_volume_view* volume, double iso, unsigned threads, uint64_t* edges,
                                    size_t capacity, size_t* count) {
    if (count) *count = 0;
    return guarded([&] {
        list_out(volume, "voxmesh_vertex_edges", "edges", "crossed edges", edges, capacity, count,
                 [&](const voxmesh::VolumeView& view, std::span<std::uint64_t> room) {
                     return voxmesh::vertex_edges_into(view, iso, room, threads);
                 });
    });
}

voxmesh_status voxmesh_triangle_cells(const voxmesh_volume_view* volume, double iso, unsigned threads, uint64_t* cells,
                                      size_t capacity, size_t* count) {
    if (count) *count = 0;
    return guarded([&] {
        list_out(volume, "voxmesh_triangle_cells", "cells", "triangles", cells, capacity, count,
                 [&](const voxmesh::VolumeView& view, std::span<std::uint64_t> room) {
                     return voxmesh::triangle_cells_into(view, iso, room, threads);
                 });
    });
}

voxmesh_status voxmesh_edge_cell_ranges(const voxmesh_volume_view* volume, const uint64_t* edges, size_t count,
                                        double offset, const uint8_t* cell_mask, unsigned threads, float* ranges) {
    return guarded([&] {
        const char* who = "voxmesh_edge_cell_ranges";
        require(volume, who, "the volume");
        if (count) require(edges, who, "the edges");
        if (count) require(ranges, who, "the ranges");
        voxmesh::edge_cell_ranges_into(cpp_view(*volume, who), {edges, count}, {ranges, count}, offset, cell_mask, threads);
    });
}

voxmesh_status voxmesh_write_mesh(const char* path, const voxmesh_mesh* mesh) {
    return guarded([&] {
        require(path, "voxmesh_write_mesh", "the path");
        require(mesh, "voxmesh_write_mesh", "the mesh");
        voxmesh::write_mesh(path, mesh->mesh);
    });
}

voxmesh_status voxmesh_read_mesh(const char* path, voxmesh_mesh** mesh) {
    if (mesh) *mesh = nullptr;
    return guarded([&] {
        require(mesh, "voxmesh_read_mesh", "the mesh pointer");
        require(path, "voxmesh_read_mesh", "the path");
        *mesh = new voxmesh_mesh{voxmesh::read_mesh(path)};  // no stats: not extracted
    });
}

voxmesh_status voxmesh_mesh_from_arrays(const float* positions, size_t vertex_count, const uint32_t* indices,
                                        size_t triangle_count, voxmesh_mesh** mesh) {
    if (mesh) *mesh = nullptr;
    return guarded([&] {
        require(mesh, "voxmesh_mesh_from_arrays", "the mesh pointer");
        if (vertex_count) require(positions, "voxmesh_mesh_from_arrays", "positions");
        if (triangle_count) require(indices, "voxmesh_mesh_from_arrays", "indices");
        // What the vectors can hold (beyond that assign throws std::length_error, not an Error).
        const size_t most = std::min(std::vector<float>().max_size(), std::vector<uint32_t>().max_size()) / 3;
        if (vertex_count > most || triangle_count > most)
            throw voxmesh::Error("voxmesh_mesh_from_arrays: " + std::to_string(std::max(vertex_count, triangle_count)) +
                                 " elements cannot be addressed");
        voxmesh::Mesh copy;
        copy.positions.assign(positions, positions + 3 * vertex_count);
        copy.indices.assign(indices, indices + 3 * triangle_count);
        *mesh = new voxmesh_mesh{std::move(copy)};
    });
}

voxmesh_status voxmesh_analyze_topology(const voxmesh_mesh* mesh, voxmesh_topology* topology) {
    return guarded([&] {
        require(mesh, "voxmesh_analyze_topology", "the mesh");
        require(topology, "voxmesh_analyze_topology", "the topology pointer");
        const voxmesh::MeshTopology found = voxmesh::analyze_topology(mesh->mesh);
        topology->boundary_edges = found.boundary_edges;
        topology->nonmanifold_edges = found.nonmanifold_edges;
        topology->euler = found.euler;
        topology->components = found.components;
    });
}

voxmesh_voxelize_options voxmesh_default_voxelize_options(void) {
    const voxmesh::VoxelizeOptions defaults;
    voxmesh_voxelize_options options{};
    options.resolution = defaults.resolution;
    options.padding = defaults.padding;
    options.field = defaults.field == voxmesh::VoxelField::Occupancy ? VOXMESH_FIELD_OCCUPANCY : VOXMESH_FIELD_DISTANCE;
    options.band = defaults.band;
    options.threads = defaults.threads;
    options.fill = defaults.fill == voxmesh::FillRule::NonZero ? VOXMESH_FILL_NONZERO : VOXMESH_FILL_EVENODD;
    return options;
}

voxmesh_status voxmesh_voxelize(const voxmesh_mesh* mesh, const voxmesh_voxelize_options* options,
                                voxmesh_volume** volume) {
    if (volume) *volume = nullptr;
    return guarded([&] {
        require(volume, "voxmesh_voxelize", "the volume pointer");
        require(mesh, "voxmesh_voxelize", "the mesh");
        const voxmesh_voxelize_options given = options ? *options : voxmesh_default_voxelize_options();
        *volume = new voxmesh_volume{voxmesh::voxelize(mesh->mesh, voxelize_options(given, "voxmesh_voxelize"))};
    });
}

voxmesh_status voxmesh_read_volume(const char* path, voxmesh_volume** volume) {
    if (volume) *volume = nullptr;
    return guarded([&] {
        require(volume, "voxmesh_read_volume", "the volume pointer");
        require(path, "voxmesh_read_volume", "the path");
        voxmesh::VolumeInfo info;
        voxmesh::Volume read = voxmesh::read_volume(path, info);
        *volume = new voxmesh_volume{std::move(read), std::move(info)};
    });
}

voxmesh_status voxmesh_read_volume_from_memory(const void* data, size_t size, const char* name,
                                               voxmesh_volume** volume) {
    if (volume) *volume = nullptr;
    return guarded([&] {
        require(volume, "voxmesh_read_volume_from_memory", "the volume pointer");
        require(name, "voxmesh_read_volume_from_memory", "the name");
        if (size) require(data, "voxmesh_read_volume_from_memory", "the data");
        voxmesh::VolumeInfo info;
        voxmesh::Volume read = voxmesh::read_volume_from_memory(data, size, name, info);
        *volume = new voxmesh_volume{std::move(read), std::move(info)};
    });
}

voxmesh_raw_layout voxmesh_default_raw_layout(void) {
    const voxmesh::RawLayout defaults;
    voxmesh_raw_layout layout{};
    copy_geometry(defaults, layout);
    layout.type = scalar_code(defaults.type);
    layout.big_endian = defaults.big_endian;
    layout.offset = defaults.offset;
    return layout;
}

voxmesh_status voxmesh_read_raw(const char* path, const voxmesh_raw_layout* layout, voxmesh_volume** volume) {
    if (volume) *volume = nullptr;
    return guarded([&] {
        require(volume, "voxmesh_read_raw", "the volume pointer");
        require(path, "voxmesh_read_raw", "the path");
        require(layout, "voxmesh_read_raw", "the layout");
        voxmesh::RawLayout cpp;
        copy_geometry(*layout, cpp);
        cpp.type = scalar_type(layout->type, "voxmesh_read_raw");
        cpp.big_endian = layout->big_endian != 0;
        cpp.offset = layout->offset;
        voxmesh::VolumeInfo info;
        voxmesh::Volume read = voxmesh::read_raw(path, cpp, info);
        *volume = new voxmesh_volume{std::move(read), std::move(info)};
    });
}

voxmesh_volume_info voxmesh_volume_get_info(const voxmesh_volume* volume) {
    voxmesh_volume_info out{};
    static const voxmesh::VolumeInfo kNotRead;  // identity and origin 0
    const voxmesh::VolumeInfo& info = volume ? volume->info : kNotRead;
    std::copy(info.directions.begin(), info.directions.end(), out.directions);
    std::copy(info.world_origin.begin(), info.world_origin.end(), out.world_origin);
    out.value_scale = 1;
    if (!volume) return out;
    copy_text(out.format, info.format);
    copy_text(out.encoding, info.encoding);
    out.big_endian = info.big_endian;
    for (int a = 0; a < 3; ++a) out.flipped[a] = info.flipped[a];
    out.rotation_dropped = info.rotation_dropped;
    out.value_scale = info.value_scale;
    out.value_offset = info.value_offset;
    return out;
}

voxmesh_status voxmesh_mesh_to_world(voxmesh_mesh* mesh, const voxmesh_volume* volume) {
    return guarded([&] {
        require(mesh, "voxmesh_mesh_to_world", "the mesh");
        require(volume, "voxmesh_mesh_to_world", "the volume");
        voxmesh::to_world(mesh->mesh, volume->info);
    });
}

voxmesh_status voxmesh_write_nrrd(const char* path, const voxmesh_volume_view* volume) {
    return guarded([&] {
        require(path, "voxmesh_write_nrrd", "the path");
        require(volume, "voxmesh_write_nrrd", "the volume");
        voxmesh::write_nrrd(path, cpp_view(*volume, "voxmesh_write_nrrd"));
    });
}

voxmesh_status voxmesh_write_nrrd_to_memory(const voxmesh_volume_view* volume, const char* name,
                                            voxmesh_bytes** bytes) {
    if (bytes) *bytes = nullptr;
    return guarded([&] {
        require(bytes, "voxmesh_write_nrrd_to_memory", "the bytes pointer");
        require(volume, "voxmesh_write_nrrd_to_memory", "the volume");
        require(name, "voxmesh_write_nrrd_to_memory", "the name");
        const voxmesh::VolumeView view = cpp_view(*volume, "voxmesh_write_nrrd_to_memory");
        *bytes = new voxmesh_bytes{voxmesh::write_nrrd_to_memory(view, name)};
    });
}

voxmesh_volume_view voxmesh_volume_get_view(const voxmesh_volume* volume) {
    return volume ? c_view(volume->volume.view()) : voxmesh_volume_view{};
}

void voxmesh_volume_free(voxmesh_volume* volume) { delete volume; }

voxmesh_sculpt_options voxmesh_default_sculpt_options(void) {
    const voxmesh::SculptOptions defaults;
    voxmesh_sculpt_options options{};
    options.iso = defaults.iso;
    options.threads = defaults.threads;
    options.block_size = defaults.block_size;
    options.normals = defaults.normals;
    options.inside_below = defaults.inside_below;
    options.strength_scale = defaults.strength_scale;
    options.backend = backend_code(defaults.backend);
    options.device = defaults.device;
    return options;
}

voxmesh_status voxmesh_sculpt_new(const voxmesh_volume_view* volume, const voxmesh_sculpt_options* options,
                                  voxmesh_sculpt** sculpt) {
    if (sculpt) *sculpt = nullptr;
    return guarded([&] {
        require(sculpt, "voxmesh_sculpt_new", "the sculpt pointer");
        require(volume, "voxmesh_sculpt_new", "the volume");
        const voxmesh::VolumeView view = cpp_view(*volume, "voxmesh_sculpt_new");
        new_sculpt(sculpt, options, "voxmesh_sculpt_new",
                   [&](const voxmesh::SculptOptions& cpp) { return voxmesh::Sculpt(view, cpp); });
    });
}

voxmesh_status voxmesh_sculpt_from_mesh(const voxmesh_mesh* model, const voxmesh_voxelize_options* voxelize,
                                        const voxmesh_sculpt_options* options, voxmesh_sculpt** sculpt) {
    if (sculpt) *sculpt = nullptr;
    return guarded([&] {
        require(sculpt, "voxmesh_sculpt_from_mesh", "the sculpt pointer");
        require(model, "voxmesh_sculpt_from_mesh", "the model");
        new_sculpt(sculpt, options, "voxmesh_sculpt_from_mesh", [&](const voxmesh::SculptOptions& cpp) {
            const voxmesh::VoxelizeOptions grid =
                voxelize ? voxelize_options(*voxelize, "voxmesh_sculpt_from_mesh")
                         : voxmesh::Sculpt::model_voxelization(voxmesh::VoxelizeOptions{}.resolution, cpp);
            return voxmesh::Sculpt::from_mesh(model->mesh, grid, cpp);
        });
    });
}

voxmesh_status voxmesh_sculpt_from_function(const size_t dims[3], int type, voxmesh_sample_function f, void* user,
                                            const voxmesh_sculpt_options* options, voxmesh_sculpt** sculpt) {
    if (sculpt) *sculpt = nullptr;
    return guarded([&] {
        const char* who = "voxmesh_sculpt_from_function";
        require(sculpt, who, "the sculpt pointer");
        require(dims, who, "dims");
        require(reinterpret_cast<const void*>(f), who, "the function");
        const voxmesh::ScalarType scalar = scalar_type(type, who);
        new_sculpt(sculpt, options, who, [&](const voxmesh::SculptOptions& cpp) {
            return voxmesh::Sculpt::from_function(
                {dims[0], dims[1], dims[2]}, scalar, [f, user](double x, double y, double z) { return f(x, y, z, user); },
                cpp);
        });
    });
}

void voxmesh_sculpt_free(voxmesh_sculpt* sculpt) { delete sculpt; }

voxmesh_status voxmesh_sculpt_apply(voxmesh_sculpt* sculpt, int brush_code, const double center[3], double radius,
                                    double strength, int units_code) {
    return guarded([&] {
        require(sculpt, "voxmesh_sculpt_apply", "the sculpt");
        require(center, "voxmesh_sculpt_apply", "the center");
        voxmesh::Dab dab;
        dab.op = brush(brush_code, "voxmesh_sculpt_apply");
        dab.center = point(center);
        dab.radius = radius;
        dab.strength = strength;
        sculpt->sculpt.apply(dab, units(units_code, "voxmesh_sculpt_apply"));
    });
}

voxmesh_status voxmesh_sculpt_set_region(voxmesh_sculpt* sculpt, const double lo[3], const double hi[3],
                                         double value, int units_code) {
    return guarded([&] {
        require(sculpt, "voxmesh_sculpt_set_region", "the sculpt");
        require(lo, "voxmesh_sculpt_set_region", "lo");
        require(hi, "voxmesh_sculpt_set_region", "hi");
        sculpt->sculpt.set_region(point(lo), point(hi), value, units(units_code, "voxmesh_sculpt_set_region"));
    });
}

voxmesh_volume_view voxmesh_sculpt_get_view(const voxmesh_sculpt* sculpt) {
    return sculpt ? c_view(sculpt->sculpt.view()) : voxmesh_volume_view{};
}

void* voxmesh_sculpt_data(voxmesh_sculpt* sculpt) { return sculpt ? sculpt->sculpt.data() : nullptr; }

voxmesh_status voxmesh_sculpt_invalidate_all(voxmesh_sculpt* sculpt) {
    return guarded([&] {
        require(sculpt, "voxmesh_sculpt_invalidate_all", "the sculpt");
        sculpt->sculpt.invalidate_all();
    });
}

voxmesh_status voxmesh_sculpt_update(voxmesh_sculpt* sculpt, voxmesh_update_result* result) {
    if (result) *result = voxmesh_update_result{};
    return guarded([&] {
        require(sculpt, "voxmesh_sculpt_update", "the sculpt");
        sculpt->last_update = sculpt->sculpt.update();
        if (!result) return;
        const voxmesh::UpdateResult& r = sculpt->last_update;
        result->changed = data_or_null(r.changed);
        result->changed_count = r.changed.size();
        result->remeshed = r.remeshed;
        result->seconds = r.seconds;
    });
}

int voxmesh_sculpt_dirty(const voxmesh_sculpt* sculpt) { return sculpt && sculpt->sculpt.dirty(); }
size_t voxmesh_sculpt_block_count(const voxmesh_sculpt* sculpt) { return sculpt ? sculpt->sculpt.block_count() : 0; }
void voxmesh_sculpt_block_grid(const voxmesh_sculpt* sculpt, size_t grid[3]) {
    if (!grid) return;
    const std::array<std::size_t, 3> g = sculpt ? sculpt->sculpt.block_grid() : std::array<std::size_t, 3>{};
    for (int a = 0; a < 3; ++a) grid[a] = g[a];
}

voxmesh_status voxmesh_sculpt_get_block(const voxmesh_sculpt* sculpt, size_t index, voxmesh_block* block) {
    return guarded([&] {
        require(sculpt, "voxmesh_sculpt_get_block", "the sculpt");
        require(block, "voxmesh_sculpt_get_block", "the block pointer");
        if (index >= sculpt->sculpt.block_count())
            throw voxmesh::Error("voxmesh_sculpt_get_block: block " + std::to_string(index) + " does not exist (" +
                                 std::to_string(sculpt->sculpt.block_count()) + " blocks)");
        const voxmesh::BlockMesh b = sculpt->sculpt.block(index);
        *block = voxmesh_block{};
        block->index = b.index;
        for (int a = 0; a < 3; ++a) {
            block->coord[a] = b.coord[a];
            block->cell_begin[a] = b.cell_begin[a];
            block->cell_end[a] = b.cell_end[a];
        }
        block->positions = data_or_null(b.positions);
        block->normals = data_or_null(b.normals);
        block->indices = data_or_null(b.indices);
        block->vertex_count = b.vertex_count();
        block->triangle_count = b.triangle_count();
    });
}

voxmesh_status voxmesh_sculpt_run_stroke_script(voxmesh_sculpt* sculpt, const char* path,
                                                voxmesh_stroke_callback on_frame, void* user) {
    return guarded([&] {
        const char* who = "voxmesh_sculpt_run_stroke_script";
        require(sculpt, who, "the sculpt");
        require(path, who, "the path");
        run_script(*sculpt, voxmesh::read_stroke_script(path), on_frame, user, who);
    });
}

voxmesh_status voxmesh_sculpt_run_strokes(voxmesh_sculpt* sculpt, const char* text, size_t size, const char* name,
                                          voxmesh_stroke_callback on_frame, void* user) {
    return guarded([&] {
        const char* who = "voxmesh_sculpt_run_strokes";
        require(sculpt, who, "the sculpt");
        if (size > 0) require(text, who, "the text");
        MemoryBuffer buffer(text, size);
        std::istream in(&buffer);
        run_script(*sculpt, voxmesh::parse_stroke_script(in, name ? name : "strokes"), on_frame, user, who);
    });
}

voxmesh_status voxmesh_sculpt_mesh(voxmesh_sculpt* sculpt, voxmesh_mesh** mesh) {
    if (mesh) *mesh = nullptr;
    return guarded([&] {
        require(mesh, "voxmesh_sculpt_mesh", "the mesh pointer");
        require(sculpt, "voxmesh_sculpt_mesh", "the sculpt");
        *mesh = new voxmesh_mesh{sculpt->sculpt.mesh()};  // no stats: not an extract
    });
}

int voxmesh_sculpt_backend(const voxmesh_sculpt* sculpt) {
    return sculpt ? backend_code(sculpt->sculpt.backend()) : VOXMESH_BACKEND_AUTO;
}

const char* voxmesh_sculpt_device_name(const voxmesh_sculpt* sculpt) {
    if (!sculpt) return "";
    try {
        sculpt->device_name = sculpt->sculpt.device_name();
    } catch (...) {
        return "";
    }
    return sculpt->device_name.c_str();
}

const char* voxmesh_sculpt_warnings(const voxmesh_sculpt* sculpt) { return sculpt ? sculpt->warnings->c_str() : ""; }

const char* voxmesh_last_error(void) { return g_last_error.c_str(); }

const char* voxmesh_version(void) { return VOXMESH_VERSION_STRING; }

}  // extern "C"
