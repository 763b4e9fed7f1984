// The engine against the naive oracle: the case table itself, all 256 cube cases, and
// random small volumes of odd dimensions, down to the exact canonical vertex/triangle order.
#include <catch2/catch.hpp>

#include "core/bit_rows.hpp"
#include "core/case_tables.hpp"
#include "support/mesh_checks.hpp"
#include "support/reference_mc.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <vector>

using vmtest::Dims;

namespace {

voxmesh::Options cpu_options(double iso, unsigned threads, bool inside_below = false) {
    voxmesh::Options o;
    o.iso = iso;
    o.backend = voxmesh::Backend::Cpu;
    o.threads = threads;
    o.inside_below = inside_below;
    return o;
}

// All the ways the engine must agree with the oracle.
void require_matches(const voxmesh::Mesh& mesh, const vmtest::RefMesh& ref) {
    const vmtest::Comparison c = vmtest::compare_with_reference(mesh, ref);
    INFO(c.first_problem);
    CHECK(c.same_counts);
    CHECK(c.same_triangle_set);
    CHECK(c.same_indices);
    CHECK(c.max_position_error <= 1e-6);
    CHECK(c.max_normal_error <= 1e-5);
}

// A 2x2x2 volume whose inside corners are exactly the bits of `code`, with distinct values
// so that every crossed edge gets its own interpolation parameter.
std::vector<double> cube_case_values(unsigned code) {
    std::vector<double> v(8);
    for (int c = 0; c < 8; ++c) {
        const int* o = vmtest::kRefCorner[c];
        const std::size_t idx = static_cast<std::size_t>(o[0] + 2 * (o[1] + 2 * o[2]));
        v[idx] = (code >> c & 1) ? 1.0 + 0.13 * c : -(0.5 + 0.21 * c);
    }
    return v;
}

}  // namespace

TEST_CASE("case table: corner and edge numbering agree with the oracle's", "[core]") {
    for (int c = 0; c < 8; ++c)
        for (int d = 0; d < 3; ++d) CHECK(int(voxmesh::detail::kCornerOffset[c][d]) == vmtest::kRefCorner[c][d]);
    for (int e = 0; e < 12; ++e) {
        const int* a = vmtest::kRefCorner[vmtest::kRefEdge[e][0]];
        const int* b = vmtest::kRefCorner[vmtest::kRefEdge[e][1]];
        const auto& edge = voxmesh::detail::kCellEdge[e];
        INFO("edge " << e);
        CHECK(int(edge.dx) == std::min(a[0], b[0]));
        CHECK(int(edge.dy) == std::min(a[1], b[1]));
        CHECK(int(edge.dz) == std::min(a[2], b[2]));
        CHECK(a[edge.axis] != b[edge.axis]);
    }
}

TEST_CASE("case table: each case uses exactly its crossed edges, wound outward", "[core]") {
    for (unsigned code = 0; code < 256; ++code) {
        INFO("case " << code);
        const auto& entry = voxmesh::detail::kCaseTable[code];
        REQUIRE(entry.count <= 5);
        std::set<int> used, crossed;
        for (int e = 0; e < 12; ++e)
            if ((code >> vmtest::kRefEdge[e][0] & 1) != (code >> vmtest::kRefEdge[e][1] & 1)) crossed.insert(e);
        for (unsigned i = 0; i < 15; ++i) {
            if (i >= 3u * entry.count) {
                CHECK(int(entry.edges[i]) == -1);
                continue;
            }
            REQUIRE(entry.edges[i] >= 0);
            REQUIRE(entry.edges[i] < 12);
            used.insert(entry.edges[i]);
        }
        CHECK(used == crossed);
        // With vertices at edge midpoints, a triangle's normal must lean from the inside
        // corners of its edges toward their outside corners.
        for (unsigned t = 0; t < entry.count; ++t) {
            double p[3][3], dir[3][3];
            for (int k = 0; k < 3; ++k) {
                const int e = entry.edges[3 * t + k];
                const int ca = vmtest::kRefEdge[e][0], cb = vmtest::kRefEdge[e][1];
                const bool a_inside = code >> ca & 1;
                for (int d = 0; d < 3; ++d) {
                    p[k][d] = 0.5 * (vmtest::kRefCorner[ca][d] + vmtest::kRefCorner[cb][d]);
                    dir[k][d] = (a_inside ? 1 : -1) * (vmtest::kRefCorner[cb][d] - vmtest::kRefCorner[ca][d]);
                }
            }
            const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
            const double w[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
            const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
            double lean = 0;
            for (int k = 0; k < 3; ++k) lean += n[0] * dir[k][0] + n[1] * dir[k][1] + n[2] * dir[k][2];
            INFO("triangle " << t);
            CHECK(lean > 0);
        }
    }
}

// Classify counts the triangles of a word with many non-uniform cells as V - 2F - 4R
// (CellWord::triangle_sum), not by a table lookup per cell: check that against the table,
// case by case and on random words.
TEST_CASE("triangle counts summed a word at a time agree with the case table", "[core]") {
    using voxmesh::detail::CellWord;
    using voxmesh::detail::Word;
    constexpr std::size_t kWords = 2, kNx = 64 * kWords;
    SECTION("each non-uniform case alone, at either end of a word and inside it") {
        for (unsigned code = 1; code < 255; ++code)
            for (unsigned r : {0u, 1u, 30u, 62u, 63u}) {
                Word rows[4][kWords] = {};  // (y, z), (y + 1, z), (y, z + 1), (y + 1, z + 1)
                for (unsigned k = 0; k < 8; ++k) {
                    if (!(code >> k & 1)) continue;
                    const auto* at = voxmesh::detail::kCornerOffset[k];
                    const unsigned x = r + at[0];
                    rows[at[1] + 2 * at[2]][x / 64] |= Word{1} << (x % 64);
                }
                const CellWord cell(rows[0], rows[1], rows[2], rows[3], 0, kWords);
                INFO("case " << code << " at bit " << r);
                REQUIRE((cell.nonuniform(0, kNx) >> r & 1) == 1);
                CHECK(cell.cell_case(r) == code);
                CHECK(cell.triangle_sum(Word{1} << r) == voxmesh::detail::kCaseTable[code].count);
            }
    }
    SECTION("random words: the sum over a word's non-uniform cells") {
        std::mt19937_64 rng(6);
        for (int trial = 0; trial < 20000; ++trial) {
            Word rows[4][kWords];
            // Sparse, dense and half-filled rows: every mix of cases, runs of one case, rings.
            const int density = trial % 4;
            for (auto& row : rows)
                for (Word& w : row) {
                    w = rng();
                    if (density == 1) w &= rng() & rng();
                    if (density == 2) w |= rng() | rng();
                    if (density == 3) w = trial % 8 < 4 ? ~Word{0} ^ (Word{1} << (rng() % 64)) : Word{1} << (rng() % 64);
                }
            const CellWord cell(rows[0], rows[1], rows[2], rows[3], 0, kWords);
            const Word cells = cell.nonuniform(0, kNx);
            unsigned expected = 0;
            for (unsigned r = 0; r < 64; ++r)
                if (cells >> r & 1) expected += voxmesh::detail::kCaseTable[cell.cell_case(r)].count;
            INFO("trial " << trial);
            REQUIRE(cell.triangle_sum(cells) == expected);
        }
    }
}

TEST_CASE("all 256 cube cases match the oracle", "[core]") {
    const Dims dims{2, 2, 2};
    for (bool inside_below : {false, true}) {
        for (unsigned code = 0; code < 256; ++code) {
            INFO("case " << code << (inside_below ? " inside_below" : ""));
            const std::vector<double> values = cube_case_values(code);
            REQUIRE(vmtest::reference_case(values, dims, 0, 0, 0, 0.0) == code);
            vmtest::RefOptions ro;
            ro.inside_below = inside_below;
            const vmtest::RefMesh ref = vmtest::reference_mc(values, dims, ro);
            CHECK(ref.triangle_count() == voxmesh::detail::kCaseTable[code].count);
            for (unsigned threads : {1u, 2u}) {
                INFO("threads " << threads);
                require_matches(voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0, threads, inside_below)), ref);
            }
            // The same case as f32 and as u8 (inside 200 + c, outside 10 + c, iso 100.5).
            const std::vector<float> as_float(values.begin(), values.end());
            require_matches(voxmesh::extract(vmtest::view_of(as_float, dims), cpu_options(0.0, 1, inside_below)),
                            vmtest::reference_mc(vmtest::to_doubles(as_float), dims, ro));
            std::vector<std::uint8_t> as_u8(8);
            for (std::size_t i = 0; i < 8; ++i) as_u8[i] = static_cast<std::uint8_t>(values[i] > 0 ? 200 + i : 10 + 3 * i);
            vmtest::RefOptions ro8 = ro;
            ro8.iso = 100.5;
            require_matches(voxmesh::extract(vmtest::view_of(as_u8, dims), cpu_options(100.5, 1, inside_below)),
                            vmtest::reference_mc(vmtest::to_doubles(as_u8), dims, ro8));
        }
    }
}

TEST_CASE("random small volumes of odd dimensions match the oracle", "[core]") {
    const std::vector<Dims> shapes = {{3, 3, 3}, {5, 3, 7}, {7, 9, 5}, {11, 7, 9}, {13, 15, 11}, {3, 17, 5},
                                     {2, 9, 7}, {9, 2, 5}, {7, 5, 2}, {2, 2, 9}};
    // Samples are integers in [0, 9]: iso 4 and 9 equal samples exactly, 0 makes every
    // sample inside, 9.5 none.
    const double isos[] = {4.5, 4.0, 9.0, 0.0, 2.25, 9.5, -1.0};
    for (const Dims& dims : shapes) {
        for (std::uint32_t seed = 1; seed <= 4; ++seed) {
            const std::vector<double> values = vmtest::random_doubles(dims, seed, 0, 9);
            const std::vector<float> f32(values.begin(), values.end());
            const std::vector<std::int16_t> i16 = vmtest::random_field<std::int16_t>(dims, seed, 0, 9);
            for (double iso : isos) {
                INFO("dims " << dims[0] << "x" << dims[1] << "x" << dims[2] << " seed " << seed << " iso " << iso);
                vmtest::RefOptions ro;
                ro.iso = iso;
                const vmtest::RefMesh ref = vmtest::reference_mc(values, dims, ro);
                if (iso <= 0 || iso > 9) CHECK(ref.triangle_count() == 0);
                for (unsigned threads : {1u, 3u}) {
                    INFO("threads " << threads);
                    require_matches(voxmesh::extract(vmtest::view_of(values, dims), cpu_options(iso, threads)), ref);
                    require_matches(voxmesh::extract(vmtest::view_of(f32, dims), cpu_options(iso, threads)), ref);
                    require_matches(voxmesh::extract(vmtest::view_of(i16, dims), cpu_options(iso, threads)), ref);
                }
                ro.inside_below = true;
                require_matches(voxmesh::extract(vmtest::view_of(values, dims), cpu_options(iso, 2, true)),
                                vmtest::reference_mc(values, dims, ro));
            }
        }
    }
}

TEST_CASE("random non-integer fields match the oracle", "[core]") {
    const Dims dims{15, 13, 11};
    const vmtest::FieldFn wavy = vmtest::wavy(0.9);
    const std::vector<double> base = vmtest::sample_field<double>(dims, wavy);
    for (std::uint32_t seed : {7u, 8u, 9u}) {
        // Add seeded noise so that cells take many different cases.
        const std::vector<double> noise = vmtest::random_doubles(dims, seed, -50, 50);
        std::vector<double> values(base.size());
        for (std::size_t i = 0; i < base.size(); ++i) values[i] = base[i] + noise[i] / 40.0;
        for (double iso : {0.1, -0.7, 1.3}) {
            INFO("seed " << seed << " iso " << iso);
            vmtest::RefOptions ro;
            ro.iso = iso;
            const vmtest::RefMesh ref = vmtest::reference_mc(values, dims, ro);
            CHECK(ref.triangle_count() > 50);
            for (unsigned threads : {1u, 2u, 5u}) require_matches(voxmesh::extract(vmtest::view_of(values, dims), cpu_options(iso, threads)), ref);
        }
    }
}

TEST_CASE("random volumes inside an outside border give closed, outward-oriented meshes", "[core]") {
    // The table's ambiguous faces must be decided the same way from both cells that share
    // them; otherwise random fields show holes or flipped patches.
    const Dims dims{19, 17, 21};
    for (std::uint32_t seed = 11; seed <= 16; ++seed) {
        std::vector<float> values = vmtest::random_field<float>(dims, seed, 0, 9);
        for (std::size_t z = 0; z < dims[2]; ++z)
            for (std::size_t y = 0; y < dims[1]; ++y)
                for (std::size_t x = 0; x < dims[0]; ++x)
                    if (x == 0 || y == 0 || z == 0 || x + 1 == dims[0] || y + 1 == dims[1] || z + 1 == dims[2])
                        values[x + dims[0] * (y + dims[1] * z)] = 0;
        for (double iso : {4.5, 2.5, 7.5}) {
            INFO("seed " << seed << " iso " << iso);
            const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(iso, 2));
            REQUIRE(vmtest::structural_problem(mesh).empty());
            REQUIRE(mesh.triangle_count() > 0);
            const vmtest::Topology topo = vmtest::topology(mesh);
            CHECK(topo.boundary_edges == 0);
            CHECK(topo.nonmanifold_edges == 0);
            CHECK(topo.consistently_oriented());
            CHECK(topo.degenerate_triangles == 0);
            CHECK(vmtest::signed_volume(mesh) > 0);
            // The library's own topology summary agrees with this one.
            const voxmesh::MeshTopology lib = voxmesh::analyze_topology(mesh);
            CHECK(lib.closed());
            CHECK(lib.euler == topo.euler);
        }
    }
}

TEST_CASE("the test harness itself notices broken meshes", "[core]") {
    const Dims dims{15, 15, 15};
    const std::vector<double> values = vmtest::sample_field<double>(dims, vmtest::sphere({7.2, 6.9, 7.1}, 5));
    vmtest::RefOptions ro;
    const vmtest::RefMesh ref = vmtest::reference_mc(values, dims, ro);
    const voxmesh::Mesh good = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0, 1));
    REQUIRE(vmtest::compare_with_reference(good, ref).first_problem.empty());
    REQUIRE(vmtest::topology(good).closed());
    REQUIRE(vmtest::topology(good).euler == 2);

    SECTION("a missing triangle opens the surface") {
        voxmesh::Mesh m = good;
        m.indices.resize(m.indices.size() - 3);
        CHECK(vmtest::topology(m).boundary_edges == 3);
        CHECK_FALSE(vmtest::compare_with_reference(m, ref).same_triangle_set);
    }
    SECTION("one flipped triangle breaks the orientation") {
        voxmesh::Mesh m = good;
        std::swap(m.indices[4], m.indices[5]);
        CHECK_FALSE(vmtest::topology(m).consistently_oriented());
        const vmtest::Comparison c = vmtest::compare_with_reference(m, ref);
        CHECK_FALSE(c.same_triangle_set);
        CHECK_FALSE(c.same_indices);
    }
    SECTION("reordered triangles: same set, different buffer") {
        voxmesh::Mesh m = good;
        for (int k = 0; k < 3; ++k) std::swap(m.indices[k], m.indices[3 + k]);
        const vmtest::Comparison c = vmtest::compare_with_reference(m, ref);
        CHECK(c.same_triangle_set);
        CHECK_FALSE(c.same_indices);
    }
    SECTION("a rotated triangle is the same oriented triangle") {
        voxmesh::Mesh m = good;
        std::rotate(m.indices.begin(), m.indices.begin() + 1, m.indices.begin() + 3);
        CHECK(vmtest::compare_with_reference(m, ref).same_triangle_set);
    }
    SECTION("a moved vertex and a wrong normal are measured") {
        voxmesh::Mesh m = good;
        m.positions[7] += 0.01f;
        m.normals[4] = -m.normals[4];
        const vmtest::Comparison c = vmtest::compare_with_reference(m, ref);
        CHECK(c.max_position_error > 1e-4);
        CHECK(c.max_normal_error > 1e-3);
    }
    SECTION("an out-of-range index is a structural problem") {
        voxmesh::Mesh m = good;
        m.indices[0] = static_cast<std::uint32_t>(m.vertex_count());
        CHECK_FALSE(vmtest::structural_problem(m).empty());
    }
    SECTION("two copies of a sphere have Euler 4") {
        CHECK(vmtest::signed_volume(good) > 0);
        voxmesh::Mesh twice = good;
        const auto n = static_cast<std::uint32_t>(good.vertex_count());
        twice.positions.insert(twice.positions.end(), good.positions.begin(), good.positions.end());
        for (std::uint32_t i : good.indices) twice.indices.push_back(i + n);
        CHECK(vmtest::topology(twice).euler == 4);
    }
}

TEST_CASE("extreme integer values match the oracle", "[core]") {
    const Dims dims{7, 5, 9};
    const std::vector<double> pattern = vmtest::random_doubles(dims, 31, 0, 1);  // 0 or 1 per sample
    auto check = [&](auto tag, double lo, double hi, double iso) {
        using T = decltype(tag);
        std::vector<T> typed(pattern.size());
        std::vector<double> as_double(pattern.size());
        for (std::size_t i = 0; i < pattern.size(); ++i) {
            typed[i] = static_cast<T>(pattern[i] > 0 ? hi : lo);
            as_double[i] = static_cast<double>(typed[i]);
        }
        vmtest::RefOptions ro;
        ro.iso = iso;
        const vmtest::RefMesh ref = vmtest::reference_mc(as_double, dims, ro);
        REQUIRE(ref.triangle_count() > 0);
        INFO("type " << voxmesh::scalar_name(vmtest::scalar_type_of<T>()) << " iso " << iso);
        require_matches(voxmesh::extract(vmtest::view_of(typed, dims), cpu_options(iso, 2)), ref);
    };
    check(std::uint8_t{}, 0, 255, 254.5);
    check(std::int8_t{}, -128, 127, -127.5);
    check(std::uint16_t{}, 0, 65535, 0.5);
    check(std::int16_t{}, -32768, 32767, 0.0);
    check(std::uint32_t{}, 0, 4294967295.0, 2147483647.5);
    check(std::uint32_t{}, 0, 4294967295.0, 4294967295.0);  // iso equal to the maximum
    check(std::int32_t{}, -2147483648.0, 2147483647.0, -2147483647.5);
    check(std::int32_t{}, -2147483648.0, 2147483647.0, 2147483647.0);
    check(float{}, -3.0e38, 3.0e38, 1e30);
    check(double{}, -1e300, 1e300, -5e299);
}

TEST_CASE("rows around machine-word lengths match the oracle", "[core]") {
    // Rows of 31..33, 63..65 and 127..129 samples: any packing of inside bits into words
    // must handle the last partial word and crossings at word boundaries.
    for (std::size_t nx : {31u, 32u, 33u, 63u, 64u, 65u, 127u, 128u, 129u}) {
        const Dims dims{nx, 4, 3};
        for (std::uint32_t seed : {41u, 42u}) {
            INFO("nx " << nx << " seed " << seed);
            const std::vector<double> dense = vmtest::random_doubles(dims, seed, 0, 9);
            // Sparse: one crossing per row, placed at and around word boundaries.
            std::vector<double> sparse(dense.size(), 0.0);
            for (std::size_t row = 0; row < dims[1] * dims[2]; ++row) {
                const std::size_t at = (row * 31 + seed) % nx;
                sparse[row * nx + at] = 9.0;
            }
            for (const std::vector<double>* values : {&dense, static_cast<const std::vector<double>*>(&sparse)}) {
                vmtest::RefOptions ro;
                ro.iso = 4.5;
                const vmtest::RefMesh ref = vmtest::reference_mc(*values, dims, ro);
                for (unsigned threads : {1u, 2u})
                    require_matches(voxmesh::extract(vmtest::view_of(*values, dims), cpu_options(4.5, threads)), ref);
                const std::vector<std::uint8_t> u8 = [&] {
                    std::vector<std::uint8_t> out(values->size());
                    for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<std::uint8_t>((*values)[i]);
                    return out;
                }();
                require_matches(voxmesh::extract(vmtest::view_of(u8, dims), cpu_options(4.5, 3)), ref);
            }
        }
    }
}

TEST_CASE("8-bit rows with long uniform runs between crossings match the oracle", "[core]") {
    // Packed inside bits, the spans between a row's first and last crossing, and the words
    // skipped as uniform: runs of inside and of outside samples over several words,
    // crossings on word boundaries, a row's partial last word inside, and rows of more
    // than 64 words (where a row's word set shares its last bit) must all come out exact.
    for (std::size_t nx : {130u, 257u, 4096u, 4097u}) {
        const Dims dims{nx, 5, 4};
        for (std::uint32_t seed : {3u, 4u}) {
            INFO("nx " << nx << " seed " << seed);
            const std::vector<double> noise = vmtest::random_doubles(dims, seed, 0, 9);
            std::vector<std::uint8_t> u8(noise.size());
            for (std::size_t row = 0; row < dims[1] * dims[2]; ++row) {
                // Inside from `from` to the row's end or to `to`, the rest outside; a few
                // noisy samples around word boundaries.
                const std::size_t from = (row * 67 + 13 * seed) % nx, to = row % 3 == 0 ? nx : (from + nx / 3) % nx;
                for (std::size_t x = 0; x < nx; ++x) {
                    const bool inside = from <= to ? x >= from && x < to : x >= from || x < to;
                    std::uint8_t v = inside ? 200 : 10;
                    if (x % 64 == 63 || x % 64 == 0) v = static_cast<std::uint8_t>(noise[row * nx + x] * 25);
                    u8[row * nx + x] = v;
                }
            }
            const std::vector<double> values(u8.begin(), u8.end());
            for (double iso : {100.5, 112.5}) {
                vmtest::RefOptions ro;
                ro.iso = iso;
                const vmtest::RefMesh ref = vmtest::reference_mc(values, dims, ro);
                CHECK(ref.triangle_count() > 0);
                for (unsigned threads : {1u, 2u})
                    require_matches(voxmesh::extract(vmtest::view_of(u8, dims), cpu_options(iso, threads)), ref);
            }
        }
    }
}

TEST_CASE("rows around the width where 16-bit vertex ids give way to 32-bit match the oracle", "[core]") {
    // The generator numbers a row's vertices from the row's first in 16 bits while a row has
    // at most 65536 edges (nx <= 21845) and in 32 bits beyond.
    for (std::size_t nx : {21845u, 21846u}) {
        const Dims dims{nx, 2, 2};
        INFO("nx " << nx);
        // A 3-d checkerboard: every edge crosses, so row (0, 0) has 3 * nx - 1 vertices.
        std::vector<double> values(nx * 4);
        for (std::size_t i = 0; i < values.size(); ++i) values[i] = ((i % nx + i / nx % 2 + i / nx / 2) % 2) ? 9.0 : 0.0;
        vmtest::RefOptions ro;
        ro.iso = 4.5;
        const vmtest::RefMesh ref = vmtest::reference_mc(values, dims, ro);
        for (unsigned threads : {1u, 2u})
            require_matches(voxmesh::extract(vmtest::view_of(values, dims), cpu_options(4.5, threads)), ref);
    }
}
