// Sculpting a model loaded from STL (read_stl + voxelize into a distance field).
#include <catch2/catch.hpp>

#include <voxmesh/io.hpp>
#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxelize.hpp>

#include <array>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <unistd.h>

TEST_CASE("sculpt: an STL model is voxelized, sculpted in world units and stays closed", "[sculpt]") {
    char dir[] = "/tmp/voxmesh-sculpt-stl-XXXXXX";
    REQUIRE(mkdtemp(dir) != nullptr);
    const std::string path = std::string(dir) + "/octahedron.stl";
    {
        // An octahedron with corners at +-10 on each axis, wound outward.
        const double p[6][3] = {{10, 0, 0}, {-10, 0, 0}, {0, 10, 0}, {0, -10, 0}, {0, 0, 10}, {0, 0, -10}};
        const int f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
        std::ofstream out(path);
        out << "solid octahedron\n";
        for (const auto& t : f) {
            out << " facet normal 0 0 0\n  outer loop\n";
            for (int v : t) out << "   vertex " << p[v][0] << " " << p[v][1] << " " << p[v][2] << "\n";
            out << "  endloop\n endfacet\n";
        }
        out << "endsolid octahedron\n";
    }
    voxmesh::SculptOptions o;
    o.block_size = 8;
    voxmesh::Sculpt s = voxmesh::Sculpt::from_stl(path, 32, o);
    std::remove(path.c_str());
    rmdir(dir);
    REQUIRE(s.view().type == voxmesh::ScalarType::F32);
    REQUIRE(s.options().strength_scale == Approx(s.view().spacing[0]));
    s.update();
    voxmesh::Options eo;
    eo.backend = voxmesh::Backend::Cpu;
    REQUIRE(s.mesh().indices == voxmesh::extract(s.view(), eo).indices);

    // Carve a dent into the +x corner and build up the -y corner, in model units.
    s.subtract({9, 0, 0}, 3, 2, voxmesh::Units::World);
    s.add({0, -9, 0}, 3, 1.5, voxmesh::Units::World);
    s.smooth({0, 0, 9}, 4, 1, voxmesh::Units::World);
    REQUIRE(s.update().changed.size() > 0);
    const voxmesh::Mesh m = s.mesh();
    const voxmesh::Mesh want = voxmesh::extract(s.view(), eo);
    REQUIRE(m.indices == want.indices);
    REQUIRE(std::memcmp(m.positions.data(), want.positions.data(), 4 * m.positions.size()) == 0);
    REQUIRE(voxmesh::analyze_topology(m).closed());
    REQUIRE_THROWS_AS(voxmesh::Sculpt::from_stl("/nonexistent/model.stl", 32), voxmesh::Error);
}

TEST_CASE("sculpt: a model voxelized with options of its own: padding, band, and only a distance field", "[sculpt]") {
    const voxmesh::Mesh model = voxmesh::read_mesh(std::string(VOXMESH_TEST_DATA) + "/unit_sphere.stl");
    voxmesh::SculptOptions o;
    o.block_size = 8;
    // The resolution-only form is this one with padding 2 and band 4.
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 24;
    vo.band = 4;
    const voxmesh::Sculpt plain = voxmesh::Sculpt::from_mesh(model, 24, o);
    const voxmesh::Sculpt same = voxmesh::Sculpt::from_mesh(model, vo, o);
    REQUIRE(same.view().dims == plain.view().dims);
    REQUIRE(std::memcmp(same.view().data, plain.view().data, 4 * 28 * 28 * 28) == 0);
    REQUIRE(same.options().strength_scale == plain.options().strength_scale);

    // A bump of 4 voxels on top: cut open by the border with 2 samples of padding, closed with 8.
    vo.padding = 8;
    voxmesh::Sculpt roomy = voxmesh::Sculpt::from_mesh(model, vo, o);
    REQUIRE(roomy.view().dims == std::array<std::size_t, 3>{40, 40, 40});
    voxmesh::Sculpt tight = voxmesh::Sculpt::from_mesh(model, 24, o);
    for (voxmesh::Sculpt* s : {&roomy, &tight}) s->add({0, 0, 1}, 0.4, 4, voxmesh::Units::World);
    CHECK(voxmesh::analyze_topology(roomy.mesh()).closed());
    CHECK(voxmesh::analyze_topology(roomy.mesh()).euler == 2);
    CHECK_FALSE(voxmesh::analyze_topology(tight.mesh()).closed());

    vo.field = voxmesh::VoxelField::Occupancy;
    REQUIRE_THROWS_WITH(voxmesh::Sculpt::from_mesh(model, vo, o), Catch::Contains("distance field"));
}

// Found by a review: a bad option (a device index past the list, a block size) was reported
// only after the model was voxelized, minutes at a high resolution. A model the voxelizer
// refuses (no triangles) shows which check came first.
TEST_CASE("sculpt: from_mesh checks its options before it voxelizes", "[sculpt]") {
    const voxmesh::Mesh no_triangles;
    voxmesh::SculptOptions o;
    REQUIRE_THROWS_WITH(voxmesh::Sculpt::from_mesh(no_triangles, 24, o), Catch::Contains("no triangles"));
    o.block_size = 1;
    CHECK_THROWS_WITH(voxmesh::Sculpt::from_mesh(no_triangles, 24, o), Catch::Contains("block size"));
    o.block_size = 16;
    o.backend = voxmesh::Backend::Hybrid;
    CHECK_THROWS_WITH(voxmesh::Sculpt::from_mesh(no_triangles, 24, o), Catch::Contains("hybrid"));
    o.backend = voxmesh::Backend::OpenCL;
    o.device = 99;
    if (voxmesh::list_devices().empty()) {
        // No device: the CPU re-meshes (with a warning), so the index is no error.
        CHECK_THROWS_WITH(voxmesh::Sculpt::from_mesh(no_triangles, 24, o), Catch::Contains("no triangles"));
    } else {
        CHECK_THROWS_WITH(voxmesh::Sculpt::from_mesh(no_triangles, 24, o),
                          Catch::Contains("device index 99 does not exist"));
    }
}
