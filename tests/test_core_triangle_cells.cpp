// triangle_cells against the reference marching cubes (tests/support/reference_mc), which meshes
// one cell at a time and so knows each triangle's cell; and against extract's own triangles,
// whose vertices (by vertex_edges) must all lie on edges of the cell named for them.
#include <catch2/catch.hpp>

#include "support/mesh_checks.hpp"
#include "support/query_volumes.hpp"
#include "support/reference_mc.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

using vmtest::Dims;

namespace {

// True when `edge` (3 * sample + axis) is one of the twelve edges of `cell`
// (x + (nx-1) * (y + (ny-1) * z)): its lower end is a corner of the cell and the edge stays in it.
bool edge_of_cell(const Dims& n, std::uint64_t edge, std::uint64_t cell) {
    const unsigned axis = static_cast<unsigned>(edge % 3);
    const std::uint64_t s = edge / 3;
    const std::uint64_t at[3] = {s % n[0], s / n[0] % n[1], s / (n[0] * n[1])};
    const std::uint64_t c[3] = {cell % (n[0] - 1), cell / (n[0] - 1) % (n[1] - 1), cell / ((n[0] - 1) * (n[1] - 1))};
    for (unsigned d = 0; d < 3; ++d) {
        if (at[d] < c[d] || at[d] > c[d] + 1) return false;
        if (d == axis && at[d] != c[d]) return false;
    }
    return true;
}

// Every vertex of every triangle of `mesh` lies on an edge of the triangle's cell.
void require_triangles_in_cells(const voxmesh::Mesh& mesh, const std::vector<std::uint64_t>& cells,
                                const std::vector<std::uint64_t>& edges, const Dims& n) {
    REQUIRE(mesh.triangle_count() == cells.size());
    REQUIRE(mesh.vertex_count() == edges.size());
    std::size_t bad = 0;
    for (std::size_t t = 0; t < cells.size(); ++t)
        for (unsigned k = 0; k < 3; ++k) {
            const std::uint32_t v = mesh.indices[3 * t + k];
            if (!edge_of_cell(n, edges[v], cells[t]) && bad++ < 5)
                UNSCOPED_INFO("triangle " << t << ": vertex " << v << " on edge " << edges[v] << " is not an edge of cell "
                                          << cells[t]);
        }
    CHECK(bad == 0);
}

template <class T>
void check_triangle_cells(const std::vector<T>& data, const Dims& dims, double iso) {
    INFO(voxmesh::scalar_name(vmtest::scalar_type_of<T>()) << " " << dims[0] << "x" << dims[1] << "x" << dims[2]
                                                           << " iso " << iso);
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    vmtest::RefOptions ro;
    ro.iso = iso;
    const std::vector<std::uint64_t> expected = vmtest::reference_mc(vmtest::to_doubles(data), dims, ro).cells;
    for (unsigned threads : {1u, 2u, 3u, 8u, 0u}) {
        INFO("threads " << threads);
        REQUIRE(voxmesh::triangle_cells(view, iso, threads) == expected);
    }
    const voxmesh::Mesh mesh = voxmesh::extract(view, vmtest::cpu_options(iso, 2));
    require_triangles_in_cells(mesh, expected, voxmesh::vertex_edges(view, iso, 2), dims);
}

const Dims kOddDims[] = {{7, 5, 9}, {17, 3, 11}, {2, 2, 2}, {3, 2, 5}, {70, 4, 3}};

}  // namespace

TEMPLATE_TEST_CASE("triangle_cells matches the reference's cell of each triangle, on any thread count",
                   "[triangle_cells][core]", std::uint8_t, std::int8_t, std::int16_t, std::uint16_t, std::int32_t,
                   std::uint32_t, float, double) {
    std::uint32_t seed = 4321;
    for (const Dims& dims : kOddDims) {
        const std::vector<TestType> data = vmtest::random_volume<TestType>(dims, seed++);
        for (double iso : vmtest::iso_values(data)) check_triangle_cells(data, dims, iso);
    }
    const Dims cube{24, 24, 24};
    const std::vector<TestType> ball = vmtest::sphere_volume<TestType>(cube);
    for (double iso : {100.0, 100.5, 97.25}) check_triangle_cells(ball, cube, iso);
}

TEST_CASE("triangle_cells on a larger volume: rows of several words, many slabs", "[triangle_cells][core]") {
    // 130 samples a row: three words, the second word's last cell (x = 127) reading the next word.
    const Dims dims{130, 37, 29};
    const std::vector<float> data = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    for (double iso : {0.25, 0.0}) {
        INFO("iso " << iso);
        vmtest::RefOptions ro;
        ro.iso = iso;
        const std::vector<std::uint64_t> expected = vmtest::reference_mc(vmtest::to_doubles(data), dims, ro).cells;
        REQUIRE(expected.size() > 10000);
        for (unsigned threads : {1u, 2u, 3u, 8u}) {
            INFO("threads " << threads);
            CHECK(voxmesh::triangle_cells(view, iso, threads) == expected);
        }
        voxmesh::Options below = vmtest::cpu_options(iso, 2);
        below.inside_below = true;  // winding only: the same cells
        require_triangles_in_cells(voxmesh::extract(view, below), expected, voxmesh::vertex_edges(view, iso), dims);
    }
}

TEST_CASE("triangle_cells picks the triangles of a region: a sphere cut to its cells with x below the middle",
          "[triangle_cells][core]") {
    // The triangles whose cells a mask keeps are the mesh of those cells: a hemisphere shell, open
    // along the cut, with as many triangles as the reference gives the cells kept.
    const Dims dims{32, 32, 32};
    const std::vector<float> data = vmtest::sample_field<float>(dims, vmtest::sphere({15.5, 15.3, 15.7}, 10.0));
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    const std::vector<std::uint64_t> cells = voxmesh::triangle_cells(view, 0.0, 2);
    const voxmesh::Mesh mesh = voxmesh::extract(view, vmtest::cpu_options(0.0, 2));
    REQUIRE(cells.size() == mesh.triangle_count());
    std::size_t kept = 0;
    double x_max = -1;
    for (std::size_t t = 0; t < cells.size(); ++t) {
        if (cells[t] % (dims[0] - 1) >= 15) continue;
        ++kept;
        for (unsigned k = 0; k < 3; ++k) x_max = std::max<double>(x_max, mesh.positions[3 * mesh.indices[3 * t + k]]);
    }
    CHECK(kept > mesh.triangle_count() / 3);
    CHECK(kept < mesh.triangle_count() * 2 / 3);
    CHECK(x_max <= 15.0);  // no vertex of a kept triangle beyond the cut
}

TEST_CASE("triangle_cells: no crossings give an empty list", "[triangle_cells][core]") {
    const Dims dims{7, 5, 9};
    const std::vector<float> flat(dims[0] * dims[1] * dims[2], 3.5f);
    for (double iso : {3.5, 3.0, 4.0})
        for (unsigned threads : {1u, 3u}) CHECK(voxmesh::triangle_cells(vmtest::view_of(flat, dims), iso, threads).empty());
    const std::vector<std::uint8_t> bytes = vmtest::random_volume<std::uint8_t>(dims, 5);
    for (double iso : {300.0, -5.0, 255.5}) CHECK(voxmesh::triangle_cells(vmtest::view_of(bytes, dims), iso, 2).empty());
    // 255 is a value u8 holds: a 254 among 255s makes a small closed surface around it.
    std::vector<std::uint8_t> mixed(bytes.size(), 255);
    mixed[3 + 7 * (2 + 5 * 4)] = 254;
    CHECK(voxmesh::triangle_cells(vmtest::view_of(mixed, dims), 255, 1).size() == 8);
}

TEST_CASE("triangle_cells: NaN or infinite samples and bad volumes are Errors", "[triangle_cells][core]") {
    const Dims dims{6, 5, 7};
    std::vector<float> data = vmtest::random_volume<float>(dims, 11);
    SECTION("NaN names the first z-plane holding one, on any thread count") {
        data[2 + 6 * (1 + 5 * 5)] = std::numeric_limits<float>::quiet_NaN();
        data[4 + 6 * (3 + 5 * 3)] = std::numeric_limits<float>::quiet_NaN();
        for (unsigned threads : {1u, 2u, 8u}) {
            INFO("threads " << threads);
            CHECK_THROWS_WITH(voxmesh::triangle_cells(vmtest::view_of(data, dims), 0.0, threads),
                              Catch::Contains("NaN") && Catch::Contains("z-plane 3"));
        }
    }
    SECTION("NaN in the last plane, and where iso is beyond every sample") {
        data[1 + 6 * (1 + 5 * 6)] = std::numeric_limits<float>::quiet_NaN();
        CHECK_THROWS_WITH(voxmesh::triangle_cells(vmtest::view_of(data, dims), 0.0, 2), Catch::Contains("z-plane 6"));
        CHECK_THROWS_AS(voxmesh::triangle_cells(vmtest::view_of(data, dims), 1e39, 2), voxmesh::Error);
    }
    SECTION("infinity") {
        data[5 + 6 * (4 + 5 * 0)] = -std::numeric_limits<float>::infinity();
        CHECK_THROWS_AS(voxmesh::triangle_cells(vmtest::view_of(data, dims), 0.0, 1), voxmesh::Error);
    }
    SECTION("a dimension below 2, no data, a NaN iso") {
        const std::vector<float> small(64, 1.0f);
        for (const Dims& d : {Dims{1, 4, 4}, Dims{4, 1, 4}, Dims{4, 4, 1}, Dims{0, 4, 4}})
            CHECK_THROWS_AS(voxmesh::triangle_cells(vmtest::view_of(small, d), 0.5, 1), voxmesh::Error);
        voxmesh::VolumeView v = vmtest::view_of(data, dims);
        v.data = nullptr;
        CHECK_THROWS_AS(voxmesh::triangle_cells(v, 0.0, 1), voxmesh::Error);
        CHECK_THROWS_AS(voxmesh::triangle_cells(vmtest::view_of(data, dims), std::nan(""), 1), voxmesh::Error);
    }
}

TEST_CASE("vertex_edges_into and triangle_cells_into: the count always, the list where it fits", "[triangle_cells][core]") {
    const Dims dims{23, 19, 21};
    const std::vector<float> data = vmtest::sample_field<float>(dims, vmtest::wavy(0.5));
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    const std::vector<std::uint64_t> edges = voxmesh::vertex_edges(view, 0.1, 1);
    const std::vector<std::uint64_t> cells = voxmesh::triangle_cells(view, 0.1, 1);
    REQUIRE(edges.size() > 100);
    REQUIRE(cells.size() > 100);
    using Into = std::size_t (*)(const voxmesh::VolumeView&, double, std::span<std::uint64_t>, unsigned);
    const std::pair<Into, const std::vector<std::uint64_t>*> calls[] = {{&voxmesh::vertex_edges_into, &edges},
                                                                        {&voxmesh::triangle_cells_into, &cells}};
    for (const auto& [into, want] : calls) {
        for (unsigned threads : {1u, 2u, 5u}) {
            INFO("threads " << threads << ", " << want->size() << " entries");
            CHECK(into(view, 0.1, {}, threads) == want->size());  // the count alone
            std::vector<std::uint64_t> small(want->size() - 1, 7);
            CHECK(into(view, 0.1, small, threads) == want->size());
            CHECK(std::all_of(small.begin(), small.end(), [](std::uint64_t v) { return v == 7; }));  // nothing written
            std::vector<std::uint64_t> room(want->size() + 3, 7);
            CHECK(into(view, 0.1, room, threads) == want->size());
            CHECK(std::equal(want->begin(), want->end(), room.begin()));
            CHECK(room[want->size()] == 7);  // nothing past the list
        }
        std::vector<std::uint64_t> room(4, 7);
        CHECK(into(view, 1e9, room, 2) == 0);  // no surface
        CHECK(room[0] == 7);
    }
}
