// Geometry and topology of meshes of known shapes: sphere, torus, two spheres, SDFs with
// inside_below, surfaces cut by the border, anisotropic spacing and origin.
#include <catch2/catch.hpp>

#include "support/mesh_checks.hpp"
#include "support/reference_mc.hpp"

#include <voxmesh/voxmesh.hpp>

#include <cmath>
#include <cstring>
#include <vector>

using vmtest::Dims;

namespace {

constexpr double kPi = 3.14159265358979323846;

voxmesh::Options cpu_options(double iso, unsigned threads = 0, bool inside_below = false) {
    voxmesh::Options o;
    o.iso = iso;
    o.backend = voxmesh::Backend::Cpu;
    o.threads = threads;
    o.inside_below = inside_below;
    return o;
}

// Smallest dot product between a vertex normal and the direction from `center` to the vertex
// (positions and center in world units).
double min_radial_alignment(const voxmesh::Mesh& mesh, const std::array<double, 3>& center) {
    double worst = 1;
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
        double r[3], len = 0;
        for (int d = 0; d < 3; ++d) {
            r[d] = mesh.positions[3 * v + d] - center[d];
            len += r[d] * r[d];
        }
        len = std::sqrt(len);
        double dot = 0;
        for (int d = 0; d < 3; ++d) dot += r[d] / len * mesh.normals[3 * v + d];
        worst = std::min(worst, dot);
    }
    return worst;
}

void require_closed_surface(const voxmesh::Mesh& mesh, long long euler) {
    REQUIRE(vmtest::structural_problem(mesh).empty());
    REQUIRE(mesh.triangle_count() > 0);
    const vmtest::Topology topo = vmtest::topology(mesh);
    CHECK(topo.boundary_edges == 0);
    CHECK(topo.nonmanifold_edges == 0);
    CHECK(topo.consistently_oriented());
    CHECK(topo.euler == euler);
    CHECK(topo.vertices_used == mesh.vertex_count());  // no unreferenced vertex
    CHECK(vmtest::signed_volume(mesh) > 0);
}

}  // namespace

TEST_CASE("sphere at 128^3: closed, Euler 2, area, volume and outward normals", "[core]") {
    const Dims dims{128, 128, 128};
    const std::array<double, 3> c{63.7, 64.1, 63.4};
    const double r = 52;
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::sphere(c, r));
    voxmesh::Stats stats;
    const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0), stats);
    CHECK(stats.backend == voxmesh::Backend::Cpu);
    CHECK(stats.threads >= 1);

    require_closed_surface(mesh, 2);
    const double area = vmtest::surface_area(mesh), sphere_area = 4 * kPi * r * r;
    const double volume = vmtest::signed_volume(mesh), sphere_volume = 4.0 / 3.0 * kPi * r * r * r;
    INFO("area " << area << " vs " << sphere_area << ", volume " << volume << " vs " << sphere_volume);
    CHECK(std::fabs(area - sphere_area) <= 0.01 * sphere_area);
    CHECK(std::fabs(volume - sphere_volume) <= 0.01 * sphere_volume);
    CHECK(vmtest::max_normal_length_error(mesh) <= 1e-5);
    CHECK(min_radial_alignment(mesh, c) > 0.99);
    // Every vertex lies on the sphere to within a fraction of a voxel.
    double worst = 0;
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
        double len = 0;
        for (int d = 0; d < 3; ++d) len += (mesh.positions[3 * v + d] - c[d]) * (mesh.positions[3 * v + d] - c[d]);
        worst = std::max(worst, std::fabs(std::sqrt(len) - r));
    }
    CHECK(worst < 0.05);

    const voxmesh::MeshTopology lib = voxmesh::analyze_topology(mesh);
    CHECK(lib.closed());
    CHECK(lib.euler == 2);

    // And the oracle agrees on every triangle, in order.
    vmtest::RefOptions ro;
    const vmtest::Comparison cmp = vmtest::compare_with_reference(mesh, vmtest::reference_mc(vmtest::to_doubles(values), dims, ro));
    INFO(cmp.first_problem);
    CHECK(cmp.same_indices);
    CHECK(cmp.max_position_error <= 1e-6);
    CHECK(cmp.max_normal_error <= 1e-5);
}

TEST_CASE("torus: closed, Euler 0", "[core]") {
    const Dims dims{61, 57, 31};
    const std::array<double, 3> c{30.2, 28.3, 15.1};
    const double R = 18, r = 7;
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::torus(c, R, r));
    const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0, 3));
    require_closed_surface(mesh, 0);
    const double volume = vmtest::signed_volume(mesh), torus_volume = 2 * kPi * kPi * R * r * r;
    INFO("volume " << volume << " vs " << torus_volume);
    CHECK(std::fabs(volume - torus_volume) <= 0.02 * torus_volume);
    CHECK(vmtest::max_normal_length_error(mesh) <= 1e-5);
}

TEST_CASE("two disjoint spheres: closed, Euler 4", "[core]") {
    const Dims dims{64, 40, 36};
    const std::vector<double> values = vmtest::sample_field<double>(
        dims, vmtest::two_spheres({16.3, 19.6, 17.2}, 12, {46.1, 20.2, 18.4}, 10.5));
    for (unsigned threads : {1u, 4u}) {
        const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0, threads));
        require_closed_surface(mesh, 4);
    }
}

TEST_CASE("inside_below flips winding and normals and keeps the triangle set", "[core]") {
    const Dims dims{41, 37, 43};
    const std::array<double, 3> c{20.3, 17.8, 21.1};
    const double r = 13.5;
    // A signed distance field: low (negative) inside.
    const vmtest::FieldFn sdf = [f = vmtest::sphere(c, r)](double x, double y, double z) { return -f(x, y, z); };

    SECTION("float SDF") {
        const std::vector<float> values = vmtest::sample_field<float>(dims, sdf);
        const voxmesh::Mesh below = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0, 2, true));
        const voxmesh::Mesh above = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0, 2, false));
        // Low-inside, flipped: a proper outward sphere.
        require_closed_surface(below, 2);
        CHECK(min_radial_alignment(below, c) > 0.99);
        // Not flipped: the same surface, wound inward.
        CHECK(vmtest::signed_volume(above) < 0);
        CHECK(min_radial_alignment(above, c) < -0.99);

        REQUIRE(below.vertex_count() == above.vertex_count());
        REQUIRE(below.triangle_count() == above.triangle_count());
        CHECK(std::memcmp(below.positions.data(), above.positions.data(), below.positions.size() * sizeof(float)) == 0);
        bool normals_negated = true;
        for (std::size_t i = 0; i < below.normals.size(); ++i) normals_negated &= below.normals[i] == -above.normals[i];
        CHECK(normals_negated);
        std::vector<std::uint64_t> identity(below.vertex_count());
        for (std::size_t i = 0; i < identity.size(); ++i) identity[i] = i;
        CHECK(vmtest::triangle_set(below.indices, identity, false) == vmtest::triangle_set(above.indices, identity, false));
        // Triangle by triangle, in the same order, with the opposite winding.
        bool reversed = true;
        for (std::size_t t = 0; t < below.triangle_count(); ++t) {
            const std::uint32_t* a = &below.indices[3 * t];
            const std::uint32_t* b = &above.indices[3 * t];
            reversed &= vmtest::oriented_key(a[0], a[1], a[2]) == vmtest::oriented_key(b[2], b[1], b[0]);
        }
        CHECK(reversed);
    }
    SECTION("integer SDF with samples exactly at iso") {
        // Quantised to quarter voxels: many samples equal iso and stay classified inside
        // (value >= iso) either way.
        const std::vector<std::int16_t> values = vmtest::sample_field<std::int16_t>(dims, sdf, 4.0);
        std::size_t at_iso = 0;
        for (auto v : values) at_iso += v == 0;
        REQUIRE(at_iso > 50);
        for (bool inside_below : {false, true}) {
            vmtest::RefOptions ro;
            ro.inside_below = inside_below;
            const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0, 3, inside_below));
            const vmtest::Comparison cmp =
                vmtest::compare_with_reference(mesh, vmtest::reference_mc(vmtest::to_doubles(values), dims, ro));
            INFO(cmp.first_problem);
            CHECK(cmp.same_triangle_set);
            CHECK(cmp.same_indices);
            CHECK(cmp.max_position_error <= 1e-6);
            CHECK(cmp.max_normal_error <= 1e-5);
            const vmtest::Topology topo = vmtest::topology(mesh);
            CHECK(topo.nonmanifold_edges == 0);
            CHECK(topo.consistently_oriented());
            CHECK((vmtest::signed_volume(mesh) > 0) == inside_below);
        }
    }
}

TEST_CASE("a surface cut by the border gives an open mesh", "[core]") {
    const Dims dims{25, 21, 23};
    struct Case {
        const char* name;
        std::array<double, 3> center;
        double radius;
    };
    const Case cases[] = {{"sphere at a corner", {0.3, 0.2, 0.4}, 15},
                          {"sphere through one face", {12.2, 10.1, 20.5}, 6},
                          {"sphere larger than the box", {12, 10, 11}, 40 - 25}};
    for (const Case& k : cases) {
        INFO(k.name);
        const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::sphere(k.center, k.radius));
        for (unsigned threads : {1u, 4u}) {
            const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims), cpu_options(0.0, threads));
            REQUIRE(vmtest::structural_problem(mesh).empty());
            REQUIRE(mesh.triangle_count() > 0);
            const vmtest::Topology topo = vmtest::topology(mesh);
            CHECK(topo.boundary_edges > 0);
            CHECK(topo.nonmanifold_edges == 0);
            CHECK(topo.consistently_oriented());
            CHECK(min_radial_alignment(mesh, k.center) > 0.9);
            vmtest::RefOptions ro;
            const vmtest::Comparison cmp =
                vmtest::compare_with_reference(mesh, vmtest::reference_mc(vmtest::to_doubles(values), dims, ro));
            INFO(cmp.first_problem);
            CHECK(cmp.same_indices);
            CHECK(cmp.max_normal_error <= 1e-5);  // one-sided differences at the border
        }
    }
}

TEST_CASE("anisotropic spacing and origin apply to positions and normals", "[core]") {
    const std::array<double, 3> spacing{0.5, 1.25, 2.0}, origin{-3.0, 7.5, 0.25};

    SECTION("oracle with spacing and origin") {
        const Dims dims{13, 11, 9};
        std::vector<double> values = vmtest::sample_field<double>(dims, vmtest::wavy(0.8));
        vmtest::RefOptions ro;
        ro.iso = 0.2;
        ro.spacing = spacing;
        ro.origin = origin;
        const vmtest::RefMesh ref = vmtest::reference_mc(values, dims, ro);
        REQUIRE(ref.triangle_count() > 50);
        for (unsigned threads : {1u, 3u}) {
            const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims, spacing, origin), cpu_options(0.2, threads));
            const vmtest::Comparison cmp = vmtest::compare_with_reference(mesh, ref);
            INFO(cmp.first_problem);
            CHECK(cmp.same_triangle_set);
            CHECK(cmp.same_indices);
            CHECK(cmp.max_position_error <= 1e-6);
            CHECK(cmp.max_normal_error <= 1e-5);
        }
    }
    SECTION("a plane field in world units: normals are the world-space plane normal") {
        const Dims dims{12, 9, 7};
        const double a = 0.6, b = -1.1, cz = 0.35;
        // f = -(a X + b Y + c Z) in world coordinates: high on the side opposite (a, b, c), so
        // the outward normal (toward decreasing values) is +(a, b, c) normalised.
        const vmtest::FieldFn plane = [&](double x, double y, double z) {
            const double X = origin[0] + x * spacing[0], Y = origin[1] + y * spacing[1], Z = origin[2] + z * spacing[2];
            return -(a * X + b * Y + cz * Z);
        };
        const std::vector<double> values = vmtest::sample_field<double>(dims, plane);
        const double iso = -(a * -0.2 + b * 13.0 + cz * 6.0);  // through a point inside the box
        const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims, spacing, origin), cpu_options(iso, 2));
        REQUIRE(mesh.triangle_count() > 20);
        const double len = std::sqrt(a * a + b * b + cz * cz);
        double worst_normal = 0, worst_plane = 0;
        for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
            const float* n = &mesh.normals[3 * v];
            const float* p = &mesh.positions[3 * v];
            worst_normal = std::max({worst_normal, std::fabs(n[0] - a / len), std::fabs(n[1] - b / len), std::fabs(n[2] - cz / len)});
            worst_plane = std::max(worst_plane, std::fabs(-(a * p[0] + b * p[1] + cz * p[2]) - iso));
        }
        CHECK(worst_normal < 1e-5);
        CHECK(worst_plane < 1e-4);
        // Positions stay inside the world-space box.
        for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
            for (int d = 0; d < 3; ++d) {
                CHECK(mesh.positions[3 * v + d] >= origin[d] - 1e-5);
                CHECK(mesh.positions[3 * v + d] <= origin[d] + (dims[d] - 1) * spacing[d] + 1e-5);
            }
    }
    SECTION("a world-space sphere on an anisotropic grid is a sphere") {
        const std::array<double, 3> sp{0.4, 0.7, 1.1};
        const Dims dims{71, 41, 27};
        const std::array<double, 3> center{origin[0] + 14.1, origin[1] + 14.2, origin[2] + 14.3};
        const double r = 11;
        const vmtest::FieldFn ball = [&](double x, double y, double z) {
            const double X = origin[0] + x * sp[0] - center[0], Y = origin[1] + y * sp[1] - center[1],
                         Z = origin[2] + z * sp[2] - center[2];
            return r - std::sqrt(X * X + Y * Y + Z * Z);
        };
        const std::vector<float> values = vmtest::sample_field<float>(dims, ball);
        const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims, sp, origin), cpu_options(0.0, 2));
        require_closed_surface(mesh, 2);
        CHECK(min_radial_alignment(mesh, center) > 0.99);
        const double area = vmtest::surface_area(mesh), expected = 4 * kPi * r * r;
        INFO("area " << area << " vs " << expected);
        CHECK(std::fabs(area - expected) <= 0.02 * expected);
        const double volume = vmtest::signed_volume(mesh), expected_volume = 4.0 / 3.0 * kPi * r * r * r;
        CHECK(std::fabs(volume - expected_volume) <= 0.02 * expected_volume);
    }
}
