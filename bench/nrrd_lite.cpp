// The volume files voxmesh-bench writes for bench/peers: raw little-endian NRRD, with the
// field's iso as a key/value pair so that every tool meshes the same samples at the same iso.
#include "bench.hpp"

#ifdef VOXMESH_BENCH_HAVE_IO
#include <voxmesh/io.hpp>
#endif

#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace vmbench {

namespace {

const char* nrrd_type(voxmesh::ScalarType t) {
    using voxmesh::ScalarType;
    switch (t) {
        case ScalarType::U8: return "uint8";
        case ScalarType::I8: return "int8";
        case ScalarType::U16: return "uint16";
        case ScalarType::I16: return "int16";
        case ScalarType::U32: return "uint32";
        case ScalarType::I32: return "int32";
        case ScalarType::F32: return "float";
        case ScalarType::F64: return "double";
    }
    throw voxmesh::Error("unknown scalar type");
}

bool little_endian_host() {
    const std::uint16_t one = 1;
    unsigned char b;
    std::memcpy(&b, &one, 1);
    return b == 1;
}

// Header lines up to the blank line; false when the file is not a NRRD.
bool read_header(std::ifstream& in, std::vector<std::string>& lines) {
    std::string line;
    if (!std::getline(in, line) || line.rfind("NRRD", 0) != 0) return false;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) return true;
        lines.push_back(line);
    }
    return false;
}

std::string value_of(const std::vector<std::string>& lines, const std::string& key, const char* sep) {
    for (const auto& l : lines)
        if (l.rfind(key + sep, 0) == 0) {
            std::string v = l.substr(key.size() + std::strlen(sep));
            while (!v.empty() && v.front() == ' ') v.erase(v.begin());
            return v;
        }
    return "";
}

}  // namespace

void write_volume_nrrd(const std::string& path, const Input& input) {
    if (!little_endian_host()) throw voxmesh::Error("--write-volume supports little-endian hosts only");
    const std::string tmp = path + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw voxmesh::Error("cannot create '" + tmp + "'");
        char iso[64];
        std::snprintf(iso, sizeof iso, "%.17g", input.iso);
        out << "NRRD0004\n"
            << "# written by voxmesh-bench --write-volume\n"
            << "type: " << nrrd_type(input.volume.type) << "\n"
            << "dimension: 3\n"
            << "sizes: " << input.dims[0] << " " << input.dims[1] << " " << input.dims[2] << "\n"
            << "spacings: 1 1 1\n"
            << "encoding: raw\n"
            << "endian: little\n"
            << "voxmesh_field:=" << input.field << "\n"
            << "voxmesh_iso:=" << iso << "\n\n";
        out.write(static_cast<const char*>(input.volume.data), std::streamsize(input.volume.byte_size()));
        out.flush();
        if (!out) throw voxmesh::Error("cannot write '" + tmp + "' (disk full?)");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw voxmesh::Error("cannot rename '" + tmp + "' to '" + path + "'");
    }
}

bool read_nrrd_iso(const std::string& path, double& iso) {
    std::ifstream in(path, std::ios::binary);
    std::vector<std::string> lines;
    if (!in || !read_header(in, lines)) return false;
    const std::string v = value_of(lines, "voxmesh_iso", ":=");
    if (v.empty()) return false;
    std::istringstream s(v);
    return static_cast<bool>(s >> iso);
}

voxmesh::Volume load_volume(const std::string& path) {
#ifdef VOXMESH_BENCH_HAVE_IO
    return voxmesh::read_volume(path);
#else
    // Fallback until the library's readers land: the raw NRRD written by write_volume_nrrd.
    std::ifstream in(path, std::ios::binary);
    if (!in) throw voxmesh::Error("cannot open '" + path + "'");
    std::vector<std::string> lines;
    if (!read_header(in, lines)) throw voxmesh::Error("'" + path + "' is not a NRRD file");
    if (value_of(lines, "encoding", ":") != "raw" || value_of(lines, "dimension", ":") != "3" ||
        (value_of(lines, "endian", ":") != "little" && value_of(lines, "endian", ":") != ""))
        throw voxmesh::Error("'" + path + "': this build reads only raw little-endian 3-D NRRD files");
    const std::string t = value_of(lines, "type", ":");
    voxmesh::ScalarType type{};
    bool found = false;
    for (auto c : {voxmesh::ScalarType::U8, voxmesh::ScalarType::I8, voxmesh::ScalarType::U16,
                   voxmesh::ScalarType::I16, voxmesh::ScalarType::U32, voxmesh::ScalarType::I32,
                   voxmesh::ScalarType::F32, voxmesh::ScalarType::F64})
        if (t == nrrd_type(c)) {
            type = c;
            found = true;
        }
    if (!found) throw voxmesh::Error("'" + path + "': unsupported NRRD type '" + t + "'");
    std::array<std::size_t, 3> dims{};
    std::istringstream s(value_of(lines, "sizes", ":"));
    if (!(s >> dims[0] >> dims[1] >> dims[2])) throw voxmesh::Error("'" + path + "': bad sizes");
    const std::size_t bytes = voxmesh::checked_volume_bytes(dims, type);
    const auto data_start = in.tellg();
    in.seekg(0, std::ios::end);
    if (std::size_t(in.tellg() - data_start) != bytes)
        throw voxmesh::Error("'" + path + "': the data size does not match the header's sizes and type");
    in.seekg(data_start);
    voxmesh::Volume v = voxmesh::Volume::allocate(type, dims);
    in.read(static_cast<char*>(v.data), std::streamsize(bytes));
    if (!in) throw voxmesh::Error("'" + path + "': read failed");
    return v;
#endif
}

}  // namespace vmbench
