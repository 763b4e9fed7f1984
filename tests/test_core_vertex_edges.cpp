// vertex_edges and edge_cell_ranges against deliberately simple oracles written here: a
// brute-force walk over every sample's three edges, and the up-to-four cells around an edge
// enumerated one by one. Also their ties to extract() and their errors.
#include <catch2/catch.hpp>

#include "support/mesh_checks.hpp"
#include "support/query_volumes.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

using vmtest::Dims;
using vmtest::iso_values;
using vmtest::random_volume;
using vmtest::sphere_volume;

namespace {

// ------------------------------------------------------------------ oracles

// Inside is value >= iso; for integer samples that is value >= ceil(iso) (the same thing for an
// integer value, spelled out as the contract says it).
template <class T>
bool oracle_inside(T value, double iso) {
    if constexpr (std::is_integral_v<T>) return static_cast<double>(value) >= std::ceil(iso);
    else return static_cast<double>(value) >= iso;
}

std::size_t sample_index(const Dims& n, std::size_t x, std::size_t y, std::size_t z) {
    return x + n[0] * (y + n[1] * z);
}

// Every edge, in (z, y, x, axis) order, whose two ends differ in inside-ness.
template <class T>
std::vector<std::uint64_t> oracle_vertex_edges(const std::vector<T>& data, const Dims& n, double iso) {
    std::vector<std::uint64_t> out;
    for (std::size_t z = 0; z < n[2]; ++z)
        for (std::size_t y = 0; y < n[1]; ++y)
            for (std::size_t x = 0; x < n[0]; ++x) {
                const std::size_t at[3] = {x, y, z};
                const std::size_t i = sample_index(n, x, y, z);
                for (unsigned axis = 0; axis < 3; ++axis) {
                    if (at[axis] + 1 >= n[axis]) continue;  // no edge past the last sample
                    std::size_t up[3] = {x, y, z};
                    ++up[axis];
                    const std::size_t j = sample_index(n, up[0], up[1], up[2]);
                    if (oracle_inside(data[i], iso) != oracle_inside(data[j], iso))
                        out.push_back(3 * static_cast<std::uint64_t>(i) + axis);
                }
            }
    return out;
}

// Every edge the volume holds, in numbering order.
std::vector<std::uint64_t> all_edges(const Dims& n) {
    std::vector<std::uint64_t> out;
    for (std::size_t z = 0; z < n[2]; ++z)
        for (std::size_t y = 0; y < n[1]; ++y)
            for (std::size_t x = 0; x < n[0]; ++x) {
                const std::size_t at[3] = {x, y, z};
                for (unsigned axis = 0; axis < 3; ++axis)
                    if (at[axis] + 1 < n[axis]) out.push_back(3 * static_cast<std::uint64_t>(sample_index(n, x, y, z)) + axis);
            }
    return out;
}

// For each edge: the cells (lower corner = the edge's lower end minus 0 or 1 along each of the
// two other axes) lying fully in the volume and marked by the mask (when given); the largest
// (max - offset) - (min - offset) over their 8 corners, in double, rounded to float; 0 for none.
template <class T>
std::vector<float> oracle_cell_ranges(const std::vector<T>& data, const Dims& n, const std::vector<std::uint64_t>& edges,
                                      double offset, const std::uint8_t* mask) {
    std::vector<float> out;
    for (std::uint64_t e : edges) {
        const unsigned axis = static_cast<unsigned>(e % 3);
        std::size_t s = static_cast<std::size_t>(e / 3);
        const std::size_t lo[3] = {s % n[0], (s / n[0]) % n[1], s / (n[0] * n[1])};
        const unsigned b = (axis + 1) % 3, c = (axis + 2) % 3;
        bool any = false;
        float best = 0;
        for (int db = 0; db <= 1; ++db)
            for (int dc = 0; dc <= 1; ++dc) {
                long long cell[3] = {static_cast<long long>(lo[0]), static_cast<long long>(lo[1]),
                                     static_cast<long long>(lo[2])};
                cell[b] -= db;
                cell[c] -= dc;
                bool inside_volume = true;
                for (unsigned d = 0; d < 3; ++d)
                    if (cell[d] < 0 || cell[d] + 1 > static_cast<long long>(n[d]) - 1) inside_volume = false;
                if (!inside_volume) continue;
                const std::size_t cx = static_cast<std::size_t>(cell[0]), cy = static_cast<std::size_t>(cell[1]),
                                  cz = static_cast<std::size_t>(cell[2]);
                if (mask && mask[cx + (n[0] - 1) * (cy + (n[1] - 1) * cz)] == 0) continue;
                double mx = -std::numeric_limits<double>::infinity(), mn = std::numeric_limits<double>::infinity();
                for (std::size_t k = 0; k < 8; ++k) {
                    const double v = static_cast<double>(data[sample_index(n, cx + (k & 1), cy + (k >> 1 & 1), cz + (k >> 2 & 1))]);
                    mx = std::max(mx, v);
                    mn = std::min(mn, v);
                }
                const float range = static_cast<float>((mx - offset) - (mn - offset));
                best = any ? std::max(best, range) : range;
                any = true;
            }
        out.push_back(any ? best : 0.0f);
    }
    return out;
}

// ------------------------------------------------------------------ extract ties

// Every vertex of extract lies on its edge: off-axis coordinates exactly the sample's, the
// axis coordinate between the edge's two ends.
void require_vertices_on_edges(const voxmesh::Mesh& mesh, const std::vector<std::uint64_t>& edges, const Dims& n,
                               const std::array<double, 3>& spacing, const std::array<double, 3>& origin) {
    REQUIRE(mesh.vertex_count() == edges.size());
    std::size_t bad = 0;
    for (std::size_t v = 0; v < edges.size(); ++v) {
        const unsigned axis = static_cast<unsigned>(edges[v] % 3);
        const std::size_t s = static_cast<std::size_t>(edges[v] / 3);
        const std::size_t at[3] = {s % n[0], (s / n[0]) % n[1], s / (n[0] * n[1])};
        bool ok = true;
        for (unsigned d = 0; d < 3; ++d) {
            const float p = mesh.positions[3 * v + d];
            const float lo = static_cast<float>(origin[d] + static_cast<double>(at[d]) * spacing[d]);
            if (d != axis) {
                ok = ok && p == lo;
            } else {
                const float hi = static_cast<float>(origin[d] + static_cast<double>(at[d] + 1) * spacing[d]);
                ok = ok && p >= lo && p <= hi;
            }
        }
        if (!ok && bad++ < 5) {
            UNSCOPED_INFO("vertex " << v << " at (" << mesh.positions[3 * v] << ", " << mesh.positions[3 * v + 1] << ", "
                                    << mesh.positions[3 * v + 2] << ") is not on edge " << edges[v] << " (sample " << at[0]
                                    << "," << at[1] << "," << at[2] << ", axis " << axis << ")");
        }
    }
    CHECK(bad == 0);
}

template <class T>
void check_vertex_edges(const std::vector<T>& data, const Dims& dims, double iso) {
    INFO(voxmesh::scalar_name(vmtest::scalar_type_of<T>()) << " " << dims[0] << "x" << dims[1] << "x" << dims[2]
                                                           << " iso " << iso);
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    const std::vector<std::uint64_t> expected = oracle_vertex_edges(data, dims, iso);
    for (unsigned threads : {1u, 2u, 3u, 8u}) {
        INFO("threads " << threads);
        const std::vector<std::uint64_t> got = voxmesh::vertex_edges(view, iso, threads);
        REQUIRE(got == expected);
    }
    CHECK(voxmesh::vertex_edges(view, iso) == expected);  // threads 0: all cores
    CHECK(std::is_sorted(expected.begin(), expected.end()));

    for (unsigned threads : {1u, 3u}) {
        INFO("extract, threads " << threads);
        voxmesh::Options o = vmtest::cpu_options(iso, threads);
        require_vertices_on_edges(voxmesh::extract(view, o), expected, dims, view.spacing, view.origin);
        o.inside_below = true;
        o.normals = false;
        require_vertices_on_edges(voxmesh::extract(view, o), expected, dims, view.spacing, view.origin);
    }
}

template <class T>
void check_cell_ranges(const std::vector<T>& data, const Dims& dims, const std::vector<std::uint64_t>& edges,
                       double offset, const std::uint8_t* mask) {
    INFO(voxmesh::scalar_name(vmtest::scalar_type_of<T>()) << " " << dims[0] << "x" << dims[1] << "x" << dims[2] << ", "
                                                           << edges.size() << " edges, offset " << offset
                                                           << (mask ? ", masked" : ""));
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    const std::vector<float> expected = oracle_cell_ranges(data, dims, edges, offset, mask);
    const std::vector<float> one = voxmesh::edge_cell_ranges(view, edges, offset, mask, 1);
    REQUIRE(one.size() == expected.size());
    std::size_t bad = 0;
    for (std::size_t i = 0; i < one.size(); ++i) {
        // Bit-for-bit: both sides round the same double to float.
        if (std::memcmp(&one[i], &expected[i], sizeof(float)) != 0 && bad++ < 5)
            UNSCOPED_INFO("edge " << edges[i] << " (#" << i << "): got " << one[i] << ", expected " << expected[i]);
    }
    CHECK(bad == 0);
    CHECK(voxmesh::edge_cell_ranges(view, edges, offset, mask, 2) == one);
    CHECK(voxmesh::edge_cell_ranges(view, edges, offset, mask, 0) == one);
}

std::vector<std::uint8_t> random_mask(const Dims& dims, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<std::uint8_t> mask((dims[0] - 1) * (dims[1] - 1) * (dims[2] - 1));
    // Mostly nonzero values other than 1 too, and zeros about a third of the time.
    for (std::uint8_t& m : mask) m = static_cast<std::uint8_t>(rng() % 3 == 0 ? 0 : 1 + rng() % 255);
    return mask;
}

const Dims kOddDims[] = {{7, 5, 9}, {17, 3, 11}, {2, 2, 2}, {3, 2, 5}};

}  // namespace

// ------------------------------------------------------------------ vertex_edges

TEMPLATE_TEST_CASE("vertex_edges matches a brute-force walk over every edge, on any thread count", "[vertex_edges][core]",
                   std::uint8_t, std::int16_t, std::uint16_t, float, double) {
    std::uint32_t seed = 1234;
    for (const Dims& dims : kOddDims) {
        const std::vector<TestType> data = random_volume<TestType>(dims, seed++);
        for (double iso : iso_values(data)) check_vertex_edges(data, dims, iso);
    }
    const Dims cube{24, 24, 24};
    const std::vector<TestType> ball = sphere_volume<TestType>(cube);
    for (double iso : {100.0, 100.5, 97.25, 120.0}) check_vertex_edges(ball, cube, iso);
}

TEST_CASE("vertex_edges on f32: iso not a float decides as the smallest float at or above it", "[vertex_edges][core]") {
    // 0.1 is not a float: samples of 0.1f (just above 0.1) are inside at iso 0.1.
    const Dims dims{9, 7, 5};
    const std::vector<double> r = vmtest::random_doubles(dims, 77, 0, 2);
    std::vector<float> data(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) data[i] = static_cast<float>(r[i]) * 0.1f;
    for (double iso : {0.1, static_cast<double>(0.1f), std::nextafter(static_cast<double>(0.1f), 1.0), 0.2, 0.15})
        check_vertex_edges(data, dims, iso);
}

TEST_CASE("vertex_edges: each vertex of extract lies on its edge with spacing and origin", "[vertex_edges][core]") {
    const Dims dims{13, 11, 9};
    const std::array<double, 3> spacing{0.7, 1.3, 2.1}, origin{-3.25, 10.5, 0.1};
    const std::vector<float> data = vmtest::sample_field<float>(dims, vmtest::sphere({6.2, 5.1, 4.3}, 3.7));
    const std::vector<std::int16_t> ints = random_volume<std::int16_t>(dims, 99);
    const voxmesh::VolumeView view = vmtest::view_of(data, dims, spacing, origin);
    const voxmesh::VolumeView iview = vmtest::view_of(ints, dims, spacing, origin);
    for (double iso : {0.0, 0.3, -1.0}) {
        INFO("iso " << iso);
        const std::vector<std::uint64_t> edges = voxmesh::vertex_edges(view, iso, 2);
        CHECK(edges == oracle_vertex_edges(data, dims, iso));
        // Spacing and origin do not change the edges.
        CHECK(edges == voxmesh::vertex_edges(vmtest::view_of(data, dims), iso, 1));
        REQUIRE_FALSE(edges.empty());
        require_vertices_on_edges(voxmesh::extract(view, vmtest::cpu_options(iso, 2)), edges, dims, spacing, origin);
        voxmesh::Options below = vmtest::cpu_options(iso, 1);
        below.inside_below = true;
        const voxmesh::Mesh flipped = voxmesh::extract(view, below);
        CHECK(flipped.vertex_count() == edges.size());
        require_vertices_on_edges(flipped, edges, dims, spacing, origin);

        const std::vector<std::uint64_t> iedges = voxmesh::vertex_edges(iview, iso, 3);
        CHECK(iedges == oracle_vertex_edges(ints, dims, iso));
        require_vertices_on_edges(voxmesh::extract(iview, vmtest::cpu_options(iso, 3)), iedges, dims, spacing, origin);
    }
}

TEST_CASE("vertex_edges: no crossings give empty vectors", "[vertex_edges][core]") {
    const Dims dims{7, 5, 9};
    SECTION("all samples equal") {
        const std::vector<float> flat(dims[0] * dims[1] * dims[2], 3.5f);
        for (double iso : {3.5, 3.0, 4.0}) {
            for (unsigned threads : {1u, 2u, 8u}) {
                INFO("iso " << iso << ", threads " << threads);
                const std::vector<std::uint64_t> edges = voxmesh::vertex_edges(vmtest::view_of(flat, dims), iso, threads);
                CHECK(edges.empty());
                CHECK(voxmesh::edge_cell_ranges(vmtest::view_of(flat, dims), edges, 0, nullptr, threads).empty());
            }
        }
        const std::vector<std::uint8_t> bytes(dims[0] * dims[1] * dims[2], 7);
        CHECK(voxmesh::vertex_edges(vmtest::view_of(bytes, dims), 7, 2).empty());
        CHECK(voxmesh::vertex_edges(vmtest::view_of(bytes, dims), 6.5, 2).empty());
        CHECK(voxmesh::vertex_edges(vmtest::view_of(bytes, dims), 7.5, 2).empty());
    }
    SECTION("iso beyond the sample type's range") {
        const std::vector<std::uint8_t> bytes = random_volume<std::uint8_t>(dims, 5);
        const voxmesh::VolumeView view = vmtest::view_of(bytes, dims);
        for (unsigned threads : {1u, 3u}) {
            std::vector<std::uint64_t> edges;
            REQUIRE_NOTHROW(edges = voxmesh::vertex_edges(view, 300, threads));
            CHECK(edges.empty());
            REQUIRE_NOTHROW(edges = voxmesh::vertex_edges(view, -5, threads));
            CHECK(edges.empty());
            REQUIRE_NOTHROW(edges = voxmesh::vertex_edges(view, 255.5, threads));
            CHECK(edges.empty());
        }
        // 255 is a value u8 holds: samples of 255 next to 254 cross it.
        std::vector<std::uint8_t> mixed(bytes.size(), 255);
        mixed[10] = 254;
        CHECK(voxmesh::vertex_edges(vmtest::view_of(mixed, dims), 255, 1) == oracle_vertex_edges(mixed, dims, 255));
        CHECK_FALSE(voxmesh::vertex_edges(vmtest::view_of(mixed, dims), 255, 1).empty());
        const std::vector<std::int16_t> shorts = random_volume<std::int16_t>(dims, 6);
        CHECK(voxmesh::vertex_edges(vmtest::view_of(shorts, dims), 40000, 2).empty());
        CHECK(voxmesh::vertex_edges(vmtest::view_of(shorts, dims), -40000, 2).empty());
    }
}

TEST_CASE("vertex_edges: NaN or infinite samples and dimensions below 2 are Errors", "[vertex_edges][core]") {
    const Dims dims{6, 5, 7};
    std::vector<float> data = random_volume<float>(dims, 11);
    SECTION("NaN names NaN and the first z-plane holding one") {
        data[sample_index(dims, 2, 1, 5)] = std::numeric_limits<float>::quiet_NaN();
        data[sample_index(dims, 4, 3, 3)] = std::numeric_limits<float>::quiet_NaN();
        for (unsigned threads : {1u, 2u, 8u}) {
            INFO("threads " << threads);
            REQUIRE_THROWS_AS(voxmesh::vertex_edges(vmtest::view_of(data, dims), 0.0, threads), voxmesh::Error);
            CHECK_THROWS_WITH(voxmesh::vertex_edges(vmtest::view_of(data, dims), 0.0, threads),
                              Catch::Contains("NaN") && Catch::Contains("z-plane 3"));
        }
    }
    SECTION("NaN far from any surface") {
        std::vector<float> flat(dims[0] * dims[1] * dims[2], 1.0f);
        flat[sample_index(dims, 0, 0, 6)] = std::numeric_limits<float>::quiet_NaN();
        CHECK_THROWS_AS(voxmesh::vertex_edges(vmtest::view_of(flat, dims), 0.5, 1), voxmesh::Error);
        CHECK_THROWS_WITH(voxmesh::vertex_edges(vmtest::view_of(flat, dims), 0.5, 1), Catch::Contains("NaN"));
        std::vector<double> dflat(flat.begin(), flat.end());
        CHECK_THROWS_AS(voxmesh::vertex_edges(vmtest::view_of(dflat, dims), 0.5, 2), voxmesh::Error);
    }
    SECTION("infinity") {
        data[sample_index(dims, 5, 4, 0)] = std::numeric_limits<float>::infinity();
        CHECK_THROWS_AS(voxmesh::vertex_edges(vmtest::view_of(data, dims), 0.0, 1), voxmesh::Error);
    }
    SECTION("a dimension below 2") {
        const std::vector<float> small(64, 1.0f);
        const Dims bad[] = {{1, 4, 4}, {4, 1, 4}, {4, 4, 1}, {0, 4, 4}, {1, 1, 1}};
        for (const Dims& d : bad) {
            INFO(d[0] << "x" << d[1] << "x" << d[2]);
            CHECK_THROWS_AS(voxmesh::vertex_edges(vmtest::view_of(small, d), 0.5, 1), voxmesh::Error);
        }
        CHECK_NOTHROW(voxmesh::vertex_edges(vmtest::view_of(small, {2, 2, 2}), 0.5, 1));
    }
    SECTION("no data") {
        voxmesh::VolumeView v = vmtest::view_of(data, dims);
        v.data = nullptr;
        CHECK_THROWS_AS(voxmesh::vertex_edges(v, 0.0, 1), voxmesh::Error);
        CHECK_THROWS_AS(voxmesh::edge_cell_ranges(v, std::vector<std::uint64_t>{0}, 0, nullptr, 1), voxmesh::Error);
    }
    SECTION("samples not aligned to their size") {
        std::vector<double> aligned(64, 0.0);
        auto* bytes = reinterpret_cast<unsigned char*>(aligned.data());
        const voxmesh::VolumeView odd{bytes + 1, voxmesh::ScalarType::F32, {3, 3, 3}};
        CHECK_THROWS_AS(voxmesh::vertex_edges(odd, 0.5, 1), voxmesh::Error);
    }
}

TEST_CASE("vertex_edges and edge_cell_ranges on a larger volume: many slabs, several pieces of edges", "[vertex_edges][core]") {
    // 190822 edges (3 per sample, less those leaving the volume): edge_cell_ranges splits them among threads.
    const Dims dims{41, 37, 43};
    const std::vector<float> data = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    const std::vector<std::uint64_t> expected = oracle_vertex_edges(data, dims, 0.25);
    REQUIRE(expected.size() > 1000);
    for (unsigned threads : {1u, 2u, 3u, 8u}) {
        INFO("threads " << threads);
        CHECK(voxmesh::vertex_edges(view, 0.25, threads) == expected);
    }
    CHECK(voxmesh::extract(view, vmtest::cpu_options(0.25, 2)).vertex_count() == expected.size());
    const std::vector<std::uint64_t> every = all_edges(dims);
    REQUIRE(every.size() > 2 * (std::size_t{1} << 16));  // three pieces of 64 Ki
    const std::vector<std::uint8_t> mask = random_mask(dims, 41);
    check_cell_ranges(data, dims, every, 0.0, nullptr);
    check_cell_ranges(data, dims, every, 0.25, mask.data());
    const std::vector<float> one = voxmesh::edge_cell_ranges(view, every, 0.25, mask.data(), 1);
    CHECK(voxmesh::edge_cell_ranges(view, every, 0.25, mask.data(), 3) == one);
    CHECK(voxmesh::edge_cell_ranges(view, every, 0.25, mask.data(), 8) == one);
}

// ------------------------------------------------------------------ edge_cell_ranges

TEMPLATE_TEST_CASE("edge_cell_ranges matches the cells around each edge, with offsets and masks", "[vertex_edges][core]",
                   std::uint8_t, std::int16_t, float, double) {
    std::uint32_t seed = 4321;
    for (const Dims& dims : kOddDims) {
        const std::vector<TestType> data = random_volume<TestType>(dims, seed++);
        const std::vector<std::uint8_t> mask = random_mask(dims, seed++);
        const double iso = static_cast<double>(data[data.size() / 2]);
        const std::vector<std::uint64_t> crossings = voxmesh::vertex_edges(vmtest::view_of(data, dims), iso, 1);
        const std::vector<std::uint64_t> every = all_edges(dims);
        for (const std::vector<std::uint64_t>* edges : {&crossings, &every}) {
            // Large offsets round (v - offset) in double: the range then differs from max - min.
            for (double offset : {0.0, iso, 1234.567, -0.3, 1e9 + 0.3, -1e17}) {
                check_cell_ranges(data, dims, *edges, offset, nullptr);
                check_cell_ranges(data, dims, *edges, offset, mask.data());
            }
        }
        // A mask of all zeros: every range is 0.
        const std::vector<std::uint8_t> none(mask.size(), 0);
        const std::vector<float> zeros = voxmesh::edge_cell_ranges(vmtest::view_of(data, dims), every, 0, none.data(), 1);
        CHECK(zeros == std::vector<float>(every.size(), 0.0f));
    }
    const Dims cube{24, 24, 24};
    const std::vector<TestType> ball = sphere_volume<TestType>(cube);
    const std::vector<std::uint8_t> mask = random_mask(cube, 8);
    const std::vector<std::uint64_t> crossings = voxmesh::vertex_edges(vmtest::view_of(ball, cube), 100.0, 2);
    REQUIRE_FALSE(crossings.empty());
    for (double offset : {0.0, 100.0}) {
        check_cell_ranges(ball, cube, crossings, offset, nullptr);
        check_cell_ranges(ball, cube, crossings, offset, mask.data());
    }
}

TEST_CASE("edge_cell_ranges takes edges in any order, repeated, and none", "[vertex_edges][core]") {
    const Dims dims{7, 5, 9};
    const std::vector<float> data = random_volume<float>(dims, 21);
    const std::vector<std::uint8_t> mask = random_mask(dims, 22);
    std::vector<std::uint64_t> edges = all_edges(dims);
    std::mt19937 rng(23);
    for (std::size_t i = edges.size(); i > 1; --i) std::swap(edges[i - 1], edges[rng() % i]);
    edges.push_back(edges.front());
    edges.push_back(edges[edges.size() / 2]);
    check_cell_ranges(data, dims, edges, 0.25, mask.data());
    check_cell_ranges(data, dims, edges, 0.0, nullptr);
    CHECK(voxmesh::edge_cell_ranges(vmtest::view_of(data, dims), std::span<const std::uint64_t>{}, 0, nullptr, 2).empty());
}

TEST_CASE("edge_cell_ranges: hand-checked values on a 3x3x2 volume", "[vertex_edges][core]") {
    // x-edge at (0,1,0): cells (0,0,0) and (0,1,0) along y; z has one cell layer (z - 1 < 0).
    const Dims dims{3, 3, 2};
    std::vector<float> data(18, 0.0f);
    data[sample_index(dims, 2, 0, 1)] = 5.0f;  // only in cell (1,0,0)
    data[sample_index(dims, 0, 2, 0)] = -2.0f;  // only in cell (0,1,0)
    data[sample_index(dims, 1, 1, 1)] = 1.0f;  // in every cell
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    const std::uint64_t x_edge = 3 * sample_index(dims, 0, 1, 0) + 0;
    const std::uint64_t z_edge_center = 3 * sample_index(dims, 1, 1, 0) + 2;  // shared by all four cells
    const std::uint64_t z_edge_corner = 3 * sample_index(dims, 0, 0, 0) + 2;  // cell (0,0,0) only
    const std::vector<std::uint64_t> edges{x_edge, z_edge_center, z_edge_corner};
    // Cells: (0,0,0) holds {0, 1}: range 1. (1,0,0) holds {0, 5, 1}: 5. (0,1,0) holds {-2, 0, 1}: 3.
    // (1,1,0) holds {0, 1}: 1.
    CHECK(voxmesh::edge_cell_ranges(view, edges, 0, nullptr, 1) == std::vector<float>{3.0f, 5.0f, 1.0f});
    const std::uint8_t mask[4] = {1, 0, 0, 1};  // cells (0,0,0) and (1,1,0)
    CHECK(voxmesh::edge_cell_ranges(view, edges, 0, mask, 1) == std::vector<float>{1.0f, 1.0f, 1.0f});
    const std::uint8_t only_b[4] = {0, 9, 0, 0};  // cell (1,0,0)
    CHECK(voxmesh::edge_cell_ranges(view, edges, 0, only_b, 2) == std::vector<float>{0.0f, 5.0f, 0.0f});
}

TEST_CASE("edge_cell_ranges: an edge the volume does not hold is an Error", "[vertex_edges][core]") {
    const Dims dims{7, 5, 9};
    const std::vector<std::int16_t> data = random_volume<std::int16_t>(dims, 31);
    const voxmesh::VolumeView view = vmtest::view_of(data, dims);
    const std::uint64_t count = dims[0] * dims[1] * dims[2];
    const std::uint64_t nx = dims[0], ny = dims[1], nz = dims[2];
    struct Bad {
        const char* what;
        std::uint64_t edge;
    };
    const Bad bad[] = {
        {"past the last sample", 3 * count},
        {"past the last sample, axis z", 3 * count + 2},
        {"x-edge from x = nx-1", 3 * (nx - 1) + 0},
        {"x-edge from x = nx-1 in a later row", 3 * ((nx - 1) + nx * 2) + 0},
        {"y-edge from y = ny-1", 3 * (nx * (ny - 1)) + 1},
        {"z-edge from z = nz-1", 3 * (nx * ny * (nz - 1)) + 2},
        {"z-edge from the last sample", 3 * (count - 1) + 2},
        {"the largest uint64", std::numeric_limits<std::uint64_t>::max()},
    };
    for (const Bad& b : bad) {
        INFO(b.what << ": edge " << b.edge);
        for (unsigned threads : {1u, 2u}) {
            // Alone, and after edges that are fine.
            REQUIRE_THROWS_AS(voxmesh::edge_cell_ranges(view, std::vector<std::uint64_t>{b.edge}, 0, nullptr, threads), voxmesh::Error);
            CHECK_THROWS_WITH(voxmesh::edge_cell_ranges(view, std::vector<std::uint64_t>{0, 1, 2, b.edge}, 0, nullptr, threads),
                              Catch::Contains("edge", Catch::CaseSensitive::No));
        }
    }
    // The edges next to them are fine.
    const std::vector<std::uint64_t> good{3 * (nx - 2) + 0, 3 * (nx - 1) + 1, 3 * (nx - 1) + 2,
                                          3 * (nx * (ny - 1)) + 0, 3 * (nx * ny * (nz - 1)) + 0,
                                          3 * (nx * ny * (nz - 2)) + 2, 3 * (count - 2) + 0};
    CHECK_NOTHROW(voxmesh::edge_cell_ranges(view, good, 0, nullptr, 1));
    check_cell_ranges(data, dims, good, 0.0, nullptr);
}

TEST_CASE("edge_cell_ranges_into writes the ranges edge_cell_ranges returns, into memory of the right size",
          "[vertex_edges][core]") {
    const Dims n{9, 8, 7};
    const auto data = vmtest::sample_field<float>(n, vmtest::sphere({4.1, 3.6, 3.2}, 2.7));
    const auto view = vmtest::view_of(data, n);
    const std::vector<std::uint64_t> edges = voxmesh::vertex_edges(view, 0.0, 1);
    REQUIRE(!edges.empty());
    const std::vector<float> want = voxmesh::edge_cell_ranges(view, edges, 0.5, nullptr, 2);
    std::vector<float> got(edges.size(), -1.0f);
    voxmesh::edge_cell_ranges_into(view, edges, got, 0.5, nullptr, 2);
    REQUIRE(std::memcmp(got.data(), want.data(), want.size() * sizeof(float)) == 0);
    std::vector<float> short_by_one(edges.size() - 1);
    REQUIRE_THROWS_WITH(voxmesh::edge_cell_ranges_into(view, edges, short_by_one),
                        Catch::Contains("room for " + std::to_string(edges.size() - 1) + " ranges"));
}

TEST_CASE("edge_cell_ranges gives infinity for double ranges beyond float's", "[vertex_edges][core]") {
    const Dims n{2, 2, 2};
    std::vector<double> data(8, 1e300);
    data[0] = -1e300;
    const std::vector<std::uint64_t> edges{0, 1, 2};
    for (const float r : voxmesh::edge_cell_ranges(vmtest::view_of(data, n), edges)) CHECK(r == std::numeric_limits<float>::infinity());
}
