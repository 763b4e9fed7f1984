// write_mesh to .glb (binary glTF 2.0), read back by the tests' small glTF reader
// (support/glb_reader.hpp), which checks what the specification requires on the way.
#include <catch2/catch.hpp>

#include "support/glb_reader.hpp"
#include "support/io_scratch.hpp"
#include "support/json_value.hpp"
#include "support/mesh_checks.hpp"

#include "core/glb_writer.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

using vmtest::JsonValue;

namespace {

vmtest::GlbContents read_glb(const std::string& bytes) {
    vmtest::GlbContents contents;
    REQUIRE_NOTHROW(contents = vmtest::read_glb(bytes));
    return contents;
}

voxmesh::Mesh sphere_mesh(bool normals) {
    const vmtest::Dims dims{21, 19, 17};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::sphere({10.2, 9.1, 8.3}, 6.5));
    voxmesh::Options o;
    o.backend = voxmesh::Backend::Cpu;
    o.normals = normals;
    return voxmesh::extract(vmtest::view_of(values, dims, {0.5, 0.75, 1.0}, {-2.5, 1.0, 100.0}), o);
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
        const std::string bytes = iotest::read_file(path);
        const std::vector<unsigned char> in_memory = voxmesh::write_mesh_to_memory(mesh, "x.GLB");
        CHECK(bytes == std::string(in_memory.begin(), in_memory.end()));
        const vmtest::GlbContents back = read_glb(bytes);
        CHECK(back.mode == 4);
        CHECK(back.meshes == 1);
        CHECK(back.mesh.positions == mesh.positions);
        CHECK(back.mesh.normals == mesh.normals);
        CHECK(back.mesh.indices == mesh.indices);
        // min/max are the bounds of the floats written, exactly: as doubles, not only once
        // rounded to float.
        REQUIRE(back.min.size() == 3);
        REQUIRE(back.max.size() == 3);
        for (unsigned d = 0; d < 3; ++d) {
            float lo = mesh.positions[d], hi = mesh.positions[d];
            for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
                lo = std::min(lo, mesh.positions[3 * v + d]);
                hi = std::max(hi, mesh.positions[3 * v + d]);
            }
            CHECK(back.min[d] == static_cast<double>(lo));
            CHECK(back.max[d] == static_cast<double>(hi));
        }
        // What a glTF viewer sees is the same closed surface.
        CHECK(voxmesh::analyze_topology(back.mesh).closed());
    }
}

TEST_CASE("write_mesh: .glb of an empty mesh is a scene without nodes, of points a point primitive", "[core][glb]") {
    const vmtest::GlbContents empty = read_glb([] {
        const auto b = voxmesh::write_mesh_to_memory(voxmesh::Mesh{}, "e.glb");
        return std::string(b.begin(), b.end());
    }());
    CHECK(empty.meshes == 0);
    CHECK(empty.mesh.positions.empty());

    voxmesh::Mesh points;
    points.positions = {1, 2, 3, -4, 5.5f, -0.0f, 0.1f, 5.831554e-39f, 3.1f};  // 3.1f is no double's 3.1; a denormal
    points.normals = {0, 0, 1, 1, 0, 0, 0, -1, 0};
    const auto b = voxmesh::write_mesh_to_memory(points, "p.glb");
    const vmtest::GlbContents back = read_glb(std::string(b.begin(), b.end()));
    CHECK(back.mode == 0);
    CHECK(back.mesh.positions == points.positions);
    CHECK(back.mesh.normals == points.normals);
    CHECK(back.mesh.indices.empty());
    CHECK(back.min == std::vector<double>{-4, double{5.831554e-39f}, -0.0});
    CHECK(back.max == std::vector<double>{1, 5.5, double{3.1f}});
}

TEST_CASE("write_mesh: .glb refuses what the others refuse and writes nothing", "[core][glb]") {
    vmtest::TempDir dir;
    voxmesh::Mesh mesh = sphere_mesh(true);
    mesh.normals[7] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(voxmesh::write_mesh(dir.file("n.glb"), mesh), Catch::Contains("non-finite normal"));
    // Normals off unit length by more than glTF-Validator's 0.00674 are refused, by less kept.
    for (const double length : {0.5, 0.0, 1.0068, 0.9932, 1.0067, 0.9933, 1 + 1e-6}) {
        INFO(length);
        mesh.normals[6] = 0;
        mesh.normals[7] = static_cast<float>(length);
        mesh.normals[8] = 0;
        const bool unit = std::fabs(length - 1) <= 0.00674;
        if (unit) {
            CHECK_NOTHROW(voxmesh::write_mesh_to_memory(mesh, "u.glb"));
        } else {
            CHECK_THROWS_WITH(voxmesh::write_mesh(dir.file("u.glb"), mesh),
                              Catch::Contains("u.glb") && Catch::Contains("vertex 2's normal has length") &&
                                  Catch::Contains("unit normals"));
        }
    }
    mesh.normals.pop_back();
    CHECK_THROWS_AS(voxmesh::write_mesh(dir.file("m.glb"), mesh), voxmesh::Error);
    CHECK(dir.entries().empty());
}

TEST_CASE("glb: a file past the container's 32-bit length is refused, counted without the arrays", "[core][glb]") {
    using voxmesh::detail::checked_glb_bytes;
    // 12 + 8 + JSON + 8 + 12 per vertex (24 with normals) + 12 per triangle.
    CHECK(checked_glb_bytes(0, false, 0, 100, "e.glb") == 120);  // no BIN chunk
    CHECK(checked_glb_bytes(3, true, 1, 1000, "t.glb") == 12 + 8 + 1000 + 8 + 72 + 12);
    const std::uint64_t limit = 0xffffffffull;
    // The largest file that fits, by its triangle count, and one byte of JSON more.
    const std::uint64_t json = limit - 12 - 8 - 8 - 24 * 1000 - 12 * 357000000ull;
    CHECK(checked_glb_bytes(1000, true, 357000000ull, json, "big.glb") == limit);
    CHECK_THROWS_WITH(checked_glb_bytes(1000, true, 357000000ull, json + 1, "big.glb"),
                      Catch::Contains("big.glb") && Catch::Contains("4294967296 bytes") && Catch::Contains("32-bit"));
    CHECK_THROWS(checked_glb_bytes(400000000ull, false, 0, 1000, "v.glb"));
}

TEST_CASE("parse_json reads what the .glb reader needs and refuses the malformed", "[core][glb]") {
    const JsonValue v = vmtest::parse_json(R"( {"a":[1,-2.5e3,true,false,null],"b":{"c":"x\"y"}}  )");
    CHECK(v["a"].size() == 5);
    CHECK(v["a"][1].number == -2500);
    CHECK(vmtest::parse_json("[0,-0,0.5,1E-2,10e+1]")[4].number == 100);
    CHECK(v["a"][2].boolean);
    CHECK_FALSE(v["a"][3].boolean);
    CHECK(v["a"][4].kind == JsonValue::Kind::Null);
    CHECK(v["b"]["c"].text == "x\"y");
    for (const char* bad : {"{", "[1,]", R"({"a":1,"a":2})", "1 2", R"({"a" 1})", "-", "\"abc", "01", "1.", "1.e5", ".5",
                            "1e", "+1", "-01", "1e+"})
        CHECK_THROWS(vmtest::parse_json(bad));
}
