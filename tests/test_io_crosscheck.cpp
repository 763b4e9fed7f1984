// The real CT meshed by the CPU engine against VTK 9's counts (tests/data LICENSES.md,
// shared data README): a check of reader and engine together.
#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <string>

using namespace voxmesh;

TEST_CASE("io cross-check: headsq meshes to VTK's triangle and vertex counts", "[io][crosscheck]") {
    const Volume v = read_volume(std::string(VOXMESH_TEST_DATA) + "/headsq.nrrd");
    Options options;
    options.backend = Backend::Cpu;
    options.normals = false;
    struct Case {
        double iso;
        std::size_t triangles, vertices;
    };
    for (const Case c : {Case{499.5, 57698, 29057}, Case{1149.5, 78476, 39420}}) {
        options.iso = c.iso;
        const Mesh mesh = extract(v.view(), options);
        INFO("iso " << c.iso);
        CHECK(mesh.triangle_count() == c.triangles);
        CHECK(mesh.vertex_count() == c.vertices);
    }
}
