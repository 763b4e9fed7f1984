// Bad input and boundary conditions of extract().
#include <catch2/catch.hpp>

#include "support/mesh_checks.hpp"
#include "support/reference_mc.hpp"

#include <voxmesh/voxmesh.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

using vmtest::Dims;
using Catch::Matchers::Contains;

namespace {

voxmesh::Options cpu_options(double iso, unsigned threads = 1) {
    voxmesh::Options o;
    o.iso = iso;
    o.backend = voxmesh::Backend::Cpu;
    o.threads = threads;
    return o;
}

void require_empty(const voxmesh::Mesh& mesh) {
    CHECK(mesh.positions.empty());
    CHECK(mesh.normals.empty());
    CHECK(mesh.indices.empty());
    CHECK(mesh.vertex_count() == 0);
    CHECK(mesh.triangle_count() == 0);
}

}  // namespace

TEST_CASE("a dimension below 2 is an Error", "[core]") {
    const std::vector<float> data(64, 1.0f);
    const Dims bad[] = {{1, 4, 4}, {4, 1, 4}, {4, 4, 1}, {0, 4, 4}, {4, 0, 4}, {4, 4, 0}, {1, 1, 1}};
    for (const Dims& dims : bad) {
        INFO(dims[0] << "x" << dims[1] << "x" << dims[2]);
        CHECK_THROWS_AS(voxmesh::extract(vmtest::view_of(data, dims), cpu_options(0.5)), voxmesh::Error);
    }
    // Exactly 2 is fine.
    CHECK_NOTHROW(voxmesh::extract(vmtest::view_of(data, {2, 2, 2}), cpu_options(0.5)));
}

TEST_CASE("invalid views are Errors", "[core]") {
    const std::vector<float> data(27, 1.0f);
    voxmesh::VolumeView v = vmtest::view_of(data, {3, 3, 3});
    SECTION("no data") {
        v.data = nullptr;
        CHECK_THROWS_AS(voxmesh::extract(v, cpu_options(0.5)), voxmesh::Error);
    }
    SECTION("spacing not positive") {
        v.spacing = {1, 0, 1};
        CHECK_THROWS_AS(voxmesh::extract(v, cpu_options(0.5)), voxmesh::Error);
        v.spacing = {1, 1, -2};
        CHECK_THROWS_AS(voxmesh::extract(v, cpu_options(0.5)), voxmesh::Error);
    }
    SECTION("samples past the float range (vertex positions would be inf)") {
        v.spacing = {1, 1e300, 1};
        CHECK_THROWS_WITH(voxmesh::extract(v, cpu_options(0.5)), Catch::Contains("along y") && Catch::Contains("float"));
        v.spacing = {1, 1, 1};
        v.origin = {0, 0, -3.4e38};
        CHECK_NOTHROW(voxmesh::extract(v, cpu_options(0.5)));  // the last sample at -3.4e38 + 2
        v.spacing = {1, 1, 1e38};
        v.origin = {0, 0, 3.3e38};
        CHECK_THROWS_WITH(voxmesh::extract(v, cpu_options(0.5)), Catch::Contains("along z"));
        v.origin = {1e39, 0, 0};
        v.spacing = {1, 1, 1};
        CHECK_THROWS_WITH(voxmesh::extract(v, cpu_options(0.5)), Catch::Contains("along x"));
    }
    SECTION("rows too long for 32-bit row counts") {
        v.dims = {(std::size_t{1} << 29) + 1, 2, 2};  // refused before a sample is read
        CHECK_THROWS_WITH(voxmesh::extract(v, cpu_options(0.5)), Catch::Contains("536870913 samples"));
    }
    SECTION("samples at an address not aligned to their size") {
        // Read as their type, they would be misaligned loads (undefined behaviour).
        std::vector<double> aligned(64, 0.0);
        auto* bytes = reinterpret_cast<unsigned char*>(aligned.data());
        for (const voxmesh::ScalarType type : {voxmesh::ScalarType::I16, voxmesh::ScalarType::U32,
                                               voxmesh::ScalarType::F32, voxmesh::ScalarType::F64}) {
            INFO(voxmesh::scalar_name(type));
            const voxmesh::VolumeView odd{bytes + 1, type, {3, 3, 3}};
            CHECK_THROWS_WITH(voxmesh::extract(odd, cpu_options(0.5)),
                              Contains("not a multiple of " + std::to_string(voxmesh::scalar_size(type))));
            voxmesh::Options any = cpu_options(0.5);
            any.backend = voxmesh::Backend::Auto;
            CHECK_THROWS_WITH(voxmesh::extract(odd, any), Contains("aligned memory"));
        }
        // Bytes have no alignment to keep.
        CHECK_NOTHROW(voxmesh::extract(voxmesh::VolumeView{bytes + 1, voxmesh::ScalarType::U8, {3, 3, 3}}, cpu_options(0.5)));
    }
    SECTION("Error is a std::runtime_error") {
        v.data = nullptr;
        CHECK_THROWS_AS(voxmesh::extract(v, cpu_options(0.5)), std::runtime_error);
    }
}

TEST_CASE("a spacing too fine for float coordinates at the grid's place is warned about", "[core]") {
    std::vector<float> data(4 * 4 * 4);
    for (std::size_t i = 0; i < data.size(); ++i) data[i] = (i % 4) < 2 ? 1.f : 0.f;  // a plane across x
    voxmesh::VolumeView v = vmtest::view_of(data, {4, 4, 4});
    auto warnings = [&] {
        voxmesh::Stats stats;
        voxmesh::extract(v, cpu_options(0.5), stats);
        return stats.warnings;
    };
    CHECK(warnings().empty());
    v.spacing = {1e-30, 1e-30, 1e-30};  // tiny, but near 0 floats resolve it
    CHECK(warnings().empty());
    // Far from 0, 1e-3 is a few float steps apart (0.0625 near 1e6): vertices snap.
    v.spacing = {1, 1, 1e-3};
    v.origin = {0, 0, 1e6};
    const auto snapped = warnings();
    REQUIRE(snapped.size() == 1);
    CHECK_THAT(snapped[0], Contains("spacing 0.001 along z") && Contains("too fine for float"));
    v.spacing = {1, 1, 1};  // 1 at 1e6: 16 float steps, fewer than 256: warned
    CHECK(warnings().size() == 1);
    v.spacing = {1, 1, 64};  // 1024 steps between samples: fine
    CHECK(warnings().empty());
}

TEST_CASE("a constant volume gives an empty mesh", "[core]") {
    const Dims dims{7, 5, 9};
    const std::vector<float> f(dims[0] * dims[1] * dims[2], 3.0f);
    const std::vector<std::uint8_t> u(dims[0] * dims[1] * dims[2], 200);
    for (unsigned threads : {1u, 3u}) {
        require_empty(voxmesh::extract(vmtest::view_of(f, dims), cpu_options(3.0, threads)));   // all inside (== iso)
        require_empty(voxmesh::extract(vmtest::view_of(f, dims), cpu_options(-1.0, threads)));  // all inside
        require_empty(voxmesh::extract(vmtest::view_of(f, dims), cpu_options(3.5, threads)));   // all outside
        require_empty(voxmesh::extract(vmtest::view_of(u, dims), cpu_options(200, threads)));
        require_empty(voxmesh::extract(vmtest::view_of(u, dims), cpu_options(1e9, threads)));   // beyond the type
        require_empty(voxmesh::extract(vmtest::view_of(u, dims), cpu_options(-1e9, threads)));
    }
    // A field with a surface, at an iso beyond the type's range, also gives nothing.
    std::vector<std::uint8_t> ramp(dims[0] * dims[1] * dims[2]);
    for (std::size_t i = 0; i < ramp.size(); ++i) ramp[i] = static_cast<std::uint8_t>(i % 256);
    require_empty(voxmesh::extract(vmtest::view_of(ramp, dims), cpu_options(255.5)));
    require_empty(voxmesh::extract(vmtest::view_of(ramp, dims), cpu_options(0.0)));
    CHECK(voxmesh::extract(vmtest::view_of(ramp, dims), cpu_options(255.0)).triangle_count() > 0);
}

TEST_CASE("samples exactly equal to iso are inside", "[core]") {
    const Dims dims{2, 2, 2};
    SECTION("f32 corner at iso") {
        std::vector<float> v(8, 0.0f);
        v[0] = 1.0f;
        const voxmesh::Mesh at = voxmesh::extract(vmtest::view_of(v, dims), cpu_options(1.0));
        REQUIRE(at.triangle_count() == 1);
        REQUIRE(at.vertex_count() == 3);
        for (float p : at.positions) CHECK(p == 0.0f);  // t = 0: every vertex on the corner
        // A hair above the sample: nothing is inside.
        require_empty(voxmesh::extract(vmtest::view_of(v, dims), cpu_options(std::nextafter(1.0, 2.0))));
        // A hair below: the corner is inside, vertices just off it.
        const voxmesh::Mesh below = voxmesh::extract(vmtest::view_of(v, dims), cpu_options(0.999));
        CHECK(below.triangle_count() == 1);
    }
    SECTION("f32 iso between two floats rounds the right way") {
        // iso lies strictly between 1.0f and the next float: 1.0f is outside.
        std::vector<float> v(8, 0.0f);
        v[0] = 1.0f;
        v[7] = std::nextafter(1.0f, 2.0f);
        const double iso = 1.0 + std::numeric_limits<float>::epsilon() / 4;
        const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(v, dims), cpu_options(iso));
        vmtest::RefOptions ro;
        ro.iso = iso;
        const vmtest::RefMesh ref = vmtest::reference_mc(vmtest::to_doubles(v), dims, ro);
        CHECK(ref.triangle_count() == 1);
        CHECK(mesh.indices == ref.indices);
        CHECK(mesh.vertex_count() == ref.vertex_count());
    }
    SECTION("integers: iso 100 vs 100.5 vs 99.5") {
        std::vector<std::uint8_t> v(8, 10);
        v[3] = 100;
        v[5] = 101;
        CHECK(voxmesh::extract(vmtest::view_of(v, dims), cpu_options(100)).triangle_count() == 2);
        CHECK(voxmesh::extract(vmtest::view_of(v, dims), cpu_options(100.5)).triangle_count() == 1);
        CHECK(voxmesh::extract(vmtest::view_of(v, dims), cpu_options(101)).triangle_count() == 1);
        CHECK(voxmesh::extract(vmtest::view_of(v, dims), cpu_options(101.001)).triangle_count() == 0);
        std::vector<std::int32_t> w(8, -10);
        w[6] = -3;
        CHECK(voxmesh::extract(vmtest::view_of(w, dims), cpu_options(-3)).triangle_count() == 1);
        CHECK(voxmesh::extract(vmtest::view_of(w, dims), cpu_options(-2.999)).triangle_count() == 0);
    }
    SECTION("every sample at iso: all inside, no surface") {
        const std::vector<double> v(27, 0.25);
        require_empty(voxmesh::extract(vmtest::view_of(v, {3, 3, 3}), cpu_options(0.25)));
    }
}

TEST_CASE("NaN samples are an Error that says NaN", "[core]") {
    const Dims dims{9, 8, 7};
    const std::size_t n = dims[0] * dims[1] * dims[2];
    const std::size_t where[] = {0, n / 2, n - 1, dims[0] * dims[1] * (dims[2] - 1), dims[0] - 1};
    for (std::size_t at : where) {
        for (unsigned threads : {1u, 3u}) {
            INFO("NaN at " << at << ", threads " << threads);
            std::vector<float> f = vmtest::sample_field<float>(dims, vmtest::sphere({4, 4, 3}, 2.5));
            f[at] = std::numeric_limits<float>::quiet_NaN();
            CHECK_THROWS_WITH(voxmesh::extract(vmtest::view_of(f, dims), cpu_options(0.0, threads)), Contains("NaN"));
            CHECK_THROWS_AS(voxmesh::extract(vmtest::view_of(f, dims), cpu_options(0.0, threads)), voxmesh::Error);
            // Far from any surface: a constant volume with one NaN.
            std::vector<double> d(n, -1.0);
            d[at] = std::numeric_limits<double>::quiet_NaN();
            CHECK_THROWS_WITH(voxmesh::extract(vmtest::view_of(d, dims), cpu_options(0.0, threads)), Contains("NaN"));
        }
    }
}

TEST_CASE("NaN samples give the same Error, naming the first z-plane with one, on any thread count", "[core]") {
    // NaN in several planes, some in slabs after the first's: a thread that reaches a later
    // NaN first must not decide the message. (Found by fuzz_extract: 3 planes, NaN in 1 and 2.)
    const auto check = [](const Dims& dims, std::vector<std::size_t> nan_planes, int repeats) {
        std::vector<double> d(dims[0] * dims[1] * dims[2], -1.0);
        for (std::size_t i = 0; i < d.size(); i += 3) d[i] = 1.0;  // crossings in every plane
        const std::size_t plane = dims[0] * dims[1];
        for (const std::size_t z : nan_planes) d[z * plane + plane / 2] = std::numeric_limits<double>::quiet_NaN();
        const std::string first = "first seen in z-plane " + std::to_string(nan_planes.front()) + ")";
        for (unsigned threads : {1u, 2u, 3u, 5u, 8u, 16u})
            for (int repeat = 0; repeat < repeats; ++repeat) {
                INFO(dims[2] << " planes, " << threads << " threads");
                CHECK_THROWS_WITH(voxmesh::extract(vmtest::view_of(d, dims), cpu_options(0.0, threads)), Contains(first));
            }
    };
    check({4, 3, 3}, {1, 2}, 200);
    check({5, 4, 9}, {2, 3, 6, 8}, 200);
    check({64, 64, 96}, {29, 37, 50, 90}, 20);
}

TEST_CASE("iso NaN is an Error", "[core]") {
    const std::vector<float> f(27, 1.0f);
    const std::vector<std::uint8_t> u(27, 1);
    const std::vector<double> d(27, 1.0);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_AS(voxmesh::extract(vmtest::view_of(f, {3, 3, 3}), cpu_options(nan)), voxmesh::Error);
    CHECK_THROWS_AS(voxmesh::extract(vmtest::view_of(u, {3, 3, 3}), cpu_options(nan)), voxmesh::Error);
    CHECK_THROWS_AS(voxmesh::extract(vmtest::view_of(d, {3, 3, 3}), cpu_options(nan, 2)), voxmesh::Error);
}

TEST_CASE("checked_volume_bytes detects overflow", "[core]") {
    CHECK(voxmesh::checked_volume_bytes({3, 5, 7}, voxmesh::ScalarType::F64) == 3u * 5u * 7u * 8u);
    CHECK(voxmesh::checked_volume_bytes({512, 512, 512}, voxmesh::ScalarType::U16) == std::size_t(512) * 512 * 512 * 2);
    const std::size_t big = std::size_t(1) << 22;
    CHECK_THROWS_AS(voxmesh::checked_volume_bytes({big, big, big}, voxmesh::ScalarType::U8), voxmesh::Error);
    CHECK_THROWS_AS(voxmesh::checked_volume_bytes({big, big, std::size_t(1) << 20}, voxmesh::ScalarType::F64),
                    voxmesh::Error);
    const std::size_t max = std::numeric_limits<std::size_t>::max();
    CHECK_THROWS_AS(voxmesh::checked_volume_bytes({max, 2, 2}, voxmesh::ScalarType::U8), voxmesh::Error);
    CHECK_THROWS_AS(voxmesh::checked_volume_bytes({max / 2 + 1, 1, 1}, voxmesh::ScalarType::U16), voxmesh::Error);
    // extract() rejects such a view before touching its (tiny) data.
    const std::vector<float> tiny(8, 0.0f);
    voxmesh::VolumeView v = vmtest::view_of(tiny, {big, big, big});
    CHECK_THROWS_AS(voxmesh::extract(v, cpu_options(0.5)), voxmesh::Error);
    // And Volume::allocate as well.
    CHECK_THROWS_AS(voxmesh::Volume::allocate(voxmesh::ScalarType::F32, {big, big, big}), voxmesh::Error);
}

TEST_CASE("normals off: same positions and indices, no normals", "[core]") {
    const Dims dims{17, 19, 15};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::wavy(0.6));
    voxmesh::Options with = cpu_options(0.3, 2), without = with;
    without.normals = false;
    const voxmesh::Mesh a = voxmesh::extract(vmtest::view_of(values, dims), with);
    const voxmesh::Mesh b = voxmesh::extract(vmtest::view_of(values, dims), without);
    REQUIRE(a.triangle_count() > 0);
    CHECK(b.normals.empty());
    CHECK(a.indices == b.indices);
    CHECK(a.positions == b.positions);
}

TEST_CASE("an owning Volume meshes like the view of the same samples", "[core]") {
    voxmesh::Volume vol = voxmesh::Volume::allocate(voxmesh::ScalarType::I16, {11, 9, 13});
    CHECK(vol.sample_count() == 11u * 9u * 13u);
    CHECK(vol.byte_size() == 11u * 9u * 13u * 2u);
    const std::vector<std::int16_t> values = vmtest::random_field<std::int16_t>(vol.dims, 3, -20, 20);
    std::copy(values.begin(), values.end(), static_cast<std::int16_t*>(vol.data));
    vol.spacing = {0.5, 2, 1};
    vol.origin = {1, 2, 3};
    const voxmesh::Mesh a = voxmesh::extract(vol.view(), cpu_options(0.5, 2));
    const voxmesh::Mesh b = voxmesh::extract(vmtest::view_of(values, vol.dims, vol.spacing, vol.origin), cpu_options(0.5, 1));
    CHECK(a.indices == b.indices);
    CHECK(a.positions == b.positions);
    CHECK(a.normals == b.normals);
}

TEST_CASE("NaN samples are an Error at any iso, even one beyond the float range", "[core]") {
    // The same volume must not be rejected at iso 0.5 and silently meshed (empty) at 1e39.
    std::vector<float> f(27, 0.0f);
    f[5] = std::numeric_limits<float>::quiet_NaN();
    for (double iso : {0.5, 1e39, -1e39}) {
        INFO("iso " << iso);
        CHECK_THROWS_WITH(voxmesh::extract(vmtest::view_of(f, {3, 3, 3}), cpu_options(iso)), Contains("NaN"));
    }
}

TEST_CASE("infinite samples give an Error or finite positions, never NaN", "[core]") {
    for (float inf : {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}) {
        std::vector<float> f(27, 0.0f);
        f[13] = inf;  // the centre sample: it owns crossed edges toward +x, +y, +z
        INFO("centre sample " << inf);
        const double iso = inf > 0 ? 0.5 : -0.5;
        bool threw = false;
        voxmesh::Mesh mesh;
        try {
            mesh = voxmesh::extract(vmtest::view_of(f, {3, 3, 3}), cpu_options(iso));
        } catch (const voxmesh::Error&) {
            threw = true;
        }
        if (!threw) {
            REQUIRE(mesh.vertex_count() == 6);
            CHECK(vmtest::structural_problem(mesh).empty());  // no NaN/inf position or normal
        }
    }
}

TEST_CASE("double samples near the ends of the double range give finite positions on the edge", "[core]") {
    // v1 - v0 overflows to inf here: t was inf / inf = NaN, a NaN vertex and no Error.
    const double big = std::numeric_limits<double>::max();
    std::vector<double> v(8, -big);
    v[7] = big;  // corner (1, 1, 1)
    for (double iso : {0.0, 1e308, -1e308}) {
        INFO("iso " << iso);
        const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(v, {2, 2, 2}), cpu_options(iso, 1));
        REQUIRE(mesh.vertex_count() == 3);
        CHECK(vmtest::structural_problem(mesh).empty());  // no NaN/inf position or normal
        for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
            CHECK(mesh.positions[i] >= 0.0f);
            CHECK(mesh.positions[i] <= 1.0f);
        }
        // Vertex 0 is on the z-edge of sample (1, 1, 0) (the first in canonical order): z = t.
        const double t = (0.5 * iso + 0.5 * big) / big;
        CHECK(mesh.positions[2] == Approx(t).margin(1e-6));
    }
}

TEST_CASE("a vanishing gradient still gives a unit normal pointing outward along the edge", "[core]") {
    // Along x: -1, 0, -1 (constant in y and z), iso 0. The middle sample is inside and the
    // central difference there is 0, so both vertices (t = 1 and t = 0) sit on it with a
    // zero interpolated gradient.
    const Dims dims{3, 2, 2};
    std::vector<double> v(12);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = (i % 3 == 1) ? 0.0 : -1.0;
    for (bool inside_below : {false, true}) {
        INFO((inside_below ? "inside_below" : "inside above"));
        voxmesh::Options o = cpu_options(0.0);
        o.inside_below = inside_below;
        const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(v, dims), o);
        REQUIRE(vmtest::structural_problem(mesh).empty());
        REQUIRE(mesh.vertex_count() == 8);  // 4 rows (y, z) x 2 crossed x-edges
        CHECK(vmtest::max_normal_length_error(mesh) < 1e-6);
        const float sign = inside_below ? -1.f : 1.f;
        for (std::size_t k = 0; k < mesh.vertex_count(); ++k) {
            // Canonical order: per row, the edge owned by x = 0 (outward is -x) then x = 1 (+x).
            INFO("vertex " << k);
            CHECK(mesh.normals[3 * k] == sign * (k % 2 == 0 ? -1.f : 1.f));
            CHECK(mesh.positions[3 * k] == 1.0f);
        }
    }
}

TEST_CASE("an invalid scalar type is an Error", "[core]") {
    const std::vector<float> data(8, 0.0f);
    voxmesh::VolumeView v = vmtest::view_of(data, {2, 2, 2});
    v.type = static_cast<voxmesh::ScalarType>(99);
    CHECK_THROWS_AS(voxmesh::extract(v, cpu_options(0.5)), voxmesh::Error);
}

TEST_CASE("Backend::Auto gives the canonical mesh", "[core]") {
    const Dims dims{23, 19, 21};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::wavy(0.5));
    const voxmesh::Mesh cpu = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.1, 2));
    voxmesh::Options o = cpu_options(0.1, 2);
    o.backend = voxmesh::Backend::Auto;
    std::vector<std::string> log;
    o.log = [&log](const std::string& s) { log.push_back(s); };
    voxmesh::Stats stats;
    const voxmesh::Mesh a = voxmesh::extract(vmtest::view_of(values, dims), o, stats);
    CHECK(a.indices == cpu.indices);
    CHECK(a.vertex_count() == cpu.vertex_count());
    CHECK(stats.warnings == log);  // warnings are both returned and logged
}

// The spare room for a re-read 8-bit row is the stretch generate walks, not the whole row: a
// 2^24-sample row of an empty u8 volume (64 MB) made a 2.1 GB mesh, all of its pages touched.
TEST_CASE("long rows get no row-sized spare room in the mesh's arrays", "[core]") {
    const std::size_t nx = std::size_t{1} << 20;
    for (const auto type : {voxmesh::ScalarType::U8, voxmesh::ScalarType::F32}) {
        std::vector<double> storage(nx * 4 * voxmesh::scalar_size(type) / sizeof(double), 0.0);
        const voxmesh::VolumeView empty{storage.data(), type, {nx, 2, 2}};
        voxmesh::Mesh mesh = voxmesh::extract(empty, cpu_options(0.5));
        require_empty(mesh);
        CHECK(mesh.indices.capacity() == 0);
        CHECK(mesh.positions.capacity() == 0);
        CHECK(mesh.normals.capacity() == 0);
    }
    // One crossing near the row's end: room for its stretch only (a few words), and the mesh
    // is the oracle's.
    std::vector<std::uint8_t> samples(nx * 4, 0);
    for (std::size_t r = 0; r < 4; ++r) samples[r * nx + nx - 100] = 10;
    const voxmesh::VolumeView volume{samples.data(), voxmesh::ScalarType::U8, {nx, 2, 2}};
    vmtest::RefOptions ro;
    ro.iso = 5;
    const vmtest::RefMesh ref = vmtest::reference_mc(vmtest::to_doubles(samples), {nx, 2, 2}, ro);
    REQUIRE(ref.triangle_count() > 0);
    for (unsigned threads : {1u, 2u, 4u}) {
        const voxmesh::Mesh mesh = voxmesh::extract(volume, cpu_options(5, threads));
        const vmtest::Comparison c = vmtest::compare_with_reference(mesh, ref);
        INFO(c.first_problem);
        CHECK(c.same_indices);
        CHECK(c.max_position_error < 1e-5);
        CHECK(mesh.indices.capacity() <= mesh.indices.size() + 3 * 5 * 64 * 4);
        CHECK(mesh.positions.capacity() <= mesh.positions.size() + 3 * 3 * 64 * 4);
    }
}

// Dims whose bytes fit size_t but no memory: the list queries' plane scratch overflowed a
// vector's max_size() and threw std::length_error, not a voxmesh::Error.
TEST_CASE("list queries refuse dims too large for their scratch with an Error", "[core]") {
    static const double samples[8] = {};
    const voxmesh::VolumeView volume{samples, voxmesh::ScalarType::U8, {2, std::size_t{1} << 61, 2}};
    CHECK_THROWS_AS(voxmesh::vertex_edges(volume, 0.5), voxmesh::OutOfMemoryError);
    CHECK_THROWS_AS(voxmesh::triangle_cells(volume, 0.5), voxmesh::OutOfMemoryError);
    CHECK_THROWS_AS(voxmesh::vertex_edges_into(volume, 0.5, {}), voxmesh::OutOfMemoryError);
    CHECK_THROWS_AS(voxmesh::extract(volume, cpu_options(0.5)), voxmesh::Error);
}
