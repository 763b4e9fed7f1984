// voxmesh_vertex_edges, voxmesh_edge_cell_ranges and voxmesh_compute_value_range against the C++
// calls they wrap, and their refusals (the C++ functions themselves: test_core_vertex_edges.cpp,
// test_core_value_range.cpp).
#ifdef VOXMESH_TEST_C_API
#include <catch2/catch.hpp>
#include <voxmesh/voxmesh.h>
#include <voxmesh/voxmesh.hpp>

#include "support/c_api.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

using capitest::c_view;

struct Ball {
    std::vector<float> samples;
    voxmesh::VolumeView view;
};

Ball ball(std::size_t n) {
    Ball b;
    b.samples.resize(n * n * n);
    const double c = 0.5 * static_cast<double>(n - 1) + 0.13;
    for (std::size_t z = 0; z < n; ++z)
        for (std::size_t y = 0; y < n; ++y)
            for (std::size_t x = 0; x < n; ++x)
                b.samples[x + n * (y + n * z)] = static_cast<float>(
                    0.35 * static_cast<double>(n) - std::sqrt((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c)));
    b.view.data = b.samples.data();
    b.view.type = voxmesh::ScalarType::F32;
    b.view.dims = {n, n, n};
    return b;
}

}  // namespace

TEST_CASE("C API: vertex edges and cell ranges are the C++ calls'", "[capi][vertex_edges]") {
    const Ball b = ball(21);
    const voxmesh_volume_view view = c_view(b.view);
    const std::vector<std::uint64_t> want = voxmesh::vertex_edges(b.view, 0.0, 2);
    REQUIRE(!want.empty());

    size_t count = 0;
    REQUIRE(voxmesh_vertex_edges(&view, 0.0, 1, nullptr, 0, &count) == VOXMESH_OK);  // the count alone
    REQUIRE(count == want.size());
    std::vector<std::uint64_t> got(count + 2, 7);
    REQUIRE(voxmesh_vertex_edges(&view, 0.0, 2, got.data(), got.size(), &count) == VOXMESH_OK);
    REQUIRE(count == want.size());
    REQUIRE(std::equal(want.begin(), want.end(), got.begin()));
    REQUIRE(got[count] == 7);  // nothing past the edges written

    std::vector<std::uint8_t> mask((20 * 20 * 20), 0);
    std::mt19937 random(5);
    for (auto& m : mask) m = static_cast<std::uint8_t>(random() % 3 != 0);
    for (const std::uint8_t* cell_mask : {static_cast<const std::uint8_t*>(nullptr), static_cast<const std::uint8_t*>(mask.data())}) {
        const std::vector<float> ranges = voxmesh::edge_cell_ranges(b.view, want, 0.25, cell_mask, 1);
        std::vector<float> c(want.size(), -1.0f);
        REQUIRE(voxmesh_edge_cell_ranges(&view, want.data(), want.size(), 0.25, cell_mask, 2, c.data()) == VOXMESH_OK);
        REQUIRE(std::memcmp(c.data(), ranges.data(), ranges.size() * sizeof(float)) == 0);
    }
    REQUIRE(voxmesh_edge_cell_ranges(&view, nullptr, 0, 0.0, nullptr, 0, nullptr) == VOXMESH_OK);  // no edges, no work
}

TEST_CASE("C API: vertex edges and cell ranges refuse with the problem named", "[capi][vertex_edges]") {
    Ball b = ball(9);
    voxmesh_volume_view view = c_view(b.view);
    size_t count = 99;
    std::vector<std::uint64_t> small(3);
    REQUIRE(voxmesh_vertex_edges(&view, 0.0, 0, small.data(), small.size(), &count) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("room for 3 edges") && Catch::Contains("crossed edges"));
    REQUIRE(count == voxmesh::vertex_edges(b.view, 0.0).size());  // the room it needs
    REQUIRE(voxmesh_vertex_edges(&view, 0.0, 0, nullptr, 0, nullptr) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("count pointer"));
    REQUIRE(voxmesh_vertex_edges(nullptr, 0.0, 0, nullptr, 0, &count) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("volume"));

    b.samples[4 + 9 * (2 + 9 * 6)] = std::numeric_limits<float>::quiet_NaN();
    REQUIRE(voxmesh_vertex_edges(&view, 0.0, 0, nullptr, 0, &count) == VOXMESH_ERROR);
    REQUIRE(count == 0);  // a failure other than the room leaves no count
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("NaN") && Catch::Contains("z-plane 6"));

    const std::uint64_t past = 3 * 9 * 9 * 9;
    float range = 0;
    REQUIRE(voxmesh_edge_cell_ranges(&view, &past, 1, 0.0, nullptr, 0, &range) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("edges[0]") && Catch::Contains("past the volume"));
    const std::uint64_t last_z = 3 * (9 * 9 * 8) + 2;  // a z-edge from the last plane
    REQUIRE(voxmesh_edge_cell_ranges(&view, &last_z, 1, 0.0, nullptr, 0, &range) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("last sample"));
    REQUIRE(voxmesh_edge_cell_ranges(&view, nullptr, 1, 0.0, nullptr, 0, &range) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("edges"));
    // Counts near SIZE_MAX wrapped the piece count to 0: success, nothing done. Refused before
    // any edge is read, so the one-edge arrays are enough.
    for (const std::size_t huge : {SIZE_MAX, SIZE_MAX - 1, SIZE_MAX - 65535, SIZE_MAX / 2}) {
        INFO(huge);
        REQUIRE(voxmesh_edge_cell_ranges(&view, &past, huge, 0.0, nullptr, 0, &range) == VOXMESH_ERROR);
        REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("too many edges"));
    }
    view.type = 42;
    REQUIRE(voxmesh_vertex_edges(&view, 0.0, 0, nullptr, 0, &count) == VOXMESH_ERROR);
}

TEST_CASE("C API: triangle cells are the C++ call's, and refuse with the problem named", "[capi][triangle_cells]") {
    Ball b = ball(17);
    voxmesh_volume_view view = c_view(b.view);
    const std::vector<std::uint64_t> want = voxmesh::triangle_cells(b.view, 0.0, 2);
    REQUIRE(!want.empty());
    size_t count = 0;
    REQUIRE(voxmesh_triangle_cells(&view, 0.0, 1, nullptr, 0, &count) == VOXMESH_OK);  // the count alone
    REQUIRE(count == want.size());
    std::vector<std::uint64_t> got(count + 1, 7);
    REQUIRE(voxmesh_triangle_cells(&view, 0.0, 2, got.data(), got.size(), &count) == VOXMESH_OK);
    REQUIRE(count == want.size());
    REQUIRE(std::equal(want.begin(), want.end(), got.begin()));
    REQUIRE(got[count] == 7);

    std::vector<std::uint64_t> small(5);
    count = 0;
    REQUIRE(voxmesh_triangle_cells(&view, 0.0, 0, small.data(), small.size(), &count) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("voxmesh_triangle_cells: room for 5 cells") &&
                                           Catch::Contains(std::to_string(want.size()) + " triangles"));
    REQUIRE(count == want.size());
    REQUIRE(voxmesh_triangle_cells(&view, 0.0, 0, nullptr, 0, nullptr) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("count pointer"));
    REQUIRE(voxmesh_triangle_cells(nullptr, 0.0, 0, nullptr, 0, &count) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("volume"));
    b.samples[4 + 17 * (2 + 17 * 9)] = std::numeric_limits<float>::quiet_NaN();
    REQUIRE(voxmesh_triangle_cells(&view, 0.0, 0, nullptr, 0, &count) == VOXMESH_ERROR);
    REQUIRE(count == 0);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("NaN") && Catch::Contains("z-plane 9"));
}

TEST_CASE("C API: the value range is the C++ call's", "[capi][value_range]") {
    Ball b = ball(13);
    b.samples[3 + 13 * (4 + 13 * 5)] = std::numeric_limits<float>::infinity();
    b.samples[100] = 0.0f;
    const voxmesh_volume_view view = c_view(b.view);
    for (const double* equal_to : {static_cast<const double*>(nullptr), static_cast<const double*>(&b.view.origin[0])}) {
        const voxmesh::ValueRange want =
            voxmesh::value_range(b.view, equal_to ? std::optional<double>(*equal_to) : std::nullopt, 1);
        voxmesh_value_range got;
        REQUIRE(voxmesh_compute_value_range(&view, equal_to, 2, &got) == VOXMESH_OK);
        CHECK(got.min == want.min);
        CHECK(got.max == want.max);
        CHECK(got.nonfinite == 1);
        CHECK(got.first_nonfinite[0] == 3);
        CHECK(got.first_nonfinite[1] == 4);
        CHECK(got.first_nonfinite[2] == 5);
        CHECK(got.equal == want.equal);
        CHECK(got.equal == (equal_to ? 1u : 0u));  // the origin's 0.0: the one sample set to it
    }
    voxmesh_value_range r;
    REQUIRE(voxmesh_compute_value_range(&view, nullptr, 0, nullptr) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("result pointer"));
    REQUIRE(voxmesh_compute_value_range(nullptr, nullptr, 0, &r) == VOXMESH_ERROR);
    REQUIRE_THAT(voxmesh_last_error(), Catch::Contains("volume"));
}
#endif
