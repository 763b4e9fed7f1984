// Sculpting: block meshes, dirty tracking and the assembled mesh against full extracts.
#include <catch2/catch.hpp>

#include <voxmesh/sculpt.hpp>

#include "support/child_process.hpp"
#include "support/sculpt_fields.hpp"

#include "core/parallel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

namespace {

using voxmesh::BrushOp;
using voxmesh::Dab;
using voxmesh::Mesh;
using voxmesh::ScalarType;
using voxmesh::Sculpt;
using voxmesh::SculptOptions;
using Dims = std::array<std::size_t, 3>;

Mesh full_extract(const Sculpt& s) {
    voxmesh::Options o;
    o.iso = s.options().iso;
    o.backend = voxmesh::Backend::Cpu;
    o.threads = 2;
    o.normals = s.options().normals;
    o.inside_below = s.options().inside_below;
    return voxmesh::extract(s.view(), o);
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

// The assembled mesh is extract's canonical mesh: same indices, bit-identical vertices.
void require_equals_extract(Sculpt& s) {
    const Mesh got = s.mesh();
    const Mesh want = full_extract(s);
    REQUIRE(got.vertex_count() == want.vertex_count());
    REQUIRE(got.triangle_count() == want.triangle_count());
    REQUIRE(got.indices == want.indices);
    REQUIRE(same_bits(got.positions, want.positions));
    REQUIRE(same_bits(got.normals, want.normals));
}

struct PosKey {
    std::uint32_t b[3];
    bool operator==(const PosKey& o) const { return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2]; }
};
struct PosHash {
    std::size_t operator()(const PosKey& k) const {
        return (std::size_t{k.b[0]} * 0x9E3779B97F4A7C15ull) ^ (std::size_t{k.b[1]} * 0xC2B2AE3D27D4EB4Full) ^ k.b[2];
    }
};
PosKey pos_key(const float* p) {
    PosKey k;
    std::memcpy(k.b, p, 12);
    return k;
}

using Tri = std::array<std::uint32_t, 3>;
Tri oriented(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    if (b < a && b < c) return {b, c, a};
    if (c < a && c < b) return {c, a, b};
    return {a, b, c};
}

// Independent of Sculpt::mesh(): the union of all block meshes, each vertex identified with
// extract's vertex at the same position (extract's vertex ids are its canonical edge order,
// sample index then axis), must be extract's triangle set, oriented, as a multiset.
void require_blocks_cover_extract(const Sculpt& s) {
    const Mesh want = full_extract(s);
    std::unordered_map<PosKey, std::uint32_t, PosHash> id;
    id.reserve(want.vertex_count());
    for (std::size_t v = 0; v < want.vertex_count(); ++v)
        REQUIRE(id.emplace(pos_key(&want.positions[3 * v]), static_cast<std::uint32_t>(v)).second);
    std::vector<Tri> expected, got;
    for (std::size_t t = 0; t < want.triangle_count(); ++t)
        expected.push_back(oriented(want.indices[3 * t], want.indices[3 * t + 1], want.indices[3 * t + 2]));
    for (std::size_t b = 0; b < s.block_count(); ++b) {
        const voxmesh::BlockMesh m = s.block(b);
        std::vector<std::uint32_t> map(m.vertex_count());
        for (std::size_t v = 0; v < m.vertex_count(); ++v) {
            const auto it = id.find(pos_key(&m.positions[3 * v]));
            REQUIRE(it != id.end());
            map[v] = it->second;
            if (!m.normals.empty()) REQUIRE(std::memcmp(&m.normals[3 * v], &want.normals[3 * it->second], 12) == 0);
        }
        for (std::size_t t = 0; t < m.triangle_count(); ++t) {
            REQUIRE(m.indices[3 * t] < m.vertex_count());
            REQUIRE(m.indices[3 * t + 1] < m.vertex_count());
            REQUIRE(m.indices[3 * t + 2] < m.vertex_count());
            got.push_back(oriented(map[m.indices[3 * t]], map[m.indices[3 * t + 1]], map[m.indices[3 * t + 2]]));
        }
    }
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
    REQUIRE(got == expected);
}

// Brute force: a fresh Sculpt of the same volume meshes every block; every block of `s`
// must match it exactly (a block that missed an update differs).
void require_blocks_match_fresh(const Sculpt& s) {
    Sculpt fresh(s.view(), s.options());
    fresh.update();
    REQUIRE(fresh.block_count() == s.block_count());
    for (std::size_t b = 0; b < s.block_count(); ++b) {
        const auto x = s.block(b), y = fresh.block(b);
        INFO("block " << b);
        REQUIRE(x.indices.size() == y.indices.size());
        REQUIRE(std::equal(x.indices.begin(), x.indices.end(), y.indices.begin()));
        REQUIRE(x.positions.size() == y.positions.size());
        REQUIRE((x.positions.empty() || std::memcmp(x.positions.data(), y.positions.data(), x.positions.size_bytes()) == 0));
        REQUIRE(x.normals.size() == y.normals.size());
        REQUIRE((x.normals.empty() || std::memcmp(x.normals.data(), y.normals.data(), x.normals.size_bytes()) == 0));
    }
}

using sculpt_test::balls;
using sculpt_test::kTypes;
using sculpt_test::random_op;
using sculpt_test::random_strength;
using sculpt_test::TypeSetup;

Sculpt make(const TypeSetup& ts, Dims d, std::size_t block, unsigned threads = 2) {
    SculptOptions o;
    o.iso = ts.iso;
    o.block_size = block;
    o.threads = threads;
    o.strength_scale = ts.scale;  // strength in samples of displacement for every type
    return Sculpt::from_function(d, ts.type, balls(d, ts.scale, ts.offset), o);
}

Dab random_dab(std::mt19937& rng, Dims d, double margin, double max_radius, double set_scale, double set_offset) {
    std::uniform_real_distribution<double> u01(0, 1);
    Dab dab;
    dab.op = random_op(rng);
    dab.radius = 1 + u01(rng) * (max_radius - 1);
    for (int k = 0; k < 3; ++k) {
        const double lo = margin >= 0 ? margin + dab.radius : margin, hi = double(d[k] - 1) - lo;
        dab.center[k] = lo + u01(rng) * (hi - lo);
    }
    random_strength(dab, rng, set_scale, set_offset, 4.0);
    return dab;
}

}  // namespace

TEST_CASE("sculpt: the first update meshes every block; blocks and mesh() equal extract", "[sculpt]") {
    for (const TypeSetup& ts : kTypes) {
        for (std::size_t block : {std::size_t{5}, std::size_t{8}, std::size_t{32}}) {
            INFO(voxmesh::scalar_name(ts.type) << " block " << block);
            Sculpt s = make(ts, {41, 37, 45}, block);
            REQUIRE(s.dirty());
            const auto r = s.update();
            REQUIRE(r.remeshed == s.block_count());
            REQUIRE_FALSE(s.dirty());
            require_equals_extract(s);
            require_blocks_cover_extract(s);
            REQUIRE(voxmesh::analyze_topology(s.mesh()).closed());
        }
    }
}

// Found by a review: threads = 100000 started a worker (and a scratch) per dirty block, 2145
// threads and 7 s for a first update extract() does in 12 ms. Capped at the usable cores.
TEST_CASE("sculpt: more threads than cores run as many workers as cores, with the same mesh", "[sculpt]") {
    const std::size_t before = vmtest::proc_status_number("Threads:");
    Sculpt many = make(kTypes[0], {40, 40, 40}, 2, 5000);  // 8000 blocks
    many.update();
    const std::size_t after = vmtest::proc_status_number("Threads:");
    CHECK(after <= before + voxmesh::detail::resolve_threads(0));
    require_equals_extract(many);
    Sculpt two = make(kTypes[0], {40, 40, 40}, 2, 2);
    CHECK(two.mesh().indices == many.mesh().indices);
}

TEST_CASE("sculpt: inside_below and normals off agree with extract", "[sculpt]") {
    const Dims d{30, 34, 28};
    SculptOptions o;
    o.block_size = 7;
    o.inside_below = true;
    Sculpt a = Sculpt::from_function(d, ScalarType::F32, balls(d, -1, 0.25), o);
    a.subtract({15, 17, 14}, 5, 1.5);
    a.update();
    require_equals_extract(a);
    require_blocks_cover_extract(a);
    o.inside_below = false;
    o.normals = false;
    Sculpt b = Sculpt::from_function(d, ScalarType::F32, balls(d, 1, 0), o);
    b.add({15, 10, 14}, 6, 2);
    b.update();
    REQUIRE(b.mesh().normals.empty());
    require_equals_extract(b);
}

TEST_CASE("sculpt: random edit sequences stay equal to a full extract", "[sculpt]") {
    const Dims d{44, 40, 48};
    for (const TypeSetup& ts : kTypes) {
        for (std::uint32_t seed : {1u, 2u, 3u}) {
            INFO(voxmesh::scalar_name(ts.type) << " seed " << seed);
            std::mt19937 rng(seed);
            Sculpt s = make(ts, d, 8, seed);  // 1..3 worker threads
            s.update();
            for (int step = 0; step < 14; ++step) {
                const int dabs = 1 + static_cast<int>(rng() % 3);  // sometimes several dabs per update
                for (int k = 0; k < dabs; ++k) {
                    const Dab dab = random_dab(rng, d, -6, 9, ts.scale, ts.offset);
                    INFO("step " << step << " " << voxmesh::brush_op_name(dab.op) << " at " << dab.center[0] << ","
                                 << dab.center[1] << "," << dab.center[2] << " r " << dab.radius);
                    s.apply(dab);
                }
                const auto r = s.update();
                REQUIRE(r.changed.size() <= r.remeshed);
                require_equals_extract(s);
                if (step % 4 == 3) {
                    require_blocks_match_fresh(s);
                    require_blocks_cover_extract(s);
                }
            }
        }
    }
}

TEST_CASE("sculpt: closed models stay closed 2-manifolds under interior edits", "[sculpt]") {
    const Dims d{48, 48, 48};
    for (const TypeSetup& ts : kTypes) {
        INFO(voxmesh::scalar_name(ts.type));
        std::mt19937 rng(42);
        Sculpt s = make(ts, d, 8);
        for (int step = 0; step < 12; ++step) {
            s.apply(random_dab(rng, d, 1, 8, ts.scale, ts.offset));  // never touches the border samples
            s.update();
            const Mesh m = s.mesh();
            const auto topo = voxmesh::analyze_topology(m);
            REQUIRE(topo.closed());
            REQUIRE(m.triangle_count() > 0);
        }
        require_equals_extract(s);
    }
}

TEST_CASE("sculpt: an edit at a block corner re-meshes all 8 blocks around it", "[sculpt]") {
    // A ball centred on the corner sample (8, 8, 8) shared by blocks (0|1, 0|1, 0|1).
    const Dims d{24, 24, 24};
    SculptOptions o;
    o.block_size = 8;
    Sculpt s = Sculpt::from_function(
        d, ScalarType::F32,
        [](double x, double y, double z) { return 3.3 - std::sqrt((x - 8) * (x - 8) + (y - 8) * (y - 8) + (z - 8) * (z - 8)); },
        o);
    s.update();
    s.set_region({8, 8, 8}, {8, 8, 8}, -0.5);  // one sample: the corner
    const auto r = s.update();
    std::vector<std::size_t> want;
    for (std::size_t z = 0; z < 2; ++z)
        for (std::size_t y = 0; y < 2; ++y)
            for (std::size_t x = 0; x < 2; ++x) want.push_back(x + 3 * (y + 3 * z));
    REQUIRE(r.changed == want);
    REQUIRE(r.remeshed == 8);
    require_blocks_match_fresh(s);
    require_equals_extract(s);

    // A brush dab centred on the corner as well.
    s.add({8, 8, 8}, 2.5, 1);
    REQUIRE(s.update().changed == want);
    require_blocks_match_fresh(s);
}

TEST_CASE("sculpt: a single changed sample anywhere near block borders never misses a block", "[sculpt]") {
    // Every sample in a 5^3 neighbourhood of a block corner, each changed alone: the normals'
    // one-sample margin reaches the neighbouring blocks.
    const Dims d{20, 20, 20};
    SculptOptions o;
    o.block_size = 6;
    const auto f = [](double x, double y, double z) {
        return 0.2 + std::sin(0.9 * x + 0.3) * std::cos(0.8 * y - 0.2) + 0.7 * std::sin(1.1 * z + 0.5 * x);
    };
    Sculpt s = Sculpt::from_function(d, ScalarType::F32, f, o);
    s.update();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> value(-1.5, 1.5);
    for (std::size_t z = 4; z <= 8; ++z)
        for (std::size_t y = 4; y <= 8; ++y)
            for (std::size_t x = 4; x <= 8; ++x) {
                const std::array<double, 3> p{double(x), double(y), double(z)};
                s.set_region(p, p, value(rng));
                s.update();
                INFO("sample " << x << "," << y << "," << z);
                if ((x + y + z) % 4 == 0) require_blocks_match_fresh(s);
            }
    require_blocks_match_fresh(s);
    require_equals_extract(s);
}

TEST_CASE("sculpt: edits outside the volume are clipped", "[sculpt]") {
    const Dims d{26, 22, 30};
    Sculpt s = make(kTypes[0], d, 8);
    s.update();
    // Entirely outside: nothing changes, nothing is dirty.
    s.add({-50, 10, 10}, 5, 3);
    s.subtract({10, 1e9, 10}, 100, 3);
    s.smooth({10, 10, -1e300}, 4, 1);
    s.set_region({30, 0, 0}, {40, 10, 10}, 5);
    s.set_region({10, 10, 10}, {5, 5, 5}, 5);  // lo > hi: empty
    s.apply(Dab{BrushOp::Set, {-10, -10, -10}, 4, 2});
    REQUIRE_FALSE(s.dirty());
    REQUIRE(s.update().remeshed == 0);
    // Partly outside: clipped to the volume.
    s.add({-2, 11, 15}, 6, 3);
    s.subtract({25.5, 21.5, 29.5}, 7, 4);
    s.smooth({0, 0, 0}, 8, 1);
    s.set_region({-100, -100, 20}, {100, 3, 100}, 1.5);
    s.apply(Dab{BrushOp::Set, {30, 25, 33}, 6, -2});
    s.add({13, 11, 15}, 1e6, 0.5);  // covers everything
    REQUIRE(s.dirty());
    s.update();
    require_equals_extract(s);
    require_blocks_match_fresh(s);
    // Bad parameters are errors, not crashes.
    REQUIRE_THROWS_AS(s.add({1, 2, 3}, 0, 1), voxmesh::Error);
    REQUIRE_THROWS_AS(s.add({1, 2, 3}, -1, 1), voxmesh::Error);
    REQUIRE_THROWS_AS(s.add({NAN, 2, 3}, 2, 1), voxmesh::Error);
    REQUIRE_THROWS_AS(s.add({1, 2, 3}, INFINITY, 1), voxmesh::Error);
    REQUIRE_THROWS_AS(s.subtract({1, 2, 3}, 2, NAN), voxmesh::Error);
    REQUIRE_THROWS_AS(s.set_region({0, 0, 0}, {1, 1, 1}, INFINITY), voxmesh::Error);
    // An op that is none of the four (a cast integer) is refused, not applied as Add.
    REQUIRE_THROWS_WITH(s.apply(Dab{static_cast<BrushOp>(7), {1, 2, 3}, 2, 1}), Catch::Contains("unknown brush op 7"));
    REQUIRE_FALSE(s.dirty());
}

TEST_CASE("sculpt: integer volumes clamp, floats stay finite", "[sculpt]") {
    const Dims d{20, 20, 20};
    Sculpt u = make(kTypes[1], d, 8);
    u.add({10, 10, 10}, 6, 1e6);
    u.subtract({4, 4, 4}, 6, 1e6);
    u.update();
    require_equals_extract(u);
    Sculpt f = make(kTypes[0], d, 8);
    f.add({10, 10, 10}, 6, 1e300);
    f.subtract({12, 10, 10}, 6, 1e300);
    f.smooth({11, 10, 10}, 6, 1);
    f.update();
    const float* p = static_cast<const float*>(f.view().data);
    for (std::size_t i = 0; i < 20 * 20 * 20; ++i) REQUIRE(std::isfinite(p[i]));
    require_equals_extract(f);

    // A radius whose inverse overflows, centred on a sample, and a strength times scale that
    // overflows: they wrote NaN (0 * inf at the centre, inf * a falloff that underflows to 0).
    const float before = p[5 + 20 * (5 + 20 * 5)];
    f.add({5, 5, 5}, 1e-320, 1);
    CHECK(p[5 + 20 * (5 + 20 * 5)] > before);  // the sample it sits on, at full weight
    SculptOptions huge = f.options();
    huge.strength_scale = 1e300;
    Sculpt g = Sculpt::from_function(d, ScalarType::F32, [](double x, double, double) { return x - 10; }, huge);
    g.add({10, 10, 10}, 6, 1e300);
    g.subtract({3, 10, 10}, 6, 1e300);
    g.update();
    const float* q = static_cast<const float*>(g.view().data);
    for (std::size_t i = 0; i < 20 * 20 * 20; ++i) {
        REQUIRE(std::isfinite(p[i]));
        REQUIRE(std::isfinite(q[i]));
    }
    f.update();
    require_equals_extract(f);
    require_equals_extract(g);
}

TEST_CASE("sculpt: world units map through origin and spacing", "[sculpt]") {
    const Dims d{24, 24, 24};
    std::vector<float> samples(d[0] * d[1] * d[2]);
    const auto f = balls(d, 1, 0);
    for (std::size_t z = 0, i = 0; z < d[2]; ++z)
        for (std::size_t y = 0; y < d[1]; ++y)
            for (std::size_t x = 0; x < d[0]; ++x) samples[i++] = static_cast<float>(f(double(x), double(y), double(z)));
    voxmesh::VolumeView v;
    v.data = samples.data();
    v.type = ScalarType::F32;
    v.dims = d;
    v.spacing = {0.5, 0.5, 0.5};
    v.origin = {10, -3, 2};
    SculptOptions o;
    o.block_size = 8;
    Sculpt a(v, o), b(v, o);
    a.add({10 + 0.5 * 11, -3 + 0.5 * 12, 2 + 0.5 * 4}, 0.5 * 5, 2, voxmesh::Units::World);
    b.add({11, 12, 4}, 5, 2);
    a.update();
    b.update();
    REQUIRE(a.mesh().indices == b.mesh().indices);
    require_equals_extract(a);
    const auto p = a.to_samples({10, -3, 2});
    REQUIRE(p == std::array<double, 3>{0, 0, 0});
}

TEST_CASE("sculpt: construction errors", "[sculpt]") {
    std::vector<std::int16_t> i16(8 * 8 * 8);
    voxmesh::VolumeView v;
    v.data = i16.data();
    v.type = ScalarType::I16;
    v.dims = {8, 8, 8};
    REQUIRE_THROWS_WITH(Sculpt(v), Catch::Contains("u8, u16 or f32"));
    std::vector<float> f(8 * 8 * 8, 1.0f);
    f[100] = NAN;
    v.data = f.data();
    v.type = ScalarType::F32;
    REQUIRE_THROWS_WITH(Sculpt(v), Catch::Contains("NaN") && Catch::Contains("z-plane 1)"));  // sample 100: z 1
    f[100] = INFINITY;
    REQUIRE_THROWS_WITH(Sculpt(v), Catch::Contains("infinite"));
    f[100] = 0;
    SculptOptions o;
    o.block_size = 1;
    REQUIRE_THROWS_AS(Sculpt(v, o), voxmesh::Error);
    SculptOptions bad_device;
    bad_device.device = -5;  // only -1 means "choose one"; it used to be treated like -1
    REQUIRE_THROWS_WITH(Sculpt(v, bad_device), Catch::Contains("device") && Catch::Contains("-5"));
    bad_device.backend = voxmesh::Backend::Auto;
    REQUIRE_THROWS_WITH(Sculpt(v, bad_device), Catch::Contains("device") && Catch::Contains("-5"));
    v.dims = {1, 8, 8};
    REQUIRE_THROWS_AS(Sculpt(v), voxmesh::Error);
    REQUIRE_THROWS_AS(Sculpt::from_function({8, 8, 8}, ScalarType::F32, [](double, double, double) { return NAN; }),
                      voxmesh::Error);
    // NaN written through data(): invalidate_all refuses it (update() meshed it silently).
    v.dims = {8, 8, 8};
    Sculpt g(v);
    g.update();
    static_cast<float*>(g.data())[100] = NAN;
    REQUIRE_THROWS_WITH(g.invalidate_all(), Catch::Contains("NaN"));
    static_cast<float*>(g.data())[100] = 2;
    g.invalidate_all();
    REQUIRE(g.dirty());
    // iso outside the type's range: never a surface, never a crash.
    SculptOptions high;
    high.iso = 300;
    Sculpt u = Sculpt::from_function({10, 10, 10}, ScalarType::U8, [](double x, double, double) { return x * 20; }, high);
    u.update();
    REQUIRE(u.mesh().triangle_count() == 0);
}

TEST_CASE("sculpt: block meshes cost at most the full mesh + 10 %", "[sculpt]") {
    SculptOptions o;
    o.threads = 2;
    Sculpt s = voxmesh::make_sculpt_sphere(128, o);  // block size 32 (the default)
    s.update();
    auto check = [&] {
        const Mesh m = s.mesh();
        const double full = 4.0 * double(m.positions.size() + m.normals.size() + m.indices.size());
        const auto mem = s.memory();
        INFO("block meshes " << mem.block_meshes << " table " << mem.block_table << " full " << full);
        REQUIRE(double(mem.block_meshes + mem.block_table) <= 1.10 * full);
    };
    check();
    for (const auto& d : voxmesh::builtin_stroke_path(60, {128, 128, 128}, 4, 8)) s.apply(d.dab);
    s.update();
    check();
}

TEST_CASE("sculpt: brush values (falloff, smoothing reads old values only)", "[sculpt]") {
    const Dims d{12, 12, 12};
    SculptOptions o;
    o.block_size = 4;
    o.iso = 0.5;
    Sculpt s = Sculpt::from_function(d, ScalarType::F32, [](double, double, double) { return 0.0; }, o);
    const float* v = static_cast<const float*>(s.view().data);
    auto at = [&](std::size_t x, std::size_t y, std::size_t z) { return double(v[x + 12 * (y + 12 * z)]); };
    s.add({5, 5, 5}, 2, 3);
    CHECK(at(5, 5, 5) == Approx(3));
    CHECK(at(6, 5, 5) == Approx(3 * std::pow(1 - 0.25, 3)));
    CHECK(at(7, 5, 5) == 0);  // on the radius: falloff 0
    s.subtract({5, 5, 5}, 2, 3);
    CHECK(at(5, 5, 5) == Approx(0).margin(1e-6));

    s.set_region({5, 5, 5}, {5, 5, 5}, 12);
    s.smooth({5, 5, 5}, 3, 1);
    const double w1 = std::pow(1 - 1.0 / 9, 3);
    CHECK(at(5, 5, 5) == Approx(0).margin(1e-6));  // all six neighbours were 0
    for (const auto& p : {std::array<std::size_t, 3>{4, 5, 5}, {6, 5, 5}, {5, 4, 5}, {5, 6, 5}, {5, 5, 4}, {5, 5, 6}})
        CHECK(at(p[0], p[1], p[2]) == Approx(w1 * 2));  // one neighbour (the old spike) was 12
    CHECK(at(5, 5, 8) == 0);

    // Smoothing at the volume's corner: neighbours beyond the border are the sample itself.
    s.set_region({0, 0, 0}, {0, 0, 0}, 6);
    s.smooth({0, 0, 0}, 2, 1);
    CHECK(at(0, 0, 0) == Approx(6 + (3 * 6.0 / 6 - 6)));  // mean of (6, 6, 6, 0, 0, 0)
    s.update();
    require_equals_extract(s);
}
