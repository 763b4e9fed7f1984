// The canonical mesh does not depend on the thread count or the scalar type.
#include <catch2/catch.hpp>

#include "support/mesh_checks.hpp"
#include "support/reference_mc.hpp"

#include "core/cpu_engine.hpp"

#include <voxmesh/voxmesh.hpp>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

using vmtest::cpu_options;
using vmtest::Dims;

namespace {

bool bitwise_equal(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

void require_identical(const voxmesh::Mesh& a, const voxmesh::Mesh& b) {
    REQUIRE(a.vertex_count() == b.vertex_count());
    REQUIRE(a.triangle_count() == b.triangle_count());
    CHECK(a.indices == b.indices);
    CHECK(bitwise_equal(a.positions, b.positions));
    CHECK(bitwise_equal(a.normals, b.normals));
}

template <class T>
voxmesh::Mesh extract_as(const std::vector<double>& field, const Dims& dims, double iso) {
    std::vector<T> typed(field.size());
    for (std::size_t i = 0; i < field.size(); ++i) typed[i] = vmtest::to_scalar<T>(field[i]);
    for (std::size_t i = 0; i < field.size(); ++i) REQUIRE(static_cast<double>(typed[i]) == field[i]);
    return voxmesh::extract(vmtest::view_of(typed, dims), cpu_options(iso, 3));
}

// The volume meshed as separate z-ranges [cuts[i], cuts[i+1]) into one mesh, each at its
// first vertex and triangle, as Hybrid assembles the pieces its CPU worker takes.
template <class T>
voxmesh::Mesh extract_by_ranges(const std::vector<T>& values, const Dims& dims, double iso,
                                const std::vector<std::size_t>& cuts) {
    namespace d = voxmesh::detail;
    const voxmesh::VolumeView view = vmtest::view_of(values, dims);
    const voxmesh::Options options = cpu_options(iso, 2);
    std::vector<d::CpuChunkPlan> plans;
    std::uint64_t vertices = 0, triangles = 0;
    for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
        plans.push_back(d::cpu_classify(view, options, d::ZRange{cuts[i], cuts[i + 1]}, 2));
        vertices += plans.back().vertices;
        triangles += plans.back().triangles;
    }
    voxmesh::Mesh mesh;
    d::allocate_output(mesh, vertices, triangles, true, 1, dims[0]);
    std::uint64_t first_vertex = 0, first_triangle = 0;
    for (const d::CpuChunkPlan& plan : plans) {
        d::cpu_generate(plan, view, options, 2,
                        d::MeshOut{mesh.positions.data() + 3 * first_vertex, mesh.normals.data() + 3 * first_vertex,
                                   mesh.indices.data() + 3 * first_triangle, static_cast<std::uint32_t>(first_vertex)});
        first_vertex += plan.vertices;
        first_triangle += plan.triangles;
    }
    d::trim_output(mesh, vertices, triangles);
    return mesh;
}

}  // namespace

TEST_CASE("z-ranges meshed apart make the whole volume's mesh, the last plane alone included", "[core]") {
    // The last sample plane alone owns vertices (its x- and y-edges) but no cells: a range of
    // it alone once wrote nothing, leaving those vertices at 0 under an identical index buffer.
    const Dims dims{19, 7, 9};
    const std::vector<float> smooth = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
    const std::vector<std::uint8_t> bytes = vmtest::random_field<std::uint8_t>(dims, 11, 0, 200);
    const voxmesh::Mesh whole_f32 = voxmesh::extract(vmtest::view_of(smooth, dims), cpu_options(0.15, 1));
    const voxmesh::Mesh whole_u8 = voxmesh::extract(vmtest::view_of(bytes, dims), cpu_options(100, 1));
    const std::vector<std::vector<std::size_t>> splits = {
        {0, 8, 9}, {0, 1, 9}, {0, 4, 5, 9}, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}, {0, 3, 8, 9}};
    for (const auto& cuts : splits) {
        INFO("cuts at " << cuts[1] << ", " << cuts[2] << ", ... (" << cuts.size() - 1 << " ranges)");
        require_identical(whole_f32, extract_by_ranges(smooth, dims, 0.15, cuts));  // kept bits
        require_identical(whole_u8, extract_by_ranges(bytes, dims, 100, cuts));     // bits packed again
    }
}

TEST_CASE("identical meshes for threads 1, 2, 3, 4, 7, 16 on odd dims", "[core]") {
    const Dims dims{37, 23, 51};
    SECTION("smooth float field") {
        const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
        const voxmesh::Mesh one = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.15, 1));
        REQUIRE(one.triangle_count() > 1000);
        for (unsigned threads : {2u, 3u, 4u, 7u, 16u, 0u}) {
            INFO("threads " << threads);
            require_identical(one, voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.15, threads)));
        }
        vmtest::RefOptions ro;
        ro.iso = 0.15;
        const vmtest::Comparison cmp = vmtest::compare_with_reference(one, vmtest::reference_mc(vmtest::to_doubles(values), dims, ro));
        INFO(cmp.first_problem);
        CHECK(cmp.same_indices);
    }
    SECTION("random u16 field, surface everywhere") {
        const std::vector<std::uint16_t> values = vmtest::random_field<std::uint16_t>(dims, 5, 0, 1000);
        const voxmesh::Mesh one = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(500, 1));
        REQUIRE(one.triangle_count() > 10000);
        for (unsigned threads : {2u, 3u, 4u, 7u, 16u}) {
            INFO("threads " << threads);
            require_identical(one, voxmesh::extract(vmtest::view_of(values, dims), cpu_options(500, threads)));
        }
    }
    SECTION("more threads than planes") {
        const Dims thin{9, 7, 3};
        const std::vector<double> values = vmtest::random_doubles(thin, 21, -5, 5);
        const voxmesh::Mesh one = voxmesh::extract(vmtest::view_of(values, thin), cpu_options(0.5, 1));
        REQUIRE(one.triangle_count() > 0);
        for (unsigned threads : {2u, 3u, 16u, 64u}) {
            INFO("threads " << threads);
            require_identical(one, voxmesh::extract(vmtest::view_of(values, thin), cpu_options(0.5, threads)));
        }
        const Dims flat{6, 5, 2};
        const std::vector<double> two = vmtest::random_doubles(flat, 22, -5, 5);
        const voxmesh::Mesh ref = voxmesh::extract(vmtest::view_of(two, flat), cpu_options(0.5, 1));
        for (unsigned threads : {2u, 5u}) require_identical(ref, voxmesh::extract(vmtest::view_of(two, flat), cpu_options(0.5, threads)));
    }
}

TEST_CASE("identical meshes for every scalar type holding the same integer field", "[core]") {
    const Dims dims{29, 31, 27};
    const vmtest::FieldFn wavy = vmtest::wavy(0.35);
    SECTION("values in [0, 120], non-integer and integer iso") {
        // 60 + 20 * wavy, rounded: fits every type, u8 and i8 included.
        const std::vector<double> field = vmtest::sample_field<double>(
            dims, [&](double x, double y, double z) { return std::nearbyint(60 + 20 * wavy(x, y, z)); });
        for (double iso : {60.5, 60.0, 47.25}) {
            INFO("iso " << iso);
            const voxmesh::Mesh base = extract_as<double>(field, dims, iso);
            REQUIRE(base.triangle_count() > 500);
            vmtest::RefOptions ro;
            ro.iso = iso;
            const vmtest::Comparison cmp = vmtest::compare_with_reference(base, vmtest::reference_mc(field, dims, ro));
            INFO(cmp.first_problem);
            CHECK(cmp.same_indices);
            CHECK(cmp.max_position_error <= 1e-6);
            {
                INFO("u8");
                require_identical(base, extract_as<std::uint8_t>(field, dims, iso));
            }
            {
                INFO("i8");
                require_identical(base, extract_as<std::int8_t>(field, dims, iso));
            }
            {
                INFO("u16");
                require_identical(base, extract_as<std::uint16_t>(field, dims, iso));
            }
            {
                INFO("i16");
                require_identical(base, extract_as<std::int16_t>(field, dims, iso));
            }
            {
                INFO("u32");
                require_identical(base, extract_as<std::uint32_t>(field, dims, iso));
            }
            {
                INFO("i32");
                require_identical(base, extract_as<std::int32_t>(field, dims, iso));
            }
            {
                INFO("f32");
                require_identical(base, extract_as<float>(field, dims, iso));
            }
        }
    }
    SECTION("negative values in the signed types") {
        const std::vector<double> field = vmtest::sample_field<double>(
            dims, [&](double x, double y, double z) { return std::nearbyint(40 * wavy(x, y, z)); });
        for (double iso : {-0.5, -7.0, 3.75}) {
            INFO("iso " << iso);
            const voxmesh::Mesh base = extract_as<double>(field, dims, iso);
            REQUIRE(base.triangle_count() > 500);
            require_identical(base, extract_as<std::int8_t>(field, dims, iso));
            require_identical(base, extract_as<std::int16_t>(field, dims, iso));
            require_identical(base, extract_as<std::int32_t>(field, dims, iso));
            require_identical(base, extract_as<float>(field, dims, iso));
        }
    }
}

TEST_CASE("extract_into a mesh too small for the result gives extract()'s mesh", "[core]") {
    const Dims dims{40, 36, 38};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
    const voxmesh::VolumeView view = vmtest::view_of(values, dims);
    for (bool normals : {true, false}) {
        INFO("normals " << normals);
        // Stale contents in storage smaller than the result: new storage, none of them kept.
        voxmesh::Mesh mesh;
        mesh.positions.assign(999, -7.f);
        mesh.normals.assign(999, 3.f);
        mesh.indices.assign(999, 0xdeadbeefu);
        voxmesh::Options o = cpu_options(0.15, 2);
        o.normals = normals;
        voxmesh::Stats stats;
        voxmesh::extract_into(view, o, mesh, stats);
        REQUIRE(mesh.indices.size() > 999);
        require_identical(voxmesh::extract(view, o), mesh);
    }
}

// Hybrid compares its modes by their time less what growing the mesh's arrays took
// (hybrid_schedule.hpp): cpu_extract reports that time only where the storage was replaced.
TEST_CASE("cpu_extract reports the time spent replacing the mesh's storage, and only then", "[core]") {
    namespace d = voxmesh::detail;
    const Dims dims{40, 36, 38};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
    const voxmesh::VolumeView view = vmtest::view_of(values, dims);
    const voxmesh::Options o = cpu_options(0.15, 2);
    voxmesh::Stats stats;
    double grown = -1;
    voxmesh::Mesh mesh = d::cpu_extract(view, o, stats, {}, &grown);
    CHECK(grown > 0);
    CHECK(grown <= stats.times.total);
    grown = -1;
    mesh = d::cpu_extract(view, o, stats, std::move(mesh), &grown);  // the same surface: room enough
    CHECK(grown == 0);
}

TEST_CASE("extract_into gives extract()'s mesh in a reused mesh's storage", "[core]") {
    const Dims dims{33, 29, 31};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
    const voxmesh::VolumeView view = vmtest::view_of(values, dims);
    // Storage dirtier and larger than any result: stale values must all be overwritten.
    voxmesh::Mesh mesh;
    mesh.positions.assign(200000, -7.f);
    mesh.normals.assign(200000, 3.f);
    mesh.indices.assign(300000, 0xdeadbeefu);
    const float* storage = mesh.positions.data();
    voxmesh::Stats stats;
    for (double iso : {0.15, -0.2, 0.15}) {
        for (bool normals : {true, false, true}) {
            for (unsigned threads : {1u, 2u}) {
                INFO("iso " << iso << " normals " << normals << " threads " << threads);
                voxmesh::Options o = cpu_options(iso, threads);
                o.normals = normals;
                voxmesh::extract_into(view, o, mesh, stats);
                REQUIRE(mesh.triangle_count() > 1000);
                require_identical(voxmesh::extract(view, o), mesh);
                CHECK(mesh.positions.data() == storage);  // reused, not reallocated
                CHECK(stats.backend == voxmesh::Backend::Cpu);
            }
        }
    }
    // A volume the engine refuses leaves the mesh empty, not stale.
    std::vector<float> bad = values;
    bad[dims[0] * 3 + 5] = std::nanf("");
    CHECK_THROWS_AS(voxmesh::extract_into(vmtest::view_of(bad, dims), cpu_options(0.15, 2), mesh, stats),
                    voxmesh::Error);
    CHECK(mesh.positions.empty());
    CHECK(mesh.normals.empty());
    CHECK(mesh.indices.empty());
}

// Found by a review: a Python thread writing to an 8-bit volume during extract (the call
// releases the GIL) corrupted the heap. Generate reads 8-bit rows again, and wrote their
// crossings where classify's counts put them, past the arrays when there were more. Now a
// row that differs from its counts is an Error, and writes at most one row past them, into
// the room allocate_output leaves (ASan sees a write beyond it).
TEST_CASE("a volume changed between classify and generate is an Error, not a write past the mesh", "[core]") {
    namespace d = voxmesh::detail;
    const Dims dims{24, 20, 18};
    std::vector<std::uint8_t> values(dims[0] * dims[1] * dims[2]);
    const auto sphere = [&] {
        for (std::size_t z = 0; z < dims[2]; ++z)
            for (std::size_t y = 0; y < dims[1]; ++y)
                for (std::size_t x = 0; x < dims[0]; ++x) {
                    const double dx = double(x) - 11.5, dy = double(y) - 9.5, dz = double(z) - 8.5;
                    values[x + dims[0] * (y + dims[1] * z)] = dx * dx + dy * dy + dz * dz < 49 ? 200 : 10;
                }
    };
    const voxmesh::VolumeView view = vmtest::view_of(values, dims);
    for (const unsigned threads : {1u, 2u}) {
        for (const bool more : {true, false}) {
            sphere();
            const voxmesh::Options options = cpu_options(100, threads);
            const d::CpuChunkPlan plan = d::cpu_classify(view, options, d::ZRange{0, dims[2]}, threads);
            REQUIRE(plan.triangles > 0);
            // More crossings (a checkerboard: every edge crosses) or fewer (all outside).
            for (std::size_t i = 0; i < values.size(); ++i)
                values[i] = more ? ((i + i / dims[0] + i / (dims[0] * dims[1])) % 2 ? 200 : 10) : 10;
            voxmesh::Mesh mesh;
            d::allocate_output(mesh, plan.vertices, plan.triangles, true, threads, dims[0]);
            CHECK_THROWS_WITH(
                d::cpu_generate(plan, view, options, threads,
                                d::MeshOut{mesh.positions.data(), mesh.normals.data(), mesh.indices.data(), 0}),
                Catch::Contains("changed while it was being meshed"));
        }
    }
    // Unchanged, the same call meshes as extract() does.
    sphere();
    CHECK(voxmesh::extract(view, cpu_options(100, 2)).triangle_count() > 0);
}
