// read_volume / read_volume_info: pick the reader by extension, then load or check the
// samples the header describes. Also read_raw, the same path with a caller-given header.
#include "core/float_extent.hpp"
#include "header_text.hpp"
#include "input_file.hpp"
#include "readers.hpp"

#include <cmath>

namespace voxmesh::io {

std::array<std::size_t, 3> volume_dims(const std::string& path, const std::vector<std::size_t>& sizes) {
    if (sizes.size() < 3)
        fail(path, "has " + std::to_string(sizes.size()) + " dimensions; a volume needs 3");
    for (std::size_t a = 3; a < sizes.size(); ++a)
        if (sizes[a] != 1)
            fail(path, "axis " + std::to_string(a) + " has size " + std::to_string(sizes[a]) +
                           "; only 3-D volumes (extra axes of size 1) are supported");
    return {sizes[0], sizes[1], sizes[2]};
}

std::array<std::size_t, 3> volume_axes(const std::string& path, const std::vector<std::size_t>& sizes,
                                       const std::vector<bool>& drop_first) {
    if (sizes.size() < 3)
        fail(path, "has " + std::to_string(sizes.size()) + " dimensions; a volume needs 3");
    // Only size-1 axes go: without them the samples' order is the same.
    std::vector<bool> dropped(sizes.size(), false);
    std::size_t extra = sizes.size() - 3;
    for (const bool marked_only : {true, false})
        for (std::size_t a = sizes.size(); a-- > 0 && extra > 0;)
            if (sizes[a] == 1 && !dropped[a] && (!marked_only || (a < drop_first.size() && drop_first[a]))) {
                dropped[a] = true;
                --extra;
            }
    if (extra > 0) {
        std::string listed;
        for (const std::size_t n : sizes) {
            if (!listed.empty()) listed += " ";
            listed += std::to_string(n);
        }
        fail(path, "sizes " + listed + " have " + std::to_string(3 + extra) +
                       " axes longer than 1; only 3-D volumes (extra axes of size 1) are supported");
    }
    std::array<std::size_t, 3> axes{};
    for (std::size_t a = 0, k = 0; a < sizes.size(); ++a)
        if (!dropped[a]) axes[k++] = a;
    return axes;
}

double checked_spacing(const std::string& path, const char* field, double value) {
    if (!std::isfinite(value) || value == 0)
        fail(path, std::string("'") + field + "' gives spacing " + shortest_text(value) +
                       "; spacing must be finite and non-zero");
    return std::fabs(value);
}

double checked_origin(const std::string& path, const char* field, double value) {
    if (!std::isfinite(value)) fail(path, std::string("'") + field + "' gives a non-finite origin");
    return value;
}

double vector_length(const std::vector<double>& v) {
    // Scaled by the largest component, as hypot does: squares of 1e-300 or 1e200 would
    // underflow to 0 or overflow to inf.
    double largest = 0;
    for (const double c : v) {
        if (std::isnan(c)) return c;
        largest = std::max(largest, std::fabs(c));
    }
    if (largest == 0 || !std::isfinite(largest)) return largest;
    double norm2 = 0;
    for (const double c : v) norm2 += (c / largest) * (c / largest);
    return largest * std::sqrt(norm2);
}

void check_directions(const std::string& path, const std::array<std::vector<double>, 3>& axes,
                      const std::function<std::string(std::size_t axis, std::size_t component)>& name) {
    for (std::size_t a = 0; a < 3; ++a)
        for (std::size_t c = 0; c < axes[a].size(); ++c)
            if (!std::isfinite(axes[a][c]))
                fail(path, name(a, c) + " is " + shortest_text(axes[a][c]) +
                               ": a non-finite direction component of index axis " + std::to_string(a) +
                               " (the direction matrix must be finite)");
}

AxisDirections axis_directions(const std::array<std::vector<double>, 3>& axes) {
    AxisDirections d;
    for (std::size_t a = 0; a < 3; ++a) {
        const std::vector<double>& v = axes[a];
        const double length = vector_length(v);
        if (length == 0) continue;
        // Headers store directions as floats or rounded text: off-axis parts this small are noise.
        const double noise = 1e-6 * length;
        bool off_axis = false, own_largest = a < v.size();
        for (std::size_t c = 0; c < v.size(); ++c) {
            if (c != a && std::fabs(v[c]) > noise) off_axis = true;
            if (own_largest && std::fabs(v[c]) > std::fabs(v[a])) own_largest = false;
        }
        if (off_axis || !own_largest) d.rotation_dropped = true;
        // An axis mostly along its own world axis takes that axis's sign even when slightly
        // oblique (scans converted from DICOM usually are): keeping a negative axis unflipped
        // would mirror the mesh. Only the small off-axis part is dropped.
        if (own_largest) d.flipped[a] = v[a] < 0;
    }
    // What the samples keep: each axis along its own, flipped or not. Exact where nothing else
    // is dropped (off-axis noise stays dropped), so to_world then changes nothing.
    for (std::size_t a = 0; a < 3; ++a) d.directions[4 * a] = d.flipped[a] ? -1 : 1;
    if (!d.rotation_dropped) return d;
    // Unit directions, as spacing gives the length. World has three components: those past
    // the third (a NRRD space of more dimensions) are dropped after normalising, so the first
    // three stay as the file places samples.
    std::array<double, 9> m{};
    for (std::size_t a = 0; a < 3; ++a) {
        const std::vector<double>& v = axes[a];
        const double length = vector_length(v);
        if (length == 0) {  // a zero vector says nothing: the axis's own direction
            m[4 * a] = 1;
            continue;
        }
        for (std::size_t c = 0; c < 3 && c < v.size(); ++c) m[3 * c + a] = v[c] / length;
    }
    const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                       m[2] * (m[3] * m[7] - m[4] * m[6]);
    if (std::fabs(det) > 1e-6) d.directions = m;  // else (directions in a plane) dropped, as before
    return d;
}

void reverse_direction(std::array<std::vector<double>, 3>& axes, std::size_t a) {
    if (axes[a].empty()) {
        axes[a].assign(3, 0.0);
        axes[a][a] = 1;
    }
    for (double& c : axes[a]) c = -c;
}

void apply_directions(VolumeHeader& h, const AxisDirections& d) {
    VolumeInfo& info = h.info;
    // The file's last sample along a flipped axis is the loaded first: world_origin moves
    // along the file's direction, and the loaded axis runs the opposite way.
    info.world_origin = info.origin;
    info.directions = d.directions;
    for (std::size_t a = 0; a < 3; ++a) {
        if (!d.flipped[a]) continue;
        const double extent = info.dims[a] > 0 ? info.spacing[a] * static_cast<double>(info.dims[a] - 1) : 0.0;
        for (std::size_t c = 0; c < 3; ++c) {
            info.world_origin[c] += info.directions[3 * c + a] * extent;
            info.directions[3 * c + a] = -info.directions[3 * c + a];
        }
        info.origin[a] -= extent;
    }
    info.flipped = d.flipped;
    info.rotation_dropped = d.rotation_dropped;
    h.layout.flipped = d.flipped;
}

namespace {

// Mesh vertices are floats: a grid whose samples lie past FLT_MAX would mesh to inf.
void check_extent(const std::string& path, const VolumeInfo& info) {
    const int a = detail::axis_beyond_float(info.dims, info.spacing, info.origin);
    if (a < 0) return;
    const double far = detail::last_sample_at(info.origin[a], info.spacing[a], info.dims[a]);
    fail(path, "origin and spacing put samples along axis " + std::to_string(a) + " at " + shortest_text(far) +
                   ", beyond the range of float mesh coordinates");
}

VolumeHeader parse_header(const InputFile& file) {
    const std::string& path = file.path();
    if (ends_with_nocase(path, ".nrrd") || ends_with_nocase(path, ".nhdr")) return read_nrrd_header(file);
    if (ends_with_nocase(path, ".mhd") || ends_with_nocase(path, ".mha")) return read_metaimage_header(file);
    if (ends_with_nocase(path, ".nii") || ends_with_nocase(path, ".nii.gz")) return read_nifti_header(file);
    if (ends_with_nocase(path, ".vtk")) return read_vtk_header(file);
    if (ends_with_nocase(path, ".npy")) return read_npy_header(file);
    if (ends_with_nocase(path, ".raw"))
        fail(path, "a headerless .raw volume needs its dims and type (read_raw / --dims --type)");
    fail(path, "unknown volume format (expected .nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz, .vtk or .npy)");
}

VolumeHeader read_header(const InputFile& file) {
    VolumeHeader h = parse_header(file);
    check_extent(file.path(), h.info);
    return h;
}

// The caller's layout checked like a header: a negative spacing reverses its axis, as there.
VolumeHeader raw_header(const std::string& path, const RawLayout& raw) {
    VolumeHeader h;
    VolumeInfo& info = h.info;
    info.format = "raw";
    info.encoding = "raw";
    info.type = raw.type;
    info.dims = raw.dims;
    info.big_endian = raw.big_endian;
    info.data_file = path;
    std::array<std::vector<double>, 3> axes;
    for (std::size_t a = 0; a < 3; ++a) {
        info.spacing[a] = checked_spacing(path, "spacing", raw.spacing[a]);
        info.origin[a] = checked_origin(path, "origin", raw.origin[a]);
        if (raw.spacing[a] < 0) reverse_direction(axes, a);
    }
    apply_directions(h, axis_directions(axes));
    check_extent(path, info);
    SampleLayout& layout = h.layout;
    layout.type = raw.type;
    layout.dims = raw.dims;
    layout.big_endian = raw.big_endian;
    layout.data_path = path;
    layout.offset = raw.offset;
    return h;
}

}  // namespace

}  // namespace voxmesh::io

namespace voxmesh {

namespace {

// Loaded samples, placed where their header puts them.
Volume placed(Volume v, const VolumeInfo& info) {
    v.spacing = info.spacing;
    v.origin = info.origin;
    return v;
}

// The readers over one InputFile: a path opened, or bytes in memory.
Volume read_volume_from(const io::InputFile& file, VolumeInfo& info) {
    const io::VolumeHeader h = io::read_header(file);
    Volume v = placed(io::load_samples(file, h.layout), h.info);
    info = h.info;
    return v;
}

VolumeInfo read_volume_info_from(const io::InputFile& file) {
    io::VolumeHeader h = io::read_header(file);
    const std::size_t data_bytes = io::check_samples(file, h.layout);
    if (h.layout.data_path == file.path()) h.info.file_bytes = data_bytes;
    return h.info;
}

// f(file) with `file` the path opened, out of memory anywhere in it an Error naming the file.
template <class F>
auto reading(const std::string& path, F&& f) {
    return io::out_of_memory_reading(path, "volume", [&] {
        const io::InputFile file(path);
        return f(file);
    });
}

// The same for bytes in memory.
template <class F>
auto reading(const void* data, std::size_t size, const std::string& name, F&& f) {
    return io::out_of_memory_reading(name, "volume", [&] {
        const io::InputFile file(name, data, size);
        return f(file);
    });
}

// The caller's layout as the header of `file`'s samples.
Volume read_raw_from(const io::InputFile& file, const RawLayout& layout, VolumeInfo& info) {
    const io::VolumeHeader h = io::raw_header(file.path(), layout);
    Volume v = placed(io::load_samples(file, h.layout), h.info);
    info = h.info;
    return v;
}

}  // namespace

Volume read_volume(const std::string& path, VolumeInfo& info) {
    return reading(path, [&](const io::InputFile& file) { return read_volume_from(file, info); });
}

Volume read_volume(const std::string& path) {
    VolumeInfo info;
    return read_volume(path, info);
}

VolumeInfo read_volume_info(const std::string& path) {
    return reading(path, read_volume_info_from);
}

Volume read_raw(const std::string& path, const RawLayout& layout, VolumeInfo& info) {
    return reading(path, [&](const io::InputFile& file) { return read_raw_from(file, layout, info); });
}

Volume read_raw(const std::string& path, const RawLayout& layout) {
    VolumeInfo info;
    return read_raw(path, layout, info);
}

Volume read_raw(std::istream& in, const std::string& name, const RawLayout& layout) {
    return io::out_of_memory_reading(name, "volume", [&] {
        const io::VolumeHeader h = io::raw_header(name, layout);
        return placed(io::load_stream_samples(in, name, h.layout), h.info);
    });
}

VolumeInfo read_raw_info(const std::string& path, const RawLayout& layout) {
    return reading(path, [&](const io::InputFile& file) {
        io::VolumeHeader h = io::raw_header(path, layout);
        h.info.file_bytes = io::check_samples(file, h.layout);
        return h.info;
    });
}

Volume read_volume_from_memory(const void* data, std::size_t size, const std::string& name, VolumeInfo& info) {
    return reading(data, size, name, [&](const io::InputFile& file) { return read_volume_from(file, info); });
}

Volume read_volume_from_memory(const void* data, std::size_t size, const std::string& name) {
    VolumeInfo info;
    return read_volume_from_memory(data, size, name, info);
}

Volume read_volume_from_memory(std::vector<unsigned char>&& bytes, const std::string& name, VolumeInfo& info) {
    return io::out_of_memory_reading(name, "volume", [&] {
        // The vector moves into what the Volume may keep: its samples, used where they lie.
        const auto kept = std::make_shared<std::vector<unsigned char>>(std::move(bytes));
        const std::size_t size = kept->size();
        const io::InputFile file(name, std::shared_ptr<unsigned char>(kept, kept->data()), size);
        return read_volume_from(file, info);
    });
}

Volume read_volume_from_memory(std::vector<unsigned char>&& bytes, const std::string& name) {
    VolumeInfo info;
    return read_volume_from_memory(std::move(bytes), name, info);
}

VolumeInfo read_volume_info_from_memory(const void* data, std::size_t size, const std::string& name) {
    return reading(data, size, name, read_volume_info_from);
}

Volume read_raw_from_memory(const void* data, std::size_t size, const std::string& name, const RawLayout& layout) {
    VolumeInfo info;
    return reading(data, size, name, [&](const io::InputFile& file) { return read_raw_from(file, layout, info); });
}

}  // namespace voxmesh
