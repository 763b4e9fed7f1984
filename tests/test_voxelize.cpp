#include <catch2/catch.hpp>
#include <voxmesh/voxelize.hpp>
#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

// A private binary-STL loader (unwelded soup) so these tests do not depend on src/io.
voxmesh::Mesh load_binary_stl(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    REQUIRE(in.good());
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    REQUIRE(bytes.size() >= 84);
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    REQUIRE(bytes.size() == 84 + 50 * std::size_t(n));
    voxmesh::Mesh m;
    for (std::uint32_t t = 0; t < n; ++t) {
        const char* rec = bytes.data() + 84 + 50 * std::size_t(t) + 12;
        for (int v = 0; v < 3; ++v) {
            float p[3];
            std::memcpy(p, rec + 12 * v, 12);
            m.positions.insert(m.positions.end(), p, p + 3);
            m.indices.push_back(3 * t + static_cast<std::uint32_t>(v));
        }
    }
    return m;
}

std::string data_file(const std::string& name) { return std::string("/work/shared/data/") + name; }

std::string model_path(const std::string& name) {
    const std::string local = std::string(VOXMESH_TEST_DATA) + "/" + name;
    if (std::ifstream(local).good()) return local;
    return data_file(name);
}

double signed_volume(const voxmesh::Mesh& m) {
    double v = 0;
    const auto& p = m.positions;
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
        const std::uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
        const double ax = p[3 * a], ay = p[3 * a + 1], az = p[3 * a + 2];
        const double bx = p[3 * b], by = p[3 * b + 1], bz = p[3 * b + 2];
        const double cx = p[3 * c], cy = p[3 * c + 1], cz = p[3 * c + 2];
        v += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
    }
    return v / 6.0;
}

struct Check {
    double model_volume = 0, mesh_volume = 0;
    bool closed = false;
    std::array<float, 3> lo{}, hi{}, mlo{}, mhi{};
    double h = 0;
};

void bounds(const voxmesh::Mesh& m, std::array<float, 3>& lo, std::array<float, 3>& hi) {
    lo = {1e30f, 1e30f, 1e30f};
    hi = {-1e30f, -1e30f, -1e30f};
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        lo[i % 3] = std::min(lo[i % 3], m.positions[i]);
        hi[i % 3] = std::max(hi[i % 3], m.positions[i]);
    }
}

Check round_trip(const voxmesh::Mesh& model, std::size_t resolution, voxmesh::VoxelField field) {
    voxmesh::VoxelizeOptions vo;
    vo.resolution = resolution;
    vo.field = field;
    const voxmesh::Volume vol = voxmesh::voxelize(model, vo);
    voxmesh::Options o;
    o.backend = voxmesh::Backend::Cpu;
    o.iso = field == voxmesh::VoxelField::Distance ? 0.0 : 127.5;
    const voxmesh::Mesh m = voxmesh::extract(vol.view(), o);
    Check c;
    c.model_volume = std::abs(signed_volume(model));
    c.mesh_volume = signed_volume(m);  // outward winding: positive
    c.closed = voxmesh::analyze_topology(m).closed();
    bounds(model, c.lo, c.hi);
    bounds(m, c.mlo, c.mhi);
    c.h = vol.spacing[0];
    return c;
}

// A closed axis-aligned box [lo, hi] with every face cut into `cuts` x `cuts` squares.
voxmesh::Mesh subdivided_box(std::array<double, 3> lo, std::array<double, 3> hi, int cuts) {
    voxmesh::Mesh m;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            const auto base = static_cast<std::uint32_t>(m.vertex_count());
            for (int b = 0; b <= cuts; ++b)
                for (int a = 0; a <= cuts; ++a) {
                    std::array<float, 3> p{};
                    p[axis] = static_cast<float>(side ? hi[axis] : lo[axis]);
                    p[u] = static_cast<float>(lo[u] + (hi[u] - lo[u]) * a / cuts);
                    p[v] = static_cast<float>(lo[v] + (hi[v] - lo[v]) * b / cuts);
                    m.positions.insert(m.positions.end(), p.begin(), p.end());
                }
            auto id = [&](int a, int b) { return base + static_cast<std::uint32_t>(a + (cuts + 1) * b); };
            for (int b = 0; b < cuts; ++b)
                for (int a = 0; a < cuts; ++a) {
                    std::array<std::uint32_t, 6> t{id(a, b), id(a + 1, b), id(a + 1, b + 1),
                                                   id(a, b), id(a + 1, b + 1), id(a, b + 1)};
                    if (!side) {  // outward winding on the low side
                        std::swap(t[1], t[2]);
                        std::swap(t[4], t[5]);
                    }
                    m.indices.insert(m.indices.end(), t.begin(), t.end());
                }
        }
    return m;  // unwelded along the box edges: voxelize welds by position
}

voxmesh::Mesh octahedron(double r) {
    voxmesh::Mesh m;
    const float f = static_cast<float>(r);
    m.positions = {f, 0, 0, -f, 0, 0, 0, f, 0, 0, -f, 0, 0, 0, f, 0, 0, -f};
    m.indices = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    return m;
}

template <class F>
void for_each_sample(const voxmesh::Volume& v, F&& f) {
    for (std::size_t k = 0; k < v.dims[2]; ++k)
        for (std::size_t j = 0; j < v.dims[1]; ++j)
            for (std::size_t i = 0; i < v.dims[0]; ++i) {
                const std::size_t idx = i + v.dims[0] * (j + v.dims[1] * k);
                f(idx, v.origin[0] + double(i) * v.spacing[0], v.origin[1] + double(j) * v.spacing[1],
                  v.origin[2] + double(k) * v.spacing[2]);
            }
}

}  // namespace

TEST_CASE("voxelize: closed STL round trips at 128 within 2 % (distance field)", "[voxelize]") {
    for (const char* name : {"unit_sphere.stl", "torus.stl", "20mm-xyz-cube.stl"}) {
        INFO(name);
        const voxmesh::Mesh model = load_binary_stl(model_path(name));
        const Check c = round_trip(model, 128, voxmesh::VoxelField::Distance);
        CHECK(c.closed);
        CHECK(c.mesh_volume == Approx(c.model_volume).epsilon(0.02));
        for (int d = 0; d < 3; ++d) {  // lands in the model's coordinates
            CHECK(std::abs(c.mlo[d] - c.lo[d]) < c.h);
            CHECK(std::abs(c.mhi[d] - c.hi[d]) < c.h);
        }
        if (std::string(name) == "unit_sphere.stl") {
            CHECK(c.model_volume == Approx(4.0 / 3.0 * std::numbers::pi).epsilon(0.01));
            CHECK(c.mesh_volume == Approx(4.0 / 3.0 * std::numbers::pi).epsilon(0.01));
        }
    }
}

TEST_CASE("voxelize: occupancy field round trips at low resolution", "[voxelize]") {
    const voxmesh::Mesh model = load_binary_stl(model_path("torus.stl"));
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 48;
    vo.field = voxmesh::VoxelField::Occupancy;
    const voxmesh::Volume vol = voxmesh::voxelize(model, vo);
    REQUIRE(vol.type == voxmesh::ScalarType::U8);
    const auto* s = static_cast<const std::uint8_t*>(vol.data);
    CHECK(std::all_of(s, s + vol.sample_count(), [](std::uint8_t x) { return x == 0 || x == 255; }));
    const Check c = round_trip(model, 48, voxmesh::VoxelField::Occupancy);
    CHECK(c.closed);
    CHECK(c.mesh_volume == Approx(c.model_volume).epsilon(0.03));
}

namespace {
// Both fields of `model` at resolution 40 on 2, 3 and 7 threads are byte for byte the 1-thread ones.
void check_thread_independent(const voxmesh::Mesh& model, voxmesh::FillRule fill) {
    for (auto field : {voxmesh::VoxelField::Distance, voxmesh::VoxelField::Occupancy}) {
        voxmesh::VoxelizeOptions vo;
        vo.resolution = 40;
        vo.field = field;
        vo.fill = fill;
        vo.threads = 1;
        const voxmesh::Volume a = voxmesh::voxelize(model, vo);
        for (unsigned t : {2u, 3u, 7u}) {
            vo.threads = t;
            const voxmesh::Volume b = voxmesh::voxelize(model, vo);
            REQUIRE(a.dims == b.dims);
            CHECK(a.origin == b.origin);
            CHECK(a.spacing == b.spacing);
            CHECK(std::memcmp(a.data, b.data, a.byte_size()) == 0);
        }
    }
}
}  // namespace

TEST_CASE("voxelize: result does not depend on the thread count", "[voxelize]") {
    check_thread_independent(load_binary_stl(model_path("torus.stl")), voxmesh::FillRule::EvenOdd);
}

TEST_CASE("voxelize: grid geometry", "[voxelize]") {
    const voxmesh::Mesh box = subdivided_box({0, 0, 0}, {20, 10, 5}, 1);
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 16;
    vo.padding = 3;
    const voxmesh::Volume v = voxmesh::voxelize(box, vo);
    CHECK(v.dims == std::array<std::size_t, 3>{22, 14, 10});
    CHECK(v.spacing[0] == Approx(1.25));
    CHECK(v.spacing[1] == v.spacing[0]);
    CHECK(v.spacing[2] == v.spacing[0]);
    CHECK(v.origin[0] == Approx(0.625 - 3 * 1.25));  // first voxel centre, less the padding
}

// A PLY or OBJ may hold vertices no face uses (a mesh through the API too): the grid is the
// triangles' box, whatever lies outside it, and the samples are the same as without them.
TEST_CASE("voxelize: vertices in no triangle do not move the grid", "[voxelize]") {
    const voxmesh::Mesh box = subdivided_box({0, 0, 0}, {20, 10, 5}, 1);
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 16;
    const voxmesh::Volume plain = voxmesh::voxelize(box, vo);
    for (const std::array<float, 3> stray : {std::array<float, 3>{-1e6f, -1e6f, -1e6f}, {1e6f, 1e6f, 1e6f}}) {
        INFO("stray vertex at " << stray[0]);
        voxmesh::Mesh with_stray = box;
        with_stray.positions.insert(with_stray.positions.end(), stray.begin(), stray.end());
        const voxmesh::Volume v = voxmesh::voxelize(with_stray, vo);
        CHECK(v.dims == plain.dims);
        CHECK(v.origin == plain.origin);
        CHECK(v.spacing == plain.spacing);
        REQUIRE(v.byte_size() == plain.byte_size());
        CHECK(std::memcmp(v.data, plain.data, v.byte_size()) == 0);
    }
}

TEST_CASE("voxelize: rays through vertices and along edges leave no streaks", "[voxelize]") {
    SECTION("box whose face vertices lie on sample rows") {
        // Box [0, 1]^3 at resolution 8: samples at odd multiples of 1/16; faces cut at every
        // 1/16, so rays along x pass exactly through face vertices and along diagonals.
        const voxmesh::Mesh box = subdivided_box({0, 0, 0}, {1, 1, 1}, 16);
        for (auto field : {voxmesh::VoxelField::Occupancy, voxmesh::VoxelField::Distance}) {
            voxmesh::VoxelizeOptions vo;
            vo.resolution = 8;
            vo.field = field;
            const voxmesh::Volume v = voxmesh::voxelize(box, vo);
            std::size_t wrong = 0;
            for_each_sample(v, [&](std::size_t idx, double x, double y, double z) {
                const bool inside = x > 0 && x < 1 && y > 0 && y < 1 && z > 0 && z < 1;
                const bool got = field == voxmesh::VoxelField::Occupancy
                                     ? static_cast<const std::uint8_t*>(v.data)[idx] == 255
                                     : static_cast<const float*>(v.data)[idx] > 0;
                if (inside != got) ++wrong;
                if (field == voxmesh::VoxelField::Distance) {  // exact distance to the box
                    double out2 = 0, in = 1e30;
                    for (double c : {x, y, z}) {
                        const double o = c < 0 ? -c : c > 1 ? c - 1 : 0;
                        out2 += o * o;
                        in = std::min({in, c, 1 - c});
                    }
                    const double expect = inside ? in : -std::sqrt(out2);
                    const double got_d = static_cast<const float*>(v.data)[idx];
                    if (std::abs(expect) < 2.5 * v.spacing[0]) CHECK(got_d == Approx(expect).margin(1e-5));
                }
            });
            CHECK(wrong == 0);
        }
    }
    SECTION("octahedron with vertices and edges on sample rows") {
        // Resolution 9 puts the centre on a sample: the rays y = z = 0 go through two
        // vertices, and rays in the planes y = 0 and z = 0 run through edges.
        const double r = 4.5;
        const voxmesh::Mesh oct = octahedron(r);
        voxmesh::VoxelizeOptions vo;
        vo.resolution = 9;
        vo.field = voxmesh::VoxelField::Occupancy;
        vo.threads = 2;
        const voxmesh::Volume v = voxmesh::voxelize(oct, vo);
        CHECK(v.spacing[0] == Approx(1.0));
        std::size_t wrong = 0, checked = 0;
        for_each_sample(v, [&](std::size_t idx, double x, double y, double z) {
            const double l1 = std::abs(x) + std::abs(y) + std::abs(z);
            if (std::abs(l1 - r) < 1e-6) return;  // on the surface: either answer is right
            ++checked;
            if ((l1 < r) != (static_cast<const std::uint8_t*>(v.data)[idx] == 255)) ++wrong;
        });
        CHECK(checked > 500);
        CHECK(wrong == 0);
        // Inverted winding does not matter to the parity rule.
        voxmesh::Mesh flipped = oct;
        for (std::size_t t = 0; t < flipped.triangle_count(); ++t)
            std::swap(flipped.indices[3 * t + 1], flipped.indices[3 * t + 2]);
        const voxmesh::Volume w = voxmesh::voxelize(flipped, vo);
        CHECK(std::memcmp(v.data, w.data, v.byte_size()) == 0);
    }
}

namespace {

// A cone over the unit circle in z = 0 fanned into `segments` slivers from `apex`, its base a
// fan from the centre: vertices 0..segments-1 on the circle, then the apex, then the centre.
voxmesh::Mesh fanned_cone(std::uint32_t segments, std::array<float, 3> apex) {
    voxmesh::Mesh cone;
    for (std::uint32_t i = 0; i < segments; ++i) {
        const double a = 2 * std::numbers::pi * i / segments;
        cone.positions.insert(cone.positions.end(), {float(std::cos(a)), float(std::sin(a)), 0.f});
    }
    cone.positions.insert(cone.positions.end(), {apex[0], apex[1], apex[2], 0.f, 0.f, 0.f});
    for (std::uint32_t i = 0; i < segments; ++i) {
        const std::uint32_t j = (i + 1) % segments;
        cone.indices.insert(cone.indices.end(), {i, j, segments, j, i, segments + 1});
    }
    return cone;
}

// The distance from p to triangle abc, the plain way: the foot of the perpendicular where it
// falls inside, else the nearest of the three edges.
double oracle_distance(const std::array<double, 3>& p, const std::array<std::array<double, 3>, 3>& t) {
    const auto sub = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
        return std::array<double, 3>{u[0] - v[0], u[1] - v[1], u[2] - v[2]};
    };
    const auto dot = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
        return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    };
    const auto cross = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
        return std::array<double, 3>{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    };
    const std::array<double, 3> n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    const double n2 = dot(n, n);
    bool inside = n2 > 0;
    for (int e = 0; e < 3 && inside; ++e) inside = dot(cross(sub(t[(e + 1) % 3], t[e]), sub(p, t[e])), n) >= 0;
    if (inside) return std::abs(dot(sub(p, t[0]), n)) / std::sqrt(n2);
    double best = 1e300;
    for (int e = 0; e < 3; ++e) {
        const std::array<double, 3> d = sub(t[(e + 1) % 3], t[e]), w = sub(p, t[e]);
        const double s = dot(d, d) > 0 ? std::clamp(dot(w, d) / dot(d, d), 0.0, 1.0) : 0.0;
        const std::array<double, 3> r{w[0] - s * d[0], w[1] - s * d[1], w[2] - s * d[2]};
        best = std::min(best, std::sqrt(dot(r, r)));
    }
    return best;
}

// Voxelizes `model` and compares every sample with the brute-force distance to its nearest
// triangle: within the band, equal within `tolerance` voxels (times the distance, past one
// voxel); beyond it, the band's cap.
struct OracleCheck {
    std::size_t near = 0, wrong = 0;
};
OracleCheck check_distances(const voxmesh::Mesh& model, const voxmesh::VoxelizeOptions& vo,
                            double tolerance = 1e-5) {
    std::vector<std::array<std::array<double, 3>, 3>> tris;
    for (std::size_t t = 0; t < model.triangle_count(); ++t) {
        std::array<std::array<double, 3>, 3> tri;
        for (int c = 0; c < 3; ++c)
            for (int d = 0; d < 3; ++d) tri[c][d] = model.positions[3 * model.indices[3 * t + c] + d];
        tris.push_back(tri);
    }
    const voxmesh::Volume v = voxmesh::voxelize(model, vo);
    const double h = v.spacing[0], cap = vo.band * h;
    OracleCheck check;
    for_each_sample(v, [&](std::size_t idx, double x, double y, double z) {
        double expect = 1e300;
        for (const auto& t : tris) expect = std::min(expect, oracle_distance({x, y, z}, t));
        const double got = std::abs(static_cast<const float*>(v.data)[idx]);
        const double edge = std::min(1e-6, tolerance);  // samples this near the cap may take either
        if (expect < cap * (1 - edge)) {
            ++check.near;
            if (std::abs(got - expect) > tolerance * std::max(h, expect)) ++check.wrong;
        } else if (expect > cap * (1 + edge) && got != Approx(cap).epsilon(edge)) {
            ++check.wrong;
        }
    });
    return check;
}

// `model` turned by the rotation with these angles about x, then y, then z.
voxmesh::Mesh rotated(voxmesh::Mesh model, double ax, double ay, double az) {
    for (std::size_t i = 0; i < model.vertex_count(); ++i) {
        double p[3] = {model.positions[3 * i], model.positions[3 * i + 1], model.positions[3 * i + 2]};
        const auto turn = [&](int u, int w, double angle) {
            const double c = std::cos(angle), s = std::sin(angle), pu = p[u], pw = p[w];
            p[u] = c * pu - s * pw;
            p[w] = s * pu + c * pw;
        };
        turn(1, 2, ax);
        turn(2, 0, ay);
        turn(0, 1, az);
        for (int d = 0; d < 3; ++d) model.positions[3 * i + d] = static_cast<float>(p[d]);
    }
    return model;
}

}  // namespace

// Long thin triangles lying across the axes (a cone's side and its base, fans from one
// point): each is scanned only near itself, not over its bounding box, and every sample
// within the band must still get its exact distance to the nearest triangle.
TEST_CASE("voxelize: distances near fans of long thin triangles match a brute-force oracle", "[voxelize]") {
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 40;
    const OracleCheck check = check_distances(fanned_cone(90, {0.2f, -0.1f, 1.3f}), vo);
    CHECK(check.near > 5000);
    CHECK(check.wrong == 0);
}

// Each row of samples is narrowed to within the band of a triangle's plane and of each edge's
// side, and the AVX2 copy measures four samples a step (moved back at the row's end, or not
// at all in rows shorter than four): sides facing every way, a triangle with no area, and
// grids three to five samples wide must all keep their exact distances.
TEST_CASE("voxelize: distances of turned, degenerate and narrow models match a brute-force oracle", "[voxelize]") {
    SECTION("a cut box turned off the axes") {
        const voxmesh::Mesh box = rotated(subdivided_box({-1, -0.6, -0.4}, {1, 0.6, 0.4}, 3), 0.3, 0.7, 1.1);
        for (double band : {2.0, 4.5}) {
            voxmesh::VoxelizeOptions vo;
            vo.resolution = 30;
            vo.band = band;
            const OracleCheck check = check_distances(box, vo);
            CHECK(check.near > 3000);
            CHECK(check.wrong == 0);
        }
    }
    SECTION("a tetrahedron with a triangle of no area along one edge") {
        // Edge AB split at its midpoint M on one side: faces AMC and MBC there, ABD on the
        // other, closed by the collinear triangle AMB (no plane, no sides).
        voxmesh::Mesh tet;
        // AB lies along x, so that A, M and B stay exactly collinear in grid coordinates.
        tet.positions = {0, 0, 0, 1, 0, 0, 0.3f, 0.9f, 0.1f, 0.4f, 0.3f, 0.8f, 0.5f, 0, 0};  // A B C D M
        tet.indices = {0, 4, 2, 4, 1, 2, 0, 3, 1, 1, 3, 2, 2, 3, 0, 0, 1, 4};
        voxmesh::VoxelizeOptions vo;
        vo.resolution = 24;
        const OracleCheck check = check_distances(tet, vo);
        CHECK(check.near > 1000);
        CHECK(check.wrong == 0);
    }
    SECTION("a needle of corners collinear in the model's floats, not along an axis") {
        // In grid coordinates its corners round apart: the cross product is noise, a plane
        // the needle does not have. A cube beside it, as the needle holds no sample inside.
        voxmesh::Mesh m = subdivided_box({0, 0, 0}, {0.25, 0.25, 0.25}, 1);
        const auto base = static_cast<std::uint32_t>(m.vertex_count());
        m.positions.insert(m.positions.end(), {0.375f, 0.25f, 0.125f, 0.4375f, 0.375f, 0.3125f, 0.53125f, 0.5625f,
                                               0.59375f});  // a + (1, 2, 3) / 16, a + (1, 2, 3) * 5 / 32
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 1});
        for (std::size_t resolution : {37, 41, 64}) {
            voxmesh::VoxelizeOptions vo;
            vo.resolution = resolution;
            const OracleCheck check = check_distances(m, vo);
            CHECK(check.near > 5000);
            CHECK(check.wrong == 0);
        }
    }
    SECTION("a triangle some 1e-60 voxels across") {
        // Voxels of 2^120 model units, and a closed tetrahedron of 1e-24 at the grid's first
        // sample: |n x edge|^2 (about 1e-360) is below the smallest double.
        const float big = std::ldexp(1.0f, 120), s = 1e-24f;
        voxmesh::Mesh m;
        m.positions = {-0.5f * big, 11.5f * big, 11.5f * big, 11.5f * big, -0.5f * big, 11.5f * big,
                       11.5f * big, 11.5f * big, -0.5f * big, 11.5f * big, 11.5f * big, 11.5f * big,
                       0, 0, 0, s, 0.2f * s, 0.1f * s, 0.3f * s, s, 0.2f * s, 0.1f * s, 0.3f * s, s};
        m.indices = {0, 1, 2, 0, 3, 1, 1, 3, 2, 2, 3, 0, 4, 5, 6, 4, 7, 5, 5, 7, 6, 6, 7, 4};
        voxmesh::VoxelizeOptions vo;
        vo.resolution = 12;
        vo.padding = 0;
        const voxmesh::Volume v = voxmesh::voxelize(m, vo);
        REQUIRE(v.origin[0] == 0);  // the tiny one sits on sample (0, 0, 0)
        const OracleCheck check = check_distances(m, vo);
        CHECK(check.near > 10);
        CHECK(check.wrong == 0);
    }
    SECTION("a side rising a few millionths of a voxel along 4096 samples") {
        // A wedge's knife edge along x, 3.5e-6 voxels higher at one end than the other: the
        // x bound of its side must keep that term (a cut-off for small slopes dropped it).
        // Checked to a few float roundings, as a dropped term moves samples by some 1.7e-6.
        const float y = 0.25f, rise = 3.5e-6f, x0 = -0.5f, x1 = 4095.5f;
        voxmesh::Mesh m;
        m.positions = {x0, y, 0, x1, y + rise, 0, x0, -1.75f, 0, x1, -1.75f, 0, x0, y, -2.5f, x1, y + rise, -2.5f,
                       // a closed tetrahedron apart, so that z = 0 is a sample plane
                       100, -1.5f, 0.1f, 101, -1.5f, 0.1f, 100, -1.0f, 0.1f, 100, -1.5f, 0.5f};
        m.indices = {0, 1, 3, 0, 3, 2, 0, 4, 1, 1, 4, 5, 2, 3, 5, 2, 5, 4, 0, 2, 4, 1, 3, 5,
                     6, 7, 8, 6, 9, 7, 7, 9, 8, 8, 9, 6};
        voxmesh::VoxelizeOptions vo;
        vo.resolution = 4096;
        vo.padding = 3;
        vo.band = 2;
        const OracleCheck check = check_distances(m, vo, 2.5e-7);
        CHECK(check.near > 100000);
        CHECK(check.wrong == 0);
    }
    SECTION("grids three to five samples wide") {
        const voxmesh::Mesh oct = rotated(octahedron(1.0), 0.1, 0.2, 0.3);
        for (std::size_t resolution : {3, 4, 5}) {
            voxmesh::VoxelizeOptions vo;
            vo.resolution = resolution;
            vo.padding = 0;
            const OracleCheck check = check_distances(oct, vo);
            CHECK(check.near > 0);
            CHECK(check.wrong == 0);
        }
    }
}

// A convex cone fanned into slivers: every side triangle spans every z plane, so each row
// sees its candidates through the plane's row lists. Inside is where every face plane has
// the sample behind it; samples on a face (within a thousandth of a voxel) may go either way.
TEST_CASE("voxelize: inside test of a fanned convex cone matches its face planes", "[voxelize]") {
    constexpr std::uint32_t kFan = 300;
    const voxmesh::Mesh cone = fanned_cone(kFan, {0.3f, -0.2f, 1.1f});
    // Outward planes n . p = d of the side triangles and the base (z = 0, facing down).
    std::vector<std::array<double, 4>> planes{{0, 0, -1, 0}};
    const auto at = [&](std::uint32_t v) {
        return std::array<double, 3>{cone.positions[3 * v], cone.positions[3 * v + 1], cone.positions[3 * v + 2]};
    };
    for (std::uint32_t i = 0; i < kFan; ++i) {
        const auto a = at(i), b = at((i + 1) % kFan), c = at(kFan);
        const std::array<double, 3> u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        std::array<double, 3> n{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (double& x : n) x /= len;
        planes.push_back({n[0], n[1], n[2], n[0] * a[0] + n[1] * a[1] + n[2] * a[2]});
    }
    for (unsigned threads : {1u, 2u}) {
        voxmesh::VoxelizeOptions vo;
        vo.resolution = 56;
        vo.field = voxmesh::VoxelField::Occupancy;
        vo.threads = threads;
        const voxmesh::Volume v = voxmesh::voxelize(cone, vo);
        std::size_t inside = 0, wrong = 0;
        for_each_sample(v, [&](std::size_t idx, double x, double y, double z) {
            double out = -1e300;  // the largest signed distance to a face plane: < 0 inside
            for (const auto& p : planes) out = std::max(out, p[0] * x + p[1] * y + p[2] * z - p[3]);
            if (std::abs(out) < 1e-3 * v.spacing[0]) return;
            inside += out < 0;
            if ((out < 0) != (static_cast<const std::uint8_t*>(v.data)[idx] == 255)) ++wrong;
        });
        CHECK(inside > 20000);
        CHECK(wrong == 0);
    }
}

TEST_CASE("voxelize: open, non-manifold and empty meshes are rejected", "[voxelize]") {
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 16;
    voxmesh::Mesh open = octahedron(1);
    open.indices.resize(open.indices.size() - 3);
    CHECK_THROWS_WITH(voxmesh::voxelize(open, vo), Catch::Contains("not closed"));

    // A box with a wall across it at x = 0.5, welded to its faces: the wall's rim edges are in
    // three triangles, and which side of the wall is inside is undefined.
    voxmesh::Mesh walled = subdivided_box({0, 0, 0}, {1, 1, 1}, 2);
    const auto wall_base = static_cast<std::uint32_t>(walled.vertex_count());
    for (int b = 0; b <= 2; ++b)
        for (int a = 0; a <= 2; ++a) walled.positions.insert(walled.positions.end(), {0.5f, 0.5f * a, 0.5f * b});
    for (std::uint32_t b = 0; b < 2; ++b)
        for (std::uint32_t a = 0; a < 2; ++a) {
            const std::uint32_t v = wall_base + a + 3 * b;
            walled.indices.insert(walled.indices.end(), {v, v + 1, v + 4, v, v + 4, v + 3});
        }
    for (const auto fill : {voxmesh::FillRule::EvenOdd, voxmesh::FillRule::NonZero}) {
        vo.fill = fill;
        CHECK_THROWS_WITH(voxmesh::voxelize(walled, vo),
                          Catch::Contains("not closed: 8 edges belong to an odd number of triangles, three or more"));
    }
    vo.fill = voxmesh::FillRule::EvenOdd;

    voxmesh::Mesh empty;
    CHECK_THROWS_WITH(voxmesh::voxelize(empty, vo), Catch::Contains("no triangles"));
    voxmesh::Mesh nan = octahedron(1);
    nan.positions[4] = std::nanf("");
    CHECK_THROWS_WITH(voxmesh::voxelize(nan, vo), Catch::Contains("non-finite"));
    voxmesh::Mesh bad_index = octahedron(1);
    bad_index.indices[0] = 99;
    CHECK_THROWS_WITH(voxmesh::voxelize(bad_index, vo), Catch::Contains("out of range"));
    vo.resolution = 1;
    CHECK_THROWS_WITH(voxmesh::voxelize(octahedron(1), vo), Catch::Contains("resolution"));
}

TEST_CASE("voxelize: a grid larger than the memory available is refused before allocating", "[voxelize]") {
    // The largest grid the options allow: 4608^3 f32 samples, about 391 GB.
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 4096;
    vo.padding = 256;
    const double bytes = 4.0 * 4608.0 * 4608.0 * 4608.0;
    const double physical = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGESIZE));
    if (!(physical > 0) || physical >= bytes) {
        WARN("this machine has " << physical << " bytes of memory; the largest grid fits, nothing to refuse");
        return;
    }
    CHECK_THROWS_WITH(voxmesh::voxelize(subdivided_box({0, 0, 0}, {1, 1, 1}, 1), vo),
                      Catch::Contains("4608x4608x4608") && Catch::Contains("resolution 4096") &&
                          Catch::Contains("memory available"));
}

TEST_CASE("voxelize: a flat closed model is an error, not an empty volume", "[voxelize]") {
    // A tetrahedron squashed into z = 0: closed and manifold, every face with area, no volume.
    voxmesh::Mesh flat;
    flat.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.25f, 0.25f, 0};
    flat.indices = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 16;
    for (const voxmesh::VoxelField field : {voxmesh::VoxelField::Distance, voxmesh::VoxelField::Occupancy}) {
        vo.field = field;
        CHECK_THROWS_WITH(voxmesh::voxelize(flat, vo), Catch::Contains("no sample") && Catch::Contains("flat"));
    }
    // The same tetrahedron lifted to a height of one voxel has samples inside.
    flat.positions[11] = 1.f / 8;
    CHECK_NOTHROW(voxmesh::voxelize(flat, vo));
}

TEST_CASE("voxelize: triangle row lists larger than memory are refused before they are built",
          "[voxelize]") {
    // A thin prism along z, 1 tall at resolution 4096: each of its 2n side triangles spans 4096
    // z rows, 16 KiB of row lists each; n is chosen to need a quarter more than this machine has.
    const double physical = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGESIZE));
    const double per_side = 2.0 * 4096 * 4;
    if (!(physical > 0) || physical / per_side > 6e6) {
        WARN("this machine has " << physical << " bytes of memory; the prism that fills it is too large to test");
        return;
    }
    const auto n = static_cast<std::uint32_t>(1.25 * physical / per_side);
    voxmesh::Mesh prism;
    const double r = 0.01;
    for (std::uint32_t i = 0; i < n; ++i) {
        const double a = 2 * std::numbers::pi * i / n;
        const auto x = static_cast<float>(r * std::cos(a)), y = static_cast<float>(r * std::sin(a));
        prism.positions.insert(prism.positions.end(), {x, y, 0.f, x, y, 1.f});
    }
    prism.positions.insert(prism.positions.end(), {0.f, 0.f, 0.f, 0.f, 0.f, 1.f});  // the caps' centres
    const std::uint32_t bottom = 2 * n, top = 2 * n + 1;
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t j = (i + 1) % n;
        prism.indices.insert(prism.indices.end(), {2 * i, 2 * j, 2 * j + 1, 2 * i, 2 * j + 1, 2 * i + 1,
                                                   bottom, 2 * j, 2 * i, top, 2 * i + 1, 2 * j + 1});
    }
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 4096;
    vo.field = voxmesh::VoxelField::Occupancy;
    CHECK_THROWS_WITH(voxmesh::voxelize(prism, vo),
                      Catch::Contains("row lists") && Catch::Contains("memory available"));
}

TEST_CASE("voxelize: models near the float limit give finite samples or a clear error", "[voxelize]") {
    // A tetrahedron in the cube [-a, a]^3: the cube's corner (-a, -a, -a) is 1.15 a from it,
    // and the grid's padded corner samples farther still.
    const float a = 1e38f;
    voxmesh::Mesh tet;
    tet.positions = {a, a, a, a, -a, -a, -a, a, -a, -a, -a, a};
    tet.indices = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 2;
    vo.padding = 2;  // samples at +-2.5e38: in range, the corner's distance 3.75e38 is not
    vo.band = 4;
    const voxmesh::Volume v = voxmesh::voxelize(tet, vo);
    const auto* d = static_cast<const float*>(v.data);
    for (std::size_t i = 0; i < v.sample_count(); ++i) REQUIRE(std::isfinite(d[i]));
    REQUIRE(v.dims == std::array<std::size_t, 3>{6, 6, 6});
    CHECK(d[0] == -FLT_MAX);              // the (-, -, -) corner, clamped
    CHECK(d[3 + 6 * (3 + 6 * 3)] > 0);    // (0.5 a, 0.5 a, 0.5 a) is inside
    voxmesh::Options eo;
    eo.backend = voxmesh::Backend::Cpu;
    const voxmesh::Mesh back = voxmesh::extract(v.view(), eo);
    CHECK(back.triangle_count() > 0);

    vo.padding = 3;  // samples at +-3.5e38: no float vertex can stand for them
    CHECK_THROWS_WITH(voxmesh::voxelize(tet, vo), Catch::Contains("beyond the range of float"));
}

namespace {

// A UV sphere wound outward (inward when `inward`), welded, with poles.
voxmesh::Mesh uv_sphere(std::array<double, 3> c, double r, int segments, int rings, bool inward = false) {
    voxmesh::Mesh m;
    const double pi = std::numbers::pi;
    auto put = [&](double x, double y, double z) {
        m.positions.insert(m.positions.end(), {static_cast<float>(c[0] + r * x), static_cast<float>(c[1] + r * y),
                                               static_cast<float>(c[2] + r * z)});
    };
    put(0, 0, 1);  // north pole: 0
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const double t = pi * i / rings, p = 2 * pi * j / segments;
            put(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
        }
    put(0, 0, -1);  // south pole: last
    const auto south = static_cast<std::uint32_t>(m.vertex_count() - 1);
    auto id = [&](int i, int j) { return static_cast<std::uint32_t>(1 + (i - 1) * segments + (j % segments)); };
    auto tri = [&](std::uint32_t a, std::uint32_t b, std::uint32_t cc) {
        if (inward) std::swap(b, cc);
        m.indices.insert(m.indices.end(), {a, b, cc});
    };
    for (int j = 0; j < segments; ++j) {
        tri(0, id(1, j), id(1, j + 1));
        tri(south, id(rings - 1, j + 1), id(rings - 1, j));
        for (int i = 1; i + 1 < rings; ++i) {
            tri(id(i, j), id(i + 1, j), id(i + 1, j + 1));
            tri(id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
    }
    return m;
}

voxmesh::Mesh joined(voxmesh::Mesh a, const voxmesh::Mesh& b) {
    const auto base = static_cast<std::uint32_t>(a.vertex_count());
    a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
    for (std::uint32_t i : b.indices) a.indices.push_back(base + i);
    return a;
}

struct Meshed {
    voxmesh::Volume volume;
    voxmesh::Mesh mesh;
    voxmesh::MeshTopology topology;
    double mesh_volume = 0;
};

Meshed voxelize_and_mesh(const voxmesh::Mesh& model, voxmesh::FillRule fill, voxmesh::VoxelField field,
                         std::size_t resolution, unsigned threads = 0) {
    voxmesh::VoxelizeOptions vo;
    vo.resolution = resolution;
    vo.field = field;
    vo.fill = fill;
    vo.threads = threads;
    Meshed r;
    r.volume = voxmesh::voxelize(model, vo);
    voxmesh::Options o;
    o.backend = voxmesh::Backend::Cpu;
    o.iso = field == voxmesh::VoxelField::Distance ? 0.0 : 127.5;
    r.mesh = voxmesh::extract(r.volume.view(), o);
    r.topology = voxmesh::analyze_topology(r.mesh);
    r.mesh_volume = signed_volume(r.mesh);
    return r;
}

}  // namespace

// Two unit spheres whose centres are 1 apart (several CAD bodies in one STL).
TEST_CASE("voxelize: overlapping shells: NonZero gives their union, EvenOdd leaves the overlap out", "[voxelize]") {
    const double r = 1, d = 1, pi = std::numbers::pi;
    const voxmesh::Mesh model = joined(uv_sphere({-d / 2, 0, 0}, r, 96, 48), uv_sphere({d / 2, 0, 0}, r, 96, 48));
    const double sphere = 4.0 / 3.0 * pi * r * r * r, lens = pi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12;
    const double union_volume = 2 * sphere - lens;
    for (const auto field : {voxmesh::VoxelField::Distance, voxmesh::VoxelField::Occupancy}) {
        INFO("field " << int(field));
        const Meshed u = voxelize_and_mesh(model, voxmesh::FillRule::NonZero, field, 96);
        CHECK(u.topology.closed());
        CHECK(u.topology.euler == 2);
        CHECK(u.topology.components == 1);
        // Occupancy's stair steps and the inscribed polygons each lose some 0.2 % here.
        CHECK(u.mesh_volume == Approx(union_volume).epsilon(0.01));

        // The old rule, unchanged: the overlap is outside (two shells touching along a circle).
        const Meshed x = voxelize_and_mesh(model, voxmesh::FillRule::EvenOdd, field, 96);
        CHECK(x.mesh_volume == Approx(union_volume - lens).epsilon(0.01));
        CHECK(x.topology.euler != 2);
        voxmesh::VoxelizeOptions default_fill;
        default_fill.resolution = 96;
        default_fill.field = field;
        const voxmesh::Volume v = voxmesh::voxelize(model, default_fill);
        CHECK(std::memcmp(v.data, x.volume.data, v.byte_size()) == 0);  // EvenOdd is the default
    }

    // The distance's sign follows the rule: positive throughout the union (off its surface by
    // more than a voxel), negative outside it.
    const Meshed u = voxelize_and_mesh(model, voxmesh::FillRule::NonZero, voxmesh::VoxelField::Distance, 64);
    const auto* f = static_cast<const float*>(u.volume.data);
    const double h = u.volume.spacing[0];
    std::size_t wrong = 0, inside = 0;
    for_each_sample(u.volume, [&](std::size_t i, double x, double y, double z) {
        const double a = std::sqrt((x + d / 2) * (x + d / 2) + y * y + z * z) - r;
        const double b = std::sqrt((x - d / 2) * (x - d / 2) + y * y + z * z) - r;
        const double to_union = std::min(a, b);  // < 0 inside
        if (to_union < -h) wrong += !(f[i] > 0), ++inside;
        if (to_union > h) wrong += !(f[i] < 0);
    });
    CHECK(inside > 0);
    CHECK(wrong == 0);
}

TEST_CASE("voxelize: NonZero needs consistent winding; EvenOdd does not", "[voxelize]") {
    voxmesh::Mesh model = uv_sphere({0, 0, 0}, 1, 32, 16);
    std::swap(model.indices[40], model.indices[41]);  // one triangle flipped: its 3 edges disagree
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 24;
    vo.fill = voxmesh::FillRule::NonZero;
    CHECK_THROWS_WITH(voxmesh::voxelize(model, vo),
                      Catch::Contains("not consistently wound: 3 edges") && Catch::Contains("FillRule::EvenOdd"));
    vo.fill = voxmesh::FillRule::EvenOdd;
    CHECK_NOTHROW(voxmesh::voxelize(model, vo));

    // Wound inward throughout is consistent: the winding is -1 inside, which is non-zero.
    const voxmesh::Mesh inward = uv_sphere({0, 0, 0}, 1, 64, 32, true);
    for (const auto fill : {voxmesh::FillRule::NonZero, voxmesh::FillRule::EvenOdd}) {
        const Meshed m = voxelize_and_mesh(inward, fill, voxmesh::VoxelField::Distance, 48);
        CHECK(m.topology.closed());
        CHECK(m.topology.euler == 2);
        CHECK(m.mesh_volume == Approx(4.0 / 3.0 * std::numbers::pi).epsilon(0.01));
    }
}

// A shell inside another, both wound outward: NonZero fills the inner one too (winding 2
// there), EvenOdd leaves it hollow (two crossings: even).
TEST_CASE("voxelize: nested shells: NonZero is solid, EvenOdd is hollow", "[voxelize]") {
    const double pi = std::numbers::pi, outer = 4.0 / 3.0 * pi, inner = outer / 8;
    const voxmesh::Mesh model = joined(uv_sphere({0, 0, 0}, 1, 96, 48), uv_sphere({0.1, 0, 0}, 0.5, 64, 32));
    const Meshed solid = voxelize_and_mesh(model, voxmesh::FillRule::NonZero, voxmesh::VoxelField::Distance, 64);
    CHECK(solid.topology.closed());
    CHECK(solid.topology.components == 1);
    CHECK(solid.topology.euler == 2);
    CHECK(solid.mesh_volume == Approx(outer).epsilon(0.01));
    const Meshed hollow = voxelize_and_mesh(model, voxmesh::FillRule::EvenOdd, voxmesh::VoxelField::Distance, 64);
    CHECK(hollow.topology.closed());
    CHECK(hollow.topology.components == 2);
    CHECK(hollow.topology.euler == 4);
    CHECK(hollow.mesh_volume == Approx(outer - inner).epsilon(0.01));
}

TEST_CASE("voxelize: NonZero does not depend on the thread count", "[voxelize]") {
    // Overlapping, nested and inside-out shells at once, sharing some rays' vertices.
    voxmesh::Mesh model = joined(uv_sphere({-0.5, 0, 0}, 1, 40, 20), uv_sphere({0.5, 0, 0}, 1, 40, 20));
    model = joined(model, uv_sphere({-0.5, 0, 0}, 0.3, 16, 8, true));
    check_thread_independent(model, voxmesh::FillRule::NonZero);
}

// Bodies exported together that share faces or edges (an assembly in one STL): those edges are
// in four triangles, and a shared face's two copies cancel. Both rules fill the union.
TEST_CASE("voxelize: bodies sharing a face or an edge: both rules fill their union", "[voxelize]") {
    const voxmesh::Mesh face = joined(subdivided_box({0, 0, 0}, {1, 1, 1}, 2), subdivided_box({0, 0, 1}, {1, 1, 2}, 2));
    const voxmesh::Mesh edge = joined(subdivided_box({0, 0, 0}, {1, 1, 1}, 2), subdivided_box({1, 1, 0}, {2, 2, 1}, 2));
    for (const voxmesh::Mesh* model : {&face, &edge}) {
        for (const auto fill : {voxmesh::FillRule::EvenOdd, voxmesh::FillRule::NonZero})
            for (const auto field : {voxmesh::VoxelField::Distance, voxmesh::VoxelField::Occupancy}) {
                INFO((model == &face ? "face" : "edge") << ", fill " << int(fill) << ", field " << int(field));
                const Meshed u = voxelize_and_mesh(*model, fill, field, 32);
                CHECK(u.topology.closed());
                CHECK(u.mesh_volume == Approx(2.0).epsilon(0.02));
                if (model == &face) {
                    CHECK(u.topology.components == 1);
                    CHECK(u.topology.euler == 2);
                }
            }
    }
    // The shared face is gone, not buried: the distance inside is to the union's surface (the
    // box [0,1]x[0,1]x[0,2]), exact in the band, not to the plane z = 1 the bodies meet on.
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 32;
    vo.fill = voxmesh::FillRule::NonZero;
    const voxmesh::Volume field = voxmesh::voxelize(face, vo);
    const auto* f = static_cast<const float*>(field.data);
    const double h = field.spacing[0];
    std::size_t near_the_seam = 0;
    for_each_sample(field, [&](std::size_t i, double x, double y, double z) {
        const double to_box = std::min({x, 1 - x, y, 1 - y, z, 2 - z});
        if (to_box <= 0 || to_box > 2.5 * h || std::abs(z - 1) > h) return;
        ++near_the_seam;
        CHECK(f[i] == Approx(to_box).margin(1e-5));
    });
    CHECK(near_the_seam > 0);
}

TEST_CASE("voxelize: coincident triangles cancel as their crossings do", "[voxelize]") {
    const voxmesh::Mesh box = subdivided_box({0, 0, 0}, {1, 1, 1}, 2);
    const auto with_copies = [&](std::size_t t, int same, int flipped) {
        voxmesh::Mesh m = box;
        const std::uint32_t a = box.indices[3 * t], b = box.indices[3 * t + 1], c = box.indices[3 * t + 2];
        for (int i = 0; i < same; ++i) m.indices.insert(m.indices.end(), {a, b, c});
        for (int i = 0; i < flipped; ++i) m.indices.insert(m.indices.end(), {a, c, b});
        return m;
    };
    const auto same_volume = [](const voxmesh::Mesh& a, const voxmesh::Mesh& b, voxmesh::VoxelizeOptions vo) {
        for (const auto field : {voxmesh::VoxelField::Distance, voxmesh::VoxelField::Occupancy}) {
            vo.field = field;
            const voxmesh::Volume va = voxmesh::voxelize(a, vo), vb = voxmesh::voxelize(b, vo);
            REQUIRE(va.byte_size() == vb.byte_size());
            CHECK(std::memcmp(va.data, vb.data, va.byte_size()) == 0);
        }
    };
    voxmesh::VoxelizeOptions vo;
    vo.resolution = 16;
    vo.fill = voxmesh::FillRule::NonZero;
    // One copy the same way: winding 2 across that face, but its edges are in three triangles.
    CHECK_THROWS_WITH(voxmesh::voxelize(with_copies(5, 1, 0), vo),
                      Catch::Contains("not closed: 3 edges belong to an odd number of triangles"));
    // Two copies the same way: four triangles at each edge, three of them one way.
    CHECK_THROWS_WITH(voxmesh::voxelize(with_copies(5, 2, 0), vo),
                      Catch::Contains("not consistently wound: 3 edges are used more often in one direction"));
    // A copy each way: a two-sided sheet on the surface, whose crossings cancel: the same volume.
    same_volume(box, with_copies(5, 1, 1), vo);
    same_volume(box, with_copies(5, 2, 2), vo);

    // Parity: any two coincident triangles cancel, whatever their winding.
    vo.fill = voxmesh::FillRule::EvenOdd;
    CHECK_THROWS_WITH(voxmesh::voxelize(with_copies(5, 1, 0), vo),
                      Catch::Contains("not closed: 3 edges belong to only one triangle"));
    same_volume(box, with_copies(5, 2, 0), vo);
    same_volume(box, with_copies(5, 1, 1), vo);

    // A sheet alone encloses nothing.
    voxmesh::Mesh sheet;
    sheet.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    sheet.indices = {0, 1, 2, 0, 2, 1};
    for (const auto fill : {voxmesh::FillRule::EvenOdd, voxmesh::FillRule::NonZero}) {
        vo.fill = fill;
        CHECK_THROWS_WITH(voxmesh::voxelize(sheet, vo), Catch::Contains("has a coincident one") &&
                                                            Catch::Contains("encloses nothing"));
    }
}
