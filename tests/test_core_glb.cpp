// write_mesh to .glb (binary glTF 2.0), read back by a small reader here that follows the
// file's own references (scene -> node -> mesh -> accessor -> bufferView -> buffer), checking
// what the glTF 2.0 specification requires of each on the way.
#include <catch2/catch.hpp>

#include "support/json_value.hpp"
#include "support/mesh_checks.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

using vmtest::JsonValue;

namespace {

std::uint32_t u32_at(const std::string& bytes, std::size_t at) {
    REQUIRE(at + 4 <= bytes.size());
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
}

struct GlbFile {
    JsonValue json;
    std::string bin;       // the BIN chunk; empty where there is none
    bool has_bin = false;
};

// The container: a 12-byte header ("glTF", version 2, the file's length), then a JSON chunk
// padded with spaces, then at most one BIN chunk, chunk lengths multiples of 4.
GlbFile parse_container(const std::string& bytes) {
    REQUIRE(bytes.size() >= 20);
    CHECK(bytes.compare(0, 4, "glTF") == 0);
    CHECK(u32_at(bytes, 4) == 2);
    CHECK(u32_at(bytes, 8) == bytes.size());
    const std::uint32_t json_length = u32_at(bytes, 12);
    CHECK(json_length % 4 == 0);
    CHECK(bytes.compare(16, 4, "JSON") == 0);
    REQUIRE(20 + std::size_t{json_length} <= bytes.size());
    const std::string json_text = bytes.substr(20, json_length);
    GlbFile file;
    file.json = vmtest::parse_json(json_text);  // trailing padding spaces are JSON whitespace
    CHECK(json_text.find_first_not_of(' ', json_text.find_last_of('}') + 1) == std::string::npos);
    std::size_t at = 20 + std::size_t{json_length};
    if (at < bytes.size()) {
        const std::uint32_t bin_length = u32_at(bytes, at);
        CHECK(bin_length % 4 == 0);
        CHECK(bytes.compare(at + 4, 4, std::string("BIN\0", 4)) == 0);
        REQUIRE(at + 8 + bin_length == bytes.size());
        file.bin = bytes.substr(at + 8, bin_length);
        file.has_bin = true;
    }
    return file;
}

// The bytes accessor `a` reads, after checking it against its bufferView and buffer.
std::string accessor_bytes(const GlbFile& file, std::size_t a, std::uint32_t component_type, const std::string& type,
                           std::size_t element_bytes, std::uint32_t target) {
    const JsonValue& accessor = file.json["accessors"][a];
    CHECK(accessor["componentType"].number == component_type);
    CHECK(accessor["type"].text == type);
    const auto count = static_cast<std::size_t>(accessor["count"].number);
    CHECK(count >= 1);
    const std::size_t offset_in_view = accessor.has("byteOffset") ? static_cast<std::size_t>(accessor["byteOffset"].number) : 0;
    const JsonValue& view = file.json["bufferViews"][static_cast<std::size_t>(accessor["bufferView"].number)];
    CHECK(view["buffer"].number == 0);
    CHECK(view["target"].number == target);
    CHECK_FALSE(view.has("byteStride"));  // tightly packed
    const std::size_t view_offset = view.has("byteOffset") ? static_cast<std::size_t>(view["byteOffset"].number) : 0;
    const auto view_length = static_cast<std::size_t>(view["byteLength"].number);
    CHECK((view_offset + offset_in_view) % 4 == 0);
    REQUIRE(offset_in_view + count * element_bytes <= view_length);
    REQUIRE(file.has_bin);
    CHECK(file.json["buffers"][0]["byteLength"].number == file.bin.size());
    CHECK_FALSE(file.json["buffers"][0].has("uri"));  // the GLB's own BIN chunk
    REQUIRE(view_offset + view_length <= file.bin.size());
    return file.bin.substr(view_offset + offset_in_view, count * element_bytes);
}

template <class T>
std::vector<T> as_array(const std::string& bytes) {
    std::vector<T> out(bytes.size() / sizeof(T));
    std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
    return out;
}

struct GlbMesh {
    voxmesh::Mesh mesh;
    int mode = -1;         // the primitive's mode: 4 triangles, 0 points
    std::size_t meshes = 0;
    std::vector<double> min, max;  // POSITION's bounds as written
};

GlbMesh read_glb(const std::string& bytes) {
    const GlbFile file = parse_container(bytes);
    const JsonValue& json = file.json;
    CHECK(json["asset"]["version"].text == "2.0");
    GlbMesh out;
    const JsonValue& scene = json["scenes"][static_cast<std::size_t>(json["scene"].number)];
    if (!scene.has("nodes")) {
        CHECK_FALSE(json.has("meshes"));
        CHECK_FALSE(file.has_bin);
        return out;
    }
    REQUIRE(scene["nodes"].size() == 1);
    const JsonValue& node = json["nodes"][static_cast<std::size_t>(scene["nodes"][0].number)];
    CHECK_FALSE(node.has("matrix"));  // the mesh's own coordinates, untransformed
    out.meshes = json["meshes"].size();
    const JsonValue& primitives = json["meshes"][static_cast<std::size_t>(node["mesh"].number)]["primitives"];
    REQUIRE(primitives.size() == 1);
    const JsonValue& primitive = primitives[0];
    out.mode = primitive.has("mode") ? static_cast<int>(primitive["mode"].number) : 4;
    const JsonValue& attributes = primitive["attributes"];
    const auto position = static_cast<std::size_t>(attributes["POSITION"].number);
    out.mesh.positions = as_array<float>(accessor_bytes(file, position, 5126, "VEC3", 12, 34962));
    for (const JsonValue& v : json["accessors"][position]["min"].items) out.min.push_back(v.number);
    for (const JsonValue& v : json["accessors"][position]["max"].items) out.max.push_back(v.number);
    if (attributes.has("NORMAL"))
        out.mesh.normals = as_array<float>(
            accessor_bytes(file, static_cast<std::size_t>(attributes["NORMAL"].number), 5126, "VEC3", 12, 34962));
    if (primitive.has("indices"))
        out.mesh.indices = as_array<std::uint32_t>(
            accessor_bytes(file, static_cast<std::size_t>(primitive["indices"].number), 5125, "SCALAR", 4, 34963));
    return out;
}

voxmesh::Mesh sphere_mesh(bool normals) {
    const vmtest::Dims dims{21, 19, 17};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::sphere({10.2, 9.1, 8.3}, 6.5));
    voxmesh::Options o;
    o.backend = voxmesh::Backend::Cpu;
    o.normals = normals;
    return voxmesh::extract(vmtest::view_of(values, dims, {0.5, 0.75, 1.0}, {-2.5, 1.0, 100.0}), o);
}

std::string read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace

TEST_CASE("write_mesh: .glb holds the mesh's arrays, its bounds and one triangle primitive", "[core][glb]") {
    for (bool normals : {true, false}) {
        INFO((normals ? "with normals" : "without normals"));
        const voxmesh::Mesh mesh = sphere_mesh(normals);
        REQUIRE(mesh.triangle_count() > 100);
        vmtest::TempDir dir;
        const std::string path = dir.file("sphere.glb");
        voxmesh::write_mesh(path, mesh);
        const std::string bytes = read_all(path);
        CHECK(bytes == std::string(reinterpret_cast<const char*>(voxmesh::write_mesh_to_memory(mesh, "x.GLB").data()),
                                   bytes.size()));
        const GlbMesh back = read_glb(bytes);
        CHECK(back.mode == 4);
        CHECK(back.meshes == 1);
        CHECK(back.mesh.positions == mesh.positions);
        CHECK(back.mesh.normals == mesh.normals);
        CHECK(back.mesh.indices == mesh.indices);
        // min/max are the bounds of the floats written, exactly (shortest round-trip text).
        REQUIRE(back.min.size() == 3);
        REQUIRE(back.max.size() == 3);
        for (unsigned d = 0; d < 3; ++d) {
            float lo = mesh.positions[d], hi = mesh.positions[d];
            for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
                lo = std::min(lo, mesh.positions[3 * v + d]);
                hi = std::max(hi, mesh.positions[3 * v + d]);
            }
            CHECK(static_cast<float>(back.min[d]) == lo);
            CHECK(static_cast<float>(back.max[d]) == hi);
        }
        // What a glTF viewer sees is the same closed surface.
        CHECK(voxmesh::analyze_topology(back.mesh).closed());
    }
}

TEST_CASE("write_mesh: .glb of an empty mesh is a scene without nodes, of points a point primitive", "[core][glb]") {
    const GlbMesh empty = read_glb([] {
        const auto b = voxmesh::write_mesh_to_memory(voxmesh::Mesh{}, "e.glb");
        return std::string(b.begin(), b.end());
    }());
    CHECK(empty.meshes == 0);
    CHECK(empty.mesh.positions.empty());

    voxmesh::Mesh points;
    points.positions = {1, 2, 3, -4, 5.5f, -0.0f};
    points.normals = {0, 0, 1, 1, 0, 0};
    const auto b = voxmesh::write_mesh_to_memory(points, "p.glb");
    const GlbMesh back = read_glb(std::string(b.begin(), b.end()));
    CHECK(back.mode == 0);
    CHECK(back.mesh.positions == points.positions);
    CHECK(back.mesh.normals == points.normals);
    CHECK(back.mesh.indices.empty());
    CHECK(back.min == std::vector<double>{-4, 2, -0.0});
    CHECK(back.max == std::vector<double>{1, 5.5, 3});
}

TEST_CASE("write_mesh: .glb refuses what the others refuse and writes nothing", "[core][glb]") {
    vmtest::TempDir dir;
    voxmesh::Mesh mesh = sphere_mesh(true);
    mesh.normals[7] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(voxmesh::write_mesh(dir.file("n.glb"), mesh), Catch::Contains("non-finite normal"));
    mesh.normals[7] = 0.5f;  // not of unit length: glTF's validator calls that an error
    CHECK_THROWS_WITH(voxmesh::write_mesh(dir.file("u.glb"), mesh),
                      Catch::Contains("u.glb") && Catch::Contains("vertex 2's normal has length") &&
                          Catch::Contains("unit normals"));
    mesh.normals[7] = 0;
    mesh.normals[6] = mesh.normals[8] = 0;  // a zero normal too
    CHECK_THROWS_WITH(voxmesh::write_mesh_to_memory(mesh, "z.glb"), Catch::Contains("length 0"));
    mesh.normals.pop_back();
    CHECK_THROWS_AS(voxmesh::write_mesh(dir.file("m.glb"), mesh), voxmesh::Error);
    CHECK(dir.entries().empty());
}

TEST_CASE("parse_json reads what the .glb reader needs and refuses the malformed", "[core][glb]") {
    const JsonValue v = vmtest::parse_json(R"( {"a":[1,-2.5e3,true,false,null],"b":{"c":"x\"y"}}  )");
    CHECK(v["a"].size() == 5);
    CHECK(v["a"][1].number == -2500);
    CHECK(v["a"][2].boolean);
    CHECK_FALSE(v["a"][3].boolean);
    CHECK(v["a"][4].kind == JsonValue::Kind::Null);
    CHECK(v["b"]["c"].text == "x\"y");
    for (const char* bad : {"{", "[1,]", R"({"a":1,"a":2})", "1 2", R"({"a" 1})", "-", "\"abc"})
        CHECK_THROWS(vmtest::parse_json(bad));
}
