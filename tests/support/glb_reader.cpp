#include "glb_reader.hpp"

#include "json_value.hpp"

#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace vmtest {

namespace {

void require(bool ok, const std::string& rule) {
    if (!ok) throw std::runtime_error("glb: " + rule);
}

std::uint32_t u32_at(const std::string& bytes, std::size_t at) {
    require(at + 4 <= bytes.size(), "a field past the end of the file");
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
}

std::size_t index_of(const JsonValue& v) {
    require(v.kind == JsonValue::Kind::Number && v.number >= 0 && v.number == static_cast<double>(static_cast<std::size_t>(v.number)),
            "an index that is not a non-negative integer");
    return static_cast<std::size_t>(v.number);
}

struct GlbFile {
    JsonValue json;
    std::string bin;  // the BIN chunk; empty where there is none
    bool has_bin = false;
};

// The container: a 12-byte header ("glTF", version 2, the file's length), then a JSON chunk
// padded with spaces, then at most one BIN chunk, chunk lengths multiples of 4 and not 0.
GlbFile parse_container(const std::string& bytes) {
    require(bytes.size() >= 20, "shorter than a header and a chunk header");
    require(bytes.compare(0, 4, "glTF") == 0, "magic is not glTF");
    require(u32_at(bytes, 4) == 2, "version is not 2");
    require(u32_at(bytes, 8) == bytes.size(), "declared length is not the file's");
    const std::uint32_t json_length = u32_at(bytes, 12);
    require(json_length > 0 && json_length % 4 == 0, "JSON chunk length not a positive multiple of 4");
    require(bytes.compare(16, 4, "JSON") == 0, "first chunk is not JSON");
    require(20 + std::size_t{json_length} <= bytes.size(), "JSON chunk past the end");
    const std::string json_text = bytes.substr(20, json_length);
    for (const char c : json_text)  // ASCII, so valid UTF-8, as glTF requires of the chunk
        require(static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7f, "JSON chunk not printable ASCII");
    GlbFile file;
    file.json = parse_json(json_text);  // trailing padding spaces are JSON whitespace
    require(json_text.find_first_not_of(' ', json_text.find_last_of('}') + 1) == std::string::npos,
            "JSON chunk padded with something other than spaces");
    const std::size_t at = 20 + std::size_t{json_length};
    if (at < bytes.size()) {
        const std::uint32_t bin_length = u32_at(bytes, at);
        require(bin_length > 0 && bin_length % 4 == 0, "BIN chunk length not a positive multiple of 4");
        require(bytes.compare(at + 4, 4, std::string("BIN\0", 4)) == 0, "second chunk is not BIN");
        require(at + 8 + bin_length == bytes.size(), "BIN chunk does not end the file");
        file.bin = bytes.substr(at + 8, bin_length);
        file.has_bin = true;
    }
    return file;
}

// The bytes accessor `a` reads, after checking it against its bufferView and buffer.
std::string accessor_bytes(const GlbFile& file, std::size_t a, double component_type, const std::string& type,
                           std::size_t element_bytes, double target) {
    const JsonValue& accessor = file.json["accessors"][a];
    require(accessor["componentType"].number == component_type, "accessor componentType");
    require(accessor["type"].text == type, "accessor type");
    const std::size_t count = index_of(accessor["count"]);
    require(count >= 1, "accessor count below 1");
    const std::size_t offset_in_view = accessor.has("byteOffset") ? index_of(accessor["byteOffset"]) : 0;
    const JsonValue& view = file.json["bufferViews"][index_of(accessor["bufferView"])];
    require(view["buffer"].number == 0, "bufferView of another buffer");
    require(view["target"].number == target, "bufferView target");
    require(!view.has("byteStride"), "bufferView with a byteStride");
    const std::size_t view_offset = view.has("byteOffset") ? index_of(view["byteOffset"]) : 0;
    const std::size_t view_length = index_of(view["byteLength"]);
    require((view_offset + offset_in_view) % 4 == 0, "accessor data not 4-byte aligned");
    require(offset_in_view + count * element_bytes <= view_length, "accessor longer than its bufferView");
    require(file.has_bin, "an accessor without a BIN chunk");
    require(file.json["buffers"].size() == 1, "more than one buffer");
    require(file.json["buffers"][0]["byteLength"].number == static_cast<double>(file.bin.size()),
            "buffer byteLength is not the BIN chunk's");
    require(!file.json["buffers"][0].has("uri"), "buffer with a uri (not the GLB's own chunk)");
    require(view_offset + view_length <= file.bin.size(), "bufferView past the buffer");
    return file.bin.substr(view_offset + offset_in_view, count * element_bytes);
}

template <class T>
std::vector<T> as_array(const std::string& bytes) {
    std::vector<T> out(bytes.size() / sizeof(T));
    std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
    return out;
}

}  // namespace

GlbContents read_glb(const std::string& bytes) {
    const GlbFile file = parse_container(bytes);
    const JsonValue& json = file.json;
    require(json["asset"]["version"].text == "2.0", "asset.version is not 2.0");
    GlbContents out;
    // "scene" may be left out; voxmesh writes its one scene as 0.
    const JsonValue& scene = json["scenes"][json.has("scene") ? index_of(json["scene"]) : 0];
    if (!scene.has("nodes")) {
        require(!json.has("meshes") && !file.has_bin, "a scene without nodes, but meshes or data");
        return out;
    }
    require(scene["nodes"].size() == 1, "not one node");
    const JsonValue& node = json["nodes"][index_of(scene["nodes"][0])];
    require(!node.has("matrix") && !node.has("translation") && !node.has("rotation") && !node.has("scale"),
            "a node transform (the mesh's own coordinates expected)");
    out.meshes = json["meshes"].size();
    const JsonValue& primitives = json["meshes"][index_of(node["mesh"])]["primitives"];
    require(primitives.size() == 1, "not one primitive");
    const JsonValue& primitive = primitives[0];
    out.mode = primitive.has("mode") ? static_cast<int>(primitive["mode"].number) : 4;
    const JsonValue& attributes = primitive["attributes"];
    const std::size_t position = index_of(attributes["POSITION"]);
    out.mesh.positions = as_array<float>(accessor_bytes(file, position, 5126, "VEC3", 12, 34962));
    const JsonValue& accessor = json["accessors"][position];
    require(accessor["min"].size() == 3 && accessor["max"].size() == 3, "POSITION without 3-component min and max");
    for (std::size_t d = 0; d < 3; ++d) {
        out.min.push_back(accessor["min"][d].number);
        out.max.push_back(accessor["max"][d].number);
    }
    if (attributes.has("NORMAL")) {
        const std::size_t normal = index_of(attributes["NORMAL"]);
        require(json["accessors"][normal]["count"].number == accessor["count"].number, "NORMAL count differs");
        out.mesh.normals = as_array<float>(accessor_bytes(file, normal, 5126, "VEC3", 12, 34962));
    }
    if (primitive.has("indices"))
        out.mesh.indices =
            as_array<std::uint32_t>(accessor_bytes(file, index_of(primitive["indices"]), 5125, "SCALAR", 4, 34963));
    return out;
}

}  // namespace vmtest
