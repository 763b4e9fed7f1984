#include <voxmesh/voxmesh.hpp>

#include "dims_text.hpp"
#include "huge_pages.hpp"

#include <cstdlib>
#include <limits>
#include <new>

namespace voxmesh {

std::size_t scalar_size(ScalarType type) {
    switch (type) {
        case ScalarType::U8: case ScalarType::I8: return 1;
        case ScalarType::U16: case ScalarType::I16: return 2;
        case ScalarType::U32: case ScalarType::I32: case ScalarType::F32: return 4;
        case ScalarType::F64: return 8;
    }
    throw Error("unknown scalar type");
}

const char* scalar_name(ScalarType type) {
    switch (type) {
        case ScalarType::U8: return "u8";
        case ScalarType::I8: return "i8";
        case ScalarType::U16: return "u16";
        case ScalarType::I16: return "i16";
        case ScalarType::U32: return "u32";
        case ScalarType::I32: return "i32";
        case ScalarType::F32: return "f32";
        case ScalarType::F64: return "f64";
    }
    return "?";
}

const char* backend_name(Backend backend) {
    switch (backend) {
        case Backend::Auto: return "auto";
        case Backend::Cpu: return "cpu";
        case Backend::OpenCL: return "opencl";
        case Backend::Hybrid: return "hybrid";
    }
    return "?";
}

std::size_t checked_volume_bytes(std::array<std::size_t, 3> dims, ScalarType type) {
    std::size_t bytes = scalar_size(type);
    for (std::size_t d : dims) {
        if (d != 0 && bytes > std::numeric_limits<std::size_t>::max() / d)
            throw Error("volume dimensions " + detail::dims_text(dims) + " overflow the addressable size");
        bytes *= d;
    }
    return bytes;
}

Volume Volume::allocate(ScalarType type, std::array<std::size_t, 3> dims) {
    const std::size_t bytes = checked_volume_bytes(dims, type);
    Volume v;
    try {
        // Huge pages: a volume is filled once, page by page, and generate reads it near the
        // surface, a few rows in each of four planes at a time; 4 KiB pages cost a fault
        // each on the fill and a TLB miss per row there.
        v.storage = detail::allocate_zeroed(bytes);
    } catch (const std::bad_alloc&) {
        throw OutOfMemoryError("cannot allocate " + std::to_string(bytes) + " bytes for a volume");
    }
    v.type = type;
    v.dims = dims;
    v.data = v.storage.get();
    return v;
}

std::size_t Volume::sample_count() const { return dims[0] * dims[1] * dims[2]; }
std::size_t Volume::byte_size() const { return sample_count() * scalar_size(type); }

VolumeView Volume::view() const {
    VolumeView v;
    v.data = data;
    v.type = type;
    v.dims = dims;
    v.spacing = spacing;
    v.origin = origin;
    return v;
}

}  // namespace voxmesh
