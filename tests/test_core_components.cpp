// analyze_topology, keep_largest_components and MeshTopology::components, against deliberately
// simple oracles (sorted edge keys; a breadth-first walk over triangles that share a vertex)
// and against extract itself: a piece of a canonical mesh must be exactly the mesh of a volume
// holding that piece alone.
#include "support/mesh_checks.hpp"

#include "core/components.hpp"

#include <voxmesh/fields.hpp>
#include <voxmesh/io.hpp>
#include <voxmesh/voxmesh.hpp>

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

using namespace voxmesh;

namespace {

void require_identical(const Mesh& a, const Mesh& b) {
    REQUIRE(a.indices == b.indices);
    CHECK(vmtest::same_bits(a.positions, b.positions));
    CHECK(vmtest::same_bits(a.normals, b.normals));
}

}  // namespace

TEST_CASE("keep_largest_components: a piece of a canonical mesh is the mesh of that piece alone", "[core][components]") {
    // Two spheres 10 samples apart: near either surface the max() field is that sphere's own.
    const vmtest::Dims dims{64, 40, 40};
    const std::array<double, 3> big_c{20, 20, 20}, small_c{49, 20, 20};
    const auto both = vmtest::sample_field<float>(dims, vmtest::two_spheres(big_c, 12, small_c, 7));
    const auto big = vmtest::sample_field<float>(dims, vmtest::sphere(big_c, 12));
    const auto small = vmtest::sample_field<float>(dims, vmtest::sphere(small_c, 7));
    const Options o = vmtest::cpu_options(0, 0);
    const Mesh m = extract(vmtest::view_of(both, dims), o);

    const MeshTopology t = analyze_topology(m);
    CHECK(t.components == 2);
    CHECK(t.closed());
    CHECK(t.euler == 4);  // two spheres

    const Mesh largest = keep_largest_components(m);
    require_identical(largest, extract(vmtest::view_of(big, dims), o));
    CHECK(analyze_topology(largest).components == 1);
    CHECK(analyze_topology(largest).euler == 2);
    // The small one is what the largest leaves, and both (or more asked for) is everything.
    const Mesh small_alone = extract(vmtest::view_of(small, dims), o);
    CHECK(m.triangle_count() == largest.triangle_count() + small_alone.triangle_count());
    require_identical(keep_largest_components(m, 2), m);
    require_identical(keep_largest_components(m, 5), m);

    // Without normals, none come back.
    Options no_normals = o;
    no_normals.normals = false;
    const Mesh bare = keep_largest_components(extract(vmtest::view_of(both, dims), no_normals));
    CHECK(bare.normals.empty());
    CHECK(bare.indices == largest.indices);
}

TEST_CASE("keep_largest_components: equal pieces go to the one met first", "[core][components]") {
    const vmtest::Dims dims{56, 30, 30};
    const std::array<double, 3> left{14, 15, 15}, right{41, 15, 15};  // one sphere, moved 27 samples
    const auto both = vmtest::sample_field<float>(dims, vmtest::two_spheres(left, 9, right, 9));
    const auto first = vmtest::sample_field<float>(dims, vmtest::sphere(left, 9));
    const Options o = vmtest::cpu_options(0, 0);
    const Mesh m = extract(vmtest::view_of(both, dims), o);
    const Mesh kept = keep_largest_components(m);
    REQUIRE(2 * kept.triangle_count() == m.triangle_count());  // the same size
    // Triangles come in cell order, x fastest: the first triangle is the left sphere's.
    require_identical(kept, extract(vmtest::view_of(first, dims), o));
}

TEST_CASE("keep_largest_components matches a breadth-first oracle on a CT's many pieces", "[core][components]") {
    const Volume v = read_volume(std::string(VOXMESH_TEST_DATA) + "/headsq.nrrd");
    for (double iso : {499.5, 1150.5}) {
        INFO("iso " << iso);
        const Mesh m = extract(v.view(), vmtest::cpu_options(iso, 0));
        std::size_t pieces = 0;
        vmtest::oracle_pieces(m, pieces);
        CHECK(pieces > 5);  // a real CT: specks of noise beside the surface
        CHECK(analyze_topology(m).components == pieces);
        for (std::size_t count : {std::size_t{1}, std::size_t{3}, pieces - 1, pieces}) {
            INFO("count " << count);
            const Mesh kept = keep_largest_components(m, count);
            require_identical(kept, vmtest::oracle_keep_largest(m, count));
            CHECK(analyze_topology(kept).components == count);
            CHECK(vmtest::structural_problem(kept).empty());
        }
    }
}

TEST_CASE("keep_largest_components: pieces that touch only at a vertex are one piece", "[core][components]") {
    // Two triangles sharing vertex 2, and a third on its own.
    Mesh m;
    m.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 2, 1, 0, 2, 2, 0, 5, 5, 5, 6, 5, 5, 5, 6, 5};
    m.indices = {5, 6, 7, 0, 1, 2, 2, 3, 4};
    CHECK(analyze_topology(m).components == 2);
    const Mesh kept = keep_largest_components(m);
    CHECK(kept.indices == std::vector<std::uint32_t>{0, 1, 2, 2, 3, 4});
    CHECK(kept.positions == std::vector<float>(m.positions.begin(), m.positions.begin() + 15));
    // The single triangle, when asked for both, keeps its place first.
    const Mesh two = keep_largest_components(m, 2);
    CHECK(two.indices == m.indices);
}

TEST_CASE("keep_largest_components: empty meshes, unused vertices and bad arguments", "[core][components]") {
    CHECK(analyze_topology(Mesh{}).components == 0);
    const Mesh none = keep_largest_components(Mesh{});
    CHECK(none.positions.empty());
    CHECK(none.indices.empty());

    // A point cloud keeps nothing: vertices no triangle uses belong to no piece.
    Mesh cloud;
    cloud.positions = {0, 0, 0, 1, 1, 1};
    CHECK(keep_largest_components(cloud).positions.empty());

    Mesh stray = vmtest::small_sphere_mesh(true);
    const Mesh clean = keep_largest_components(stray);
    stray.positions.insert(stray.positions.begin(), {100, 100, 100});  // a vertex no face uses, first
    stray.normals.insert(stray.normals.begin(), {0, 0, 1});
    for (std::uint32_t& i : stray.indices) ++i;
    require_identical(keep_largest_components(stray), clean);

    CHECK_THROWS_WITH(keep_largest_components(clean, 0), Catch::Contains("count must be at least 1"));
    Mesh bad = clean;
    bad.indices.back() = static_cast<std::uint32_t>(bad.vertex_count());
    CHECK_THROWS_WITH(keep_largest_components(bad), Catch::Contains("out of range"));
    bad = clean;
    bad.positions.pop_back();
    CHECK_THROWS_AS(keep_largest_components(bad), Error);
}

TEST_CASE("analyze_topology agrees with the sorted-edge oracle on open, non-manifold and degenerate meshes", "[core][components]") {
    std::mt19937 rng(20261124);
    for (int round = 0; round < 200; ++round) {
        // Few vertices for many triangles: shared edges, edges in three or more triangles,
        // repeated corners, vertices no triangle uses.
        const std::size_t vertices = 1 + rng() % 40, triangles = rng() % 120;
        Mesh m;
        m.positions.assign(3 * vertices, 0.0f);
        for (std::size_t i = 0; i < 3 * triangles; ++i) m.indices.push_back(static_cast<std::uint32_t>(rng() % vertices));
        INFO("round " << round << ": " << vertices << " vertices, " << triangles << " triangles");
        const MeshTopology lib = analyze_topology(m);
        const vmtest::Topology oracle = vmtest::topology(m);
        CHECK(lib.boundary_edges == oracle.boundary_edges);
        CHECK(lib.nonmanifold_edges == oracle.nonmanifold_edges);
        CHECK(lib.euler == oracle.euler);
        std::size_t pieces = 0;
        vmtest::oracle_pieces(m, pieces);
        CHECK(lib.components == pieces);
        // The same on any number of worker threads, more than there are vertices too.
        for (unsigned workers : {2u, 3u, 7u}) {
            INFO(workers << " workers");
            const MeshTopology split = detail::topology_with_workers(m, workers);
            CHECK(split.boundary_edges == lib.boundary_edges);
            CHECK(split.nonmanifold_edges == lib.nonmanifold_edges);
            CHECK(split.euler == lib.euler);
            CHECK(split.components == lib.components);
        }
    }
    // And on a real CT's open surface.
    const Volume v = read_volume(std::string(VOXMESH_TEST_DATA) + "/headsq.nrrd");
    const Mesh head = extract(v.view(), vmtest::cpu_options(499.5, 0));
    const vmtest::Topology oracle = vmtest::topology(head);
    const MeshTopology lib = analyze_topology(head);
    CHECK(lib.boundary_edges == oracle.boundary_edges);
    CHECK(lib.boundary_edges > 0);
    CHECK(lib.nonmanifold_edges == oracle.nonmanifold_edges);
    CHECK(lib.euler == oracle.euler);
}

TEST_CASE("analyze_topology and the pieces give the same on any number of worker threads", "[core][components]") {
    // The CT phantom at 160³: about 270 000 triangles in 5 pieces, split over 1 to 8 workers
    // (analyze_topology and keep_largest_components pick 1 for a mesh this size here).
    const FieldVolume field = make_field(Field::Ct, 160);
    const Mesh m = extract(field.volume.view(), vmtest::cpu_options(field.iso, 0));
    const vmtest::Topology oracle = vmtest::topology(m);
    std::size_t pieces = 0;
    const std::vector<std::size_t> piece_of = vmtest::oracle_pieces(m, pieces);
    for (unsigned workers : {1u, 2u, 3u, 8u}) {
        INFO(workers << " workers");
        const detail::MeshPieces split = detail::mesh_pieces(m, workers);
        CHECK(std::equal(split.of_triangle.begin(), split.of_triangle.end(), piece_of.begin(), piece_of.end()));
        CHECK(split.triangles.size() == pieces);
        const MeshTopology t = detail::topology_with_workers(m, workers);
        CHECK(t.boundary_edges == oracle.boundary_edges);
        CHECK(t.nonmanifold_edges == oracle.nonmanifold_edges);
        CHECK(t.euler == oracle.euler);
        CHECK(t.components == pieces);
    }
    REQUIRE(pieces > 3);
    CHECK(analyze_topology(m).components == pieces);
    for (std::size_t count : {std::size_t{1}, std::size_t{3}, pieces}) {
        INFO("count " << count);
        require_identical(keep_largest_components(m, count), vmtest::oracle_keep_largest(m, count));
    }
}


TEST_CASE("analyze_topology: a repeated corner is no edge, and the one edge of a sliver counts once", "[core][components]") {
    Mesh tet;  // closed: euler 2
    tet.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    tet.indices = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
    REQUIRE(analyze_topology(tet).closed());

    // A welded sliver (0, 0, 1) on the tetrahedron's edge {0, 1}: that edge is now in three
    // triangles; there is no edge {0, 0}. It used to count {0, 1} twice more and {0, 0} as a
    // boundary edge.
    Mesh sliver = tet;
    sliver.indices.insert(sliver.indices.end(), {0, 0, 1});
    MeshTopology t = analyze_topology(sliver);
    CHECK(t.boundary_edges == 0);
    CHECK(t.nonmanifold_edges == 1);
    CHECK(t.euler == 4 - 6 + 5);

    // A point-triangle (2, 2, 2) has no edge at all: the mesh stays closed (it used to read
    // as an edge {2, 2} in three triangles).
    Mesh point = tet;
    point.indices.insert(point.indices.end(), {2, 2, 2});
    t = analyze_topology(point);
    CHECK(t.boundary_edges == 0);
    CHECK(t.nonmanifold_edges == 0);
    CHECK(t.euler == 4 - 6 + 5);
    CHECK(t.components == 1);

    // A lone sliver: one edge, in one triangle.
    Mesh lone;
    lone.positions = {0, 0, 0, 1, 0, 0};
    lone.indices = {1, 0, 1};
    t = analyze_topology(lone);
    CHECK(t.boundary_edges == 1);
    CHECK(t.nonmanifold_edges == 0);
    CHECK(t.euler == 2 - 1 + 1);
    for (unsigned workers : {2u, 3u}) {
        const MeshTopology split = detail::topology_with_workers(sliver, workers);
        CHECK(split.boundary_edges == 0);
        CHECK(split.nonmanifold_edges == 1);
        CHECK(split.euler == 3);
    }
}
