// write_nrrd: a NRRD0004 header (raw encoding, host byte order) followed by the samples,
// written through a temporary file so a failure never leaves a partial output.
#include "core/atomic_file.hpp"
#include "core/float_extent.hpp"
#include "core/write_to_stream.hpp"
#include "header_text.hpp"

#include <voxmesh/io.hpp>

#include <bit>
#include <cmath>
#include <functional>

namespace voxmesh {

namespace {

const char* nrrd_type(ScalarType type) {
    switch (type) {
        case ScalarType::U8: return "uint8";
        case ScalarType::I8: return "int8";
        case ScalarType::U16: return "uint16";
        case ScalarType::I16: return "int16";
        case ScalarType::U32: return "uint32";
        case ScalarType::I32: return "int32";
        case ScalarType::F32: return "float";
        case ScalarType::F64: return "double";
    }
    throw Error("unknown scalar type");
}

// A key or value with its backslashes doubled, as teem writes them: NRRD readers take a
// backslash-n for a line break and a doubled backslash for one backslash.
std::string escaped(const std::string& text) {
    std::string out;
    for (const char c : text) {
        if (c == '\\') out += '\\';
        out += c;
    }
    return out;
}

// What write_nrrd writes for `volume` (its header, then the samples), after its checks (Error
// naming `name`), and how many bytes that is.
struct NrrdOutput {
    std::function<void(std::FILE*)> write;
    std::size_t bytes = 0;
};

NrrdOutput checked_nrrd(const VolumeView& volume, const std::map<std::string, std::string>& key_values,
                        const std::string& name) {
    auto refuse = [&](const std::string& why) { throw Error("cannot write '" + name + "': " + why); };
    std::size_t bytes = 0;
    try {
        bytes = checked_volume_bytes(volume.dims, volume.type);
    } catch (const Error& e) {
        refuse(e.what());
    }
    if (bytes == 0) refuse("the volume is empty");
    if (!volume.data) refuse("the volume has no data");
    for (std::size_t a = 0; a < 3; ++a) {
        if (!std::isfinite(volume.spacing[a]) || volume.spacing[a] == 0) refuse("spacing must be finite and non-zero");
        if (!std::isfinite(volume.origin[a])) refuse("origin must be finite");
    }
    // What read_volume would refuse to read back (extract() refuses it too).
    if (const int a = detail::axis_beyond_float(volume.dims, volume.spacing, volume.origin); a >= 0)
        refuse(std::string("origin and spacing put samples along ") + "xyz"[a] +
               " beyond the range of float mesh coordinates, which voxmesh's readers refuse");

    std::string header = "NRRD0004\n# written by voxmesh " VOXMESH_VERSION_STRING "\n";
    header += std::string("type: ") + nrrd_type(volume.type) + "\n";
    header += "dimension: 3\n";
    header += "space dimension: 3\n";
    header += "sizes: " + std::to_string(volume.dims[0]) + " " + std::to_string(volume.dims[1]) + " " +
              std::to_string(volume.dims[2]) + "\n";
    header += "space directions: (" + io::shortest_text(volume.spacing[0]) + ",0,0) (0," + io::shortest_text(volume.spacing[1]) +
              ",0) (0,0," + io::shortest_text(volume.spacing[2]) + ")\n";
    header += "kinds: domain domain domain\n";
    header += std::string("endian: ") + (std::endian::native == std::endian::big ? "big" : "little") + "\n";
    header += "encoding: raw\n";
    header += "space origin: (" + io::shortest_text(volume.origin[0]) + "," + io::shortest_text(volume.origin[1]) + "," +
              io::shortest_text(volume.origin[2]) + ")\n";
    for (const auto& [key, value] : key_values) {
        // What reads back as this key and value, not as a comment ('#'), a field (": " before
        // ":="), another line, or without a trailing '\r' (stripped as in CRLF files).
        const auto line_break = [](const std::string& t) { return t.find_first_of("\r\n") != std::string::npos; };
        if (key.empty() || key.front() == '#' || key.find(":=") != std::string::npos ||
            key.find(": ") != std::string::npos || line_break(key) || line_break(value))
            refuse("key/value '" + key + "' cannot be written as a NRRD 'key:=value' line (a key must be non-empty, "
                   "not start with '#', and hold no ':=' or ': '; neither may hold a line break)");
        header += escaped(key) + ":=" + escaped(value) + "\n";
    }
    header += "\n";

    // Pad the comment so the samples start 8-byte aligned: readers can then map them.
    header.insert(header.find('\n', 9), (8 - header.size() % 8) % 8, ' ');
    if (header.size() > io::kMaxNrrdHeader)
        refuse("the key/value lines make a header of " + std::to_string(header.size()) +
               " bytes, more than the " + std::to_string(io::kMaxNrrdHeader) + " NRRD readers here read");

    const auto write = [header, data = volume.data, bytes](std::FILE* file) {
        detail::write_bytes(file, header.data(), header.size());
        detail::write_bytes(file, data, bytes);
    };
    return {write, header.size() + bytes};
}

}  // namespace

void write_nrrd(const std::string& path, const VolumeView& volume,
                const std::map<std::string, std::string>& key_values) {
    detail::write_file_atomically(path, checked_nrrd(volume, key_values, path).write);
}

std::vector<unsigned char> write_nrrd_to_memory(const VolumeView& volume, const std::string& name,
                                                const std::map<std::string, std::string>& key_values) {
    const NrrdOutput output = checked_nrrd(volume, key_values, name);
    return detail::write_to_memory(name, output.write, output.bytes);
}

void detail::write_nrrd_to(std::FILE* file, const VolumeView& volume,
                           const std::map<std::string, std::string>& key_values, const std::string& name) {
    write_to_stream(file, name, checked_nrrd(volume, key_values, name).write);
}

}  // namespace voxmesh
