// read_volume / read_volume_info: pick the reader by extension, then load or check the
// samples the header describes. Also read_raw, the same path with a caller-given header.
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

double checked_spacing(const std::string& path, const char* field, double value) {
    if (!std::isfinite(value) || value == 0)
        fail(path, std::string("'") + field + "' gives spacing " + std::to_string(value) +
                       "; spacing must be finite and non-zero");
    return std::fabs(value);
}

double checked_origin(const std::string& path, const char* field, double value) {
    if (!std::isfinite(value)) fail(path, std::string("'") + field + "' gives a non-finite origin");
    return value;
}

namespace {

VolumeHeader read_header(const std::string& path) {
    if (ends_with_nocase(path, ".nrrd") || ends_with_nocase(path, ".nhdr")) return read_nrrd_header(path);
    if (ends_with_nocase(path, ".mhd") || ends_with_nocase(path, ".mha")) return read_metaimage_header(path);
    if (ends_with_nocase(path, ".nii") || ends_with_nocase(path, ".nii.gz")) return read_nifti_header(path);
    if (ends_with_nocase(path, ".raw"))
        fail(path, "a headerless .raw volume needs its dims and type (read_raw / --dims --type)");
    fail(path, "unknown volume format (expected .nrrd, .nhdr, .mhd, .mha, .nii or .nii.gz)");
}

SampleLayout raw_layout(const std::string& path, const RawLayout& raw) {
    SampleLayout layout;
    layout.type = raw.type;
    layout.dims = raw.dims;
    layout.big_endian = raw.big_endian;
    layout.data_path = path;
    layout.offset = raw.offset;
    for (std::size_t a = 0; a < 3; ++a) {
        checked_spacing(path, "spacing", raw.spacing[a]);
        checked_origin(path, "origin", raw.origin[a]);
    }
    return layout;
}

}  // namespace

}  // namespace voxmesh::io

namespace voxmesh {

Volume read_volume(const std::string& path) {
    const io::VolumeHeader h = io::read_header(path);
    Volume v = io::load_samples(path, h.layout);
    v.spacing = h.info.spacing;
    v.origin = h.info.origin;
    return v;
}

VolumeInfo read_volume_info(const std::string& path) {
    io::VolumeHeader h = io::read_header(path);
    const std::size_t data_bytes = io::check_samples(path, h.layout);
    if (h.layout.data_path == path) h.info.file_bytes = data_bytes;
    return h.info;
}

Volume read_raw(const std::string& path, const RawLayout& layout) {
    Volume v = io::load_samples(path, io::raw_layout(path, layout));
    v.spacing = layout.spacing;
    v.origin = layout.origin;
    return v;
}

VolumeInfo read_raw_info(const std::string& path, const RawLayout& layout) {
    VolumeInfo info;
    info.format = "raw";
    info.type = layout.type;
    info.dims = layout.dims;
    info.spacing = layout.spacing;
    info.origin = layout.origin;
    info.encoding = "raw";
    info.big_endian = layout.big_endian;
    info.file_bytes = io::check_samples(path, io::raw_layout(path, layout));
    info.data_file = path;
    return info;
}

}  // namespace voxmesh
