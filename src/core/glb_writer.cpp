#include "glb_writer.hpp"

#include "atomic_file.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>

namespace voxmesh::detail {

namespace {

// The container and its data are little-endian; the buffer is the Mesh's own bytes.
static_assert(std::endian::native == std::endian::little, "glTF's binary chunk is written as the host's bytes");

constexpr std::uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kBinChunk = 0x004E4942;   // "BIN\0"
constexpr std::uint32_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr std::uint32_t kFloat = 5126, kUnsignedInt = 5125;
constexpr std::uint32_t kPoints = 0, kTriangles = 4;
constexpr double kUnitTolerance = 0.00674;  // glTF-Validator's for VEC3 (ACCESSOR_NON_UNIT)

// The binary chunk's bytes: xyz floats per vertex (twice with normals), three uint32 per triangle.
// Counts from a Mesh's arrays: none of these products overflows 64 bits.
std::uint64_t bin_bytes(std::uint64_t vertices, bool normals, std::uint64_t triangles) {
    return 12 * vertices * (normals ? 2 : 1) + 12 * triangles;
}

std::uint64_t bin_bytes(const Mesh& mesh) {
    return bin_bytes(mesh.vertex_count(), !mesh.normals.empty(), mesh.triangle_count());
}

std::string number(std::uint64_t value) { return std::to_string(value); }

// The float's exact value, as the shortest text that reads back as that double: a reader
// comparing in double (the data's floats widened) and one rounding to float first (Khronos'
// glTF-Validator) both find the bounds equal to the data. The float's own shortest text
// ("4.9168634") is another double, which the first kind reports as a mismatch. (JSON has no
// NaN or infinity; the writer refuses those before this runs.)
std::string decimal(double value) {
    char text[32];
    return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

std::string exact(float value) { return decimal(static_cast<double>(value)); }

std::string vec3(const float v[3]) {
    std::string text = "[";
    for (unsigned d = 0; d < 3; ++d) text.append(d ? "," : "").append(exact(v[d]));
    return text.append("]");
}

// Appends each piece in turn (GCC 12 warns falsely on chains of std::string operator+).
template <class... Pieces>
void add(std::string& out, const Pieces&... pieces) {
    (out.append(pieces), ...);
}

std::string buffer_view(std::size_t offset, std::size_t bytes, std::uint32_t target) {
    std::string view;
    add(view, R"({"buffer":0,"byteOffset":)", number(offset), R"(,"byteLength":)", number(bytes), R"(,"target":)",
        number(target), "}");
    return view;
}

void put_u32(std::FILE* f, std::uint32_t value) { write_bytes(f, &value, 4); }

}  // namespace

std::string glb_json(const Mesh& mesh) {
    const std::size_t vertices = mesh.vertex_count(), triangles = mesh.triangle_count();
    std::string json;
    add(json, R"({"asset":{"version":"2.0","generator":"voxmesh )", VOXMESH_VERSION_STRING, R"("},"scene":0,"scenes":[)");
    // glTF allows no empty accessor or buffer: a mesh without vertices is a scene without nodes.
    if (vertices == 0) {
        add(json, "{}]}");
    } else {
        // POSITION must carry its bounds.
        float lo[3], hi[3];
        for (unsigned d = 0; d < 3; ++d) lo[d] = hi[d] = mesh.positions[d];
        for (std::size_t v = 1; v < vertices; ++v)
            for (unsigned d = 0; d < 3; ++d) {
                lo[d] = std::min(lo[d], mesh.positions[3 * v + d]);
                hi[d] = std::max(hi[d], mesh.positions[3 * v + d]);
            }
        const std::size_t position_bytes = mesh.positions.size() * sizeof(float);
        const std::size_t normal_bytes = mesh.normals.size() * sizeof(float);
        std::string views = buffer_view(0, position_bytes, kArrayBuffer), accessors, attributes = R"("POSITION":0)";
        add(accessors, R"({"bufferView":0,"componentType":)", number(kFloat), R"(,"count":)", number(vertices),
            R"(,"type":"VEC3","min":)", vec3(lo), R"(,"max":)", vec3(hi), "}");
        std::size_t next = 1;
        if (!mesh.normals.empty()) {
            add(views, ",", buffer_view(position_bytes, normal_bytes, kArrayBuffer));
            add(accessors, R"(,{"bufferView":1,"componentType":)", number(kFloat), R"(,"count":)", number(vertices),
                R"(,"type":"VEC3"})");
            add(attributes, R"(,"NORMAL":1)");
            next = 2;
        }
        // Vertices without triangles stay, as points: nothing of the Mesh is dropped.
        std::string primitive;
        add(primitive, R"({"attributes":{)", attributes, "}");
        if (triangles > 0) {
            add(views, ",",
                buffer_view(position_bytes + normal_bytes, mesh.indices.size() * sizeof(std::uint32_t),
                            kElementArrayBuffer));
            add(accessors, R"(,{"bufferView":)", number(next), R"(,"componentType":)", number(kUnsignedInt),
                R"(,"count":)", number(mesh.indices.size()), R"(,"type":"SCALAR"})");
            add(primitive, R"(,"indices":)", number(next), R"(,"mode":)", number(kTriangles), "}");
        } else {
            add(primitive, R"(,"mode":)", number(kPoints), "}");
        }
        add(json, R"({"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[)", primitive,
            R"(]}],"buffers":[{"byteLength":)", number(bin_bytes(mesh)), R"(}],"bufferViews":[)", views,
            R"(],"accessors":[)", accessors, "]}");
    }
    json.resize((json.size() + 3) / 4 * 4, ' ');
    return json;
}

std::uint64_t checked_glb_bytes(std::uint64_t vertices, bool normals, std::uint64_t triangles, std::uint64_t json_bytes,
                                const std::string& name) {
    const std::uint64_t bin = bin_bytes(vertices, normals, triangles);
    const std::uint64_t total = 12 + 8 + json_bytes + (bin > 0 ? 8 + bin : 0);
    if (total > std::numeric_limits<std::uint32_t>::max())
        throw Error("cannot write '" + name + "': " + std::to_string(vertices) + " vertices and " +
                    std::to_string(triangles) + " triangles make " + std::to_string(total) +
                    " bytes, more than glTF binary's 32-bit length can hold (use .ply or .obj)");
    return total;
}

void check_glb_normals(const Mesh& mesh, const std::string& name) {
    for (std::size_t v = 0; v < mesh.normals.size() / 3; ++v) {
        const double x = mesh.normals[3 * v], y = mesh.normals[3 * v + 1], z = mesh.normals[3 * v + 2];
        const double length = std::sqrt(x * x + y * y + z * z);
        if (std::fabs(length - 1) > kUnitTolerance)
            throw Error("cannot write '" + name + "': vertex " + std::to_string(v) + "'s normal has length " +
                        decimal(length) + "; glTF needs unit normals, within 0.00674 (normalise " +
                        "them, or write without normals)");
    }
}

void write_glb(std::FILE* f, const Mesh& mesh, const std::string& json) {
    const std::uint64_t bin = bin_bytes(mesh);
    const std::uint64_t total = 12 + 8 + json.size() + (bin > 0 ? 8 + bin : 0);
    put_u32(f, kMagic);
    put_u32(f, 2);
    put_u32(f, static_cast<std::uint32_t>(total));
    put_u32(f, static_cast<std::uint32_t>(json.size()));
    put_u32(f, kJsonChunk);
    write_bytes(f, json.data(), json.size());
    if (bin == 0) return;
    // Every array is 4-byte elements, so the chunk needs no padding.
    put_u32(f, static_cast<std::uint32_t>(bin));
    put_u32(f, kBinChunk);
    write_bytes(f, mesh.positions.data(), mesh.positions.size() * sizeof(float));
    write_bytes(f, mesh.normals.data(), mesh.normals.size() * sizeof(float));
    write_bytes(f, mesh.indices.data(), mesh.indices.size() * sizeof(std::uint32_t));
}

}  // namespace voxmesh::detail
