// NIfTI-1 single files (.nii, and .nii.gz detected by the gzip magic): the 348-byte binary
// header, in either byte order (sizeof_hdr tells which), then samples at vox_offset.
// scl_slope/scl_inter are reported, not applied (see io.hpp).
#include "header_text.hpp"
#include "inflate.hpp"
#include "input_file.hpp"
#include "readers.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace voxmesh::io {

namespace {

constexpr std::size_t kHeaderBytes = 348;

class HeaderBytes {
public:
    HeaderBytes(const unsigned char* bytes, bool swap) : bytes_(bytes), swap_(swap) {}
    template <class T>
    T get(std::size_t offset) const {
        unsigned char b[sizeof(T)];
        std::memcpy(b, bytes_ + offset, sizeof(T));
        if (swap_) swap_bytes(b, 1, sizeof(T));
        T value;
        std::memcpy(&value, b, sizeof(T));
        return value;
    }
    std::int16_t i16(std::size_t offset) const { return get<std::int16_t>(offset); }
    float f32(std::size_t offset) const { return get<float>(offset); }

private:
    const unsigned char* bytes_;
    bool swap_;
};

ScalarType nifti_type(const std::string& path, int datatype) {
    switch (datatype) {
        case 2: return ScalarType::U8;
        case 4: return ScalarType::I16;
        case 8: return ScalarType::I32;
        case 16: return ScalarType::F32;
        case 64: return ScalarType::F64;
        case 256: return ScalarType::I8;
        case 512: return ScalarType::U16;
        case 768: return ScalarType::U32;
        default: break;
    }
    fail(path, "unsupported NIfTI datatype " + std::to_string(datatype) +
                   " (supported: scalar 8/16/32-bit integers, float32, float64; not complex, RGB or 64-bit integers)");
}

// Index axis a's direction is column a of the sform's 3x3 part (srow_x, srow_y, srow_z).
// A NaN would otherwise read as a zero column (spacing from pixdim, direction dropped).
std::array<std::vector<double>, 3> sform_axes(const std::string& path, const HeaderBytes& hdr) {
    std::array<std::vector<double>, 3> axes;
    for (std::size_t a = 0; a < 3; ++a)
        for (std::size_t row = 0; row < 3; ++row) axes[a].push_back(hdr.f32(280 + 16 * row + 4 * a));
    check_directions(path, axes, [](std::size_t a, std::size_t row) {
        return std::string("srow_") + "xyz"[row] + "[" + std::to_string(a) + "]";
    });
    return axes;
}

// Columns of the qform rotation: the quaternion (b, c, d; a = sqrt(1 - b^2 - c^2 - d^2)),
// its third column times qfac (-1 when pixdim[0] < 0, else 1), as nifti1_io computes them.
std::array<std::vector<double>, 3> qform_axes(const std::string& path, const HeaderBytes& hdr) {
    double b = hdr.f32(256), c = hdr.f32(260), d = hdr.f32(264);
    // Not finite, the rotation would be NaN, which reads as no rotation at all.
    if (!std::isfinite(b) || !std::isfinite(c) || !std::isfinite(d))
        fail(path, "quatern_b/c/d (" + shortest_text(b) + ", " + shortest_text(c) + ", " + shortest_text(d) +
                       ") are not finite");
    double a = 1 - (b * b + c * c + d * d);
    if (a < 1e-7) {  // a 180-degree rotation, stored slightly denormalized: normalize b, c, d
        const double scale = 1 / std::sqrt(b * b + c * c + d * d);
        b *= scale;
        c *= scale;
        d *= scale;
        a = 0;
    } else {
        a = std::sqrt(a);
    }
    const double qfac = hdr.f32(76) < 0 ? -1 : 1;
    return {{{a * a + b * b - c * c - d * d, 2 * (b * c + a * d), 2 * (b * d - a * c)},
             {2 * (b * c - a * d), a * a + c * c - b * b - d * d, 2 * (c * d + a * b)},
             {qfac * 2 * (b * d + a * c), qfac * 2 * (c * d - a * b), qfac * (a * a + d * d - c * c - b * b)}}};
}

}  // namespace

VolumeHeader read_nifti_header(const InputFile& file) {
    const std::string& path = file.path();
    if (file.size() == 0) fail(path, "file is empty");
    const std::string magic = file.read(0, 2);
    const bool gzip = magic.size() == 2 && static_cast<unsigned char>(magic[0]) == 0x1f &&
                      static_cast<unsigned char>(magic[1]) == 0x8b;
    unsigned char raw[kHeaderBytes];
    if (gzip) {
        const std::shared_ptr<const unsigned char> mapping = file.view();
        Inflater inflater(path, mapping.get(), file.size());
        const std::size_t got = inflater.read(raw, kHeaderBytes);
        if (got < kHeaderBytes)
            fail(path, "decompresses to " + std::to_string(got) + " bytes, too short for the 348-byte NIfTI-1 header");
    } else {
        if (file.size() < kHeaderBytes)
            fail(path, "is " + std::to_string(file.size()) + " bytes, too short for the 348-byte NIfTI-1 header");
        file.read_exact(0, raw, kHeaderBytes);
    }

    std::int32_t sizeof_hdr = 0;
    std::memcpy(&sizeof_hdr, raw, 4);
    std::int32_t swapped = sizeof_hdr;
    swap_bytes(&swapped, 1, 4);
    bool swap = false;
    if (sizeof_hdr == 348) {
        swap = false;
    } else if (swapped == 348) {
        swap = true;
    } else if (sizeof_hdr == 540 || swapped == 540) {
        fail(path, "is NIfTI-2 (sizeof_hdr 540); only NIfTI-1 is supported");
    } else {
        fail(path, "sizeof_hdr is " + std::to_string(sizeof_hdr) + ", not 348: not a NIfTI-1 file");
    }
    const HeaderBytes hdr(raw, swap);
    const bool host_big = std::endian::native == std::endian::big;

    if (std::memcmp(raw + 344, "ni1\0", 4) == 0)
        fail(path, "is the header of a .hdr/.img pair; only single-file NIfTI-1 (.nii, magic n+1) is supported");
    if (std::memcmp(raw + 344, "n+1\0", 4) != 0) fail(path, "NIfTI magic is not 'n+1' (ANALYZE 7.5 or not NIfTI)");

    VolumeHeader h;
    VolumeInfo& info = h.info;
    SampleLayout& layout = h.layout;
    info.format = "nifti";
    info.file_bytes = file.size();
    info.encoding = gzip ? "gzip" : "raw";
    info.big_endian = host_big != swap;

    const int ndim = hdr.i16(40);
    if (ndim < 3 || ndim > 7)
        fail(path, "dim[0] is " + std::to_string(ndim) + "; a volume needs 3 dimensions (4-7 only with extra sizes of 1)");
    std::vector<std::size_t> sizes;
    for (int a = 1; a <= ndim; ++a) {
        const int n = hdr.i16(40 + 2 * static_cast<std::size_t>(a));
        if (n < 1) fail(path, "dim[" + std::to_string(a) + "] is " + std::to_string(n) + "; sizes must be at least 1");
        sizes.push_back(static_cast<std::size_t>(n));
    }
    info.dims = volume_dims(path, sizes);

    const int datatype = hdr.i16(70), bitpix = hdr.i16(72);
    info.type = nifti_type(path, datatype);
    if (static_cast<std::size_t>(bitpix) != 8 * scalar_size(info.type))
        fail(path, "bitpix " + std::to_string(bitpix) + " contradicts datatype " + std::to_string(datatype) + " (" +
                       scalar_name(info.type) + ")");

    const float vox_offset = hdr.f32(108);
    if (!std::isfinite(vox_offset) || vox_offset < 348 || vox_offset > 1e12f || vox_offset != std::floor(vox_offset))
        fail(path, "vox_offset " + std::to_string(vox_offset) + " is not a whole byte offset past the header");

    const float slope = hdr.f32(112), inter = hdr.f32(116);
    if (std::isfinite(slope) && slope != 0) {
        info.value_scale = slope;
        info.value_offset = std::isfinite(inter) ? inter : 0.0;
    }

    // sform (code > 0) wins over qform, as in most readers; with neither the origin is 0
    // and no axis is flipped.
    const int qform_code = hdr.i16(252), sform_code = hdr.i16(254);
    std::array<std::vector<double>, 3> axes;
    if (sform_code > 0) {
        for (std::size_t a = 0; a < 3; ++a) info.origin[a] = checked_origin(path, "srow", hdr.f32(280 + 16 * a + 12));
        axes = sform_axes(path, hdr);
    } else if (qform_code > 0) {
        for (std::size_t a = 0; a < 3; ++a) info.origin[a] = checked_origin(path, "qoffset", hdr.f32(268 + 4 * a));
        axes = qform_axes(path, hdr);
    }
    // Samples lie where the sform puts them, so its column lengths are the spacing even where
    // pixdim says otherwise (as in nibabel's affine); pixdim is read only where used: without
    // an sform, or for a zero sform column, which says nothing. There a pixdim of 0 or not
    // finite is 1, as nifti1_io (and nibabel, for 0) read it.
    for (std::size_t a = 0; a < 3; ++a) {
        const double column = sform_code > 0 ? vector_length(axes[a]) : 0;
        const double pixdim = hdr.f32(80 + 4 * a);
        info.spacing[a] = column > 0 ? checked_spacing(path, "srow", column)
                          : pixdim == 0 || !std::isfinite(pixdim) ? 1.0
                                                                  : std::fabs(pixdim);
    }
    apply_directions(h, axis_directions(axes));

    layout.type = info.type;
    layout.dims = info.dims;
    layout.big_endian = info.big_endian;
    layout.data_path = path;
    layout.compressed = gzip;
    layout.more_may_follow = true;  // bytes after the samples are ignored, as nibabel and nifti1_io do
    if (gzip) layout.skip = static_cast<std::size_t>(vox_offset);
    else layout.offset = static_cast<std::size_t>(vox_offset);
    info.data_file = path;
    return h;
}

}  // namespace voxmesh::io
