// The OpenCL engine against the CPU engine (the canonical mesh), on PoCL in CI.
// Every test returns with a visible WARN when no OpenCL device is present.
#include <catch2/catch.hpp>
#include <voxmesh/voxmesh.hpp>

#include "core/case_tables.hpp"
#include "core/opencl_hook.hpp"
#include "core/parallel.hpp"
#include "support/child_process.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <sys/mman.h>

#ifdef VOXMESH_HAS_OPENCL
#include "support/cl_fault.hpp"
#endif

using namespace voxmesh;

namespace {

bool have_device() {
    if (!list_devices().empty()) return true;
    WARN("no OpenCL device found: this [opencl] test is SKIPPED");
    return false;
}

struct Grid {
    std::array<std::size_t, 3> dims;
    std::array<double, 3> spacing{1, 1, 1};
    std::array<double, 3> origin{0, 0, 0};
    std::size_t size() const { return dims[0] * dims[1] * dims[2]; }
};

// A float field from f(x, y, z) in [0,1]^3 coordinates.
template <class F>
std::vector<float> sample(const Grid& g, F f) {
    std::vector<float> v(g.size());
    std::size_t i = 0;
    for (std::size_t z = 0; z < g.dims[2]; ++z)
        for (std::size_t y = 0; y < g.dims[1]; ++y)
            for (std::size_t x = 0; x < g.dims[0]; ++x)
                v[i++] = f(double(x) / double(g.dims[0] - 1), double(y) / double(g.dims[1] - 1),
                           double(z) / double(g.dims[2] - 1));
    return v;
}

std::vector<float> sphere(const Grid& g) {  // 0.35 - distance from the centre: inside >= 0
    return sample(g, [](double x, double y, double z) {
        return float(0.35 - std::sqrt((x - .5) * (x - .5) + (y - .52) * (y - .52) + (z - .49) * (z - .49)));
    });
}
std::vector<float> torus(const Grid& g) {
    return sample(g, [](double x, double y, double z) {
        const double q = std::sqrt((x - .5) * (x - .5) + (y - .5) * (y - .5)) - 0.3;
        return float(0.12 - std::sqrt(q * q + (z - .5) * (z - .5)));
    });
}
std::vector<float> gyroid(const Grid& g) {
    return sample(g, [](double x, double y, double z) {
        const double s = 4 * M_PI;
        return float(std::sin(s * x) * std::cos(s * y) + std::sin(s * y) * std::cos(s * z) +
                     std::sin(s * z) * std::cos(s * x));
    });
}

template <class T>
std::vector<T> to_type(const std::vector<float>& f, double scale, double offset) {
    std::vector<T> out(f.size());
    for (std::size_t i = 0; i < f.size(); ++i) out[i] = static_cast<T>(std::lround(f[i] * scale + offset));
    return out;
}

VolumeView view_of(const void* data, ScalarType type, const Grid& g) {
    VolumeView v;
    v.data = data;
    v.type = type;
    v.dims = g.dims;
    v.spacing = g.spacing;
    v.origin = g.origin;
    return v;
}

double extent(const VolumeView& v) {
    double e = 0;
    for (int d = 0; d < 3; ++d) e = std::max(e, double(v.dims[d] - 1) * v.spacing[d]);
    return e;
}

// The OpenCL mesh must be the CPU engine's: same index buffer, positions within 1e-5 of the
// extent, normals within 1e-3.
void require_same(const Mesh& cpu, const Mesh& cl, const VolumeView& v) {
    REQUIRE(cl.indices.size() == cpu.indices.size());
    REQUIRE(cl.positions.size() == cpu.positions.size());
    REQUIRE(cl.normals.size() == cpu.normals.size());
    const auto mismatch = std::mismatch(cpu.indices.begin(), cpu.indices.end(), cl.indices.begin());
    INFO("first differing index at " << (mismatch.first - cpu.indices.begin()));
    REQUIRE(mismatch.first == cpu.indices.end());
    double pos = 0, nrm = 0;
    for (std::size_t i = 0; i < cpu.positions.size(); ++i)
        pos = std::max(pos, double(std::abs(cpu.positions[i] - cl.positions[i])));
    for (std::size_t i = 0; i < cpu.normals.size(); ++i)
        nrm = std::max(nrm, double(std::abs(cpu.normals[i] - cl.normals[i])));
    CHECK(pos <= 1e-5 * extent(v));
    CHECK(nrm <= 1e-3);
}

Mesh run(const VolumeView& v, Options o, Backend backend, Stats* stats = nullptr) {
    o.backend = backend;
    Stats s;
    Mesh m = extract(v, o, s);
    if (stats) *stats = s;
    return m;
}

void compare(const VolumeView& v, const Options& o) {
    const Mesh cpu = run(v, o, Backend::Cpu);
    Stats stats;
    const Mesh cl = run(v, o, Backend::OpenCL, &stats);
    CHECK(stats.backend == Backend::OpenCL);
    require_same(cpu, cl, v);
}

#ifdef VOXMESH_HAS_OPENCL  // for the tests that use the OpenCL build's hooks
bool has_warning(const Stats& stats, const std::string& text) {
    for (const std::string& w : stats.warnings)
        if (w.find(text) != std::string::npos) return true;
    return false;
}

// A u8 volume of zeros in the shared zero page, never written: a large one costs no memory.
class ZeroVolume {
public:
    explicit ZeroVolume(std::array<std::size_t, 3> dims) : bytes_(dims[0] * dims[1] * dims[2]) {
        data_ = mmap(nullptr, bytes_, PROT_READ, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
        REQUIRE(data_ != MAP_FAILED);
        view_.data = data_;
        view_.type = ScalarType::U8;
        view_.dims = dims;
    }
    ~ZeroVolume() { munmap(data_, bytes_); }
    ZeroVolume(const ZeroVolume&) = delete;
    ZeroVolume& operator=(const ZeroVolume&) = delete;
    const VolumeView& view() const { return view_; }

private:
    std::size_t bytes_;
    void* data_ = nullptr;
    VolumeView view_;
};
#endif

}  // namespace

TEST_CASE("OpenCL matches the CPU engine on sphere, torus and gyroid", "[opencl]") {
    if (!have_device()) return;
    Grid g{{41, 37, 33}, {0.5, 0.75, 1.25}, {-3, 2, 7.5}};
    const std::vector<float> fields[] = {sphere(g), torus(g), gyroid(g)};
    for (const auto& f : fields) {
        const VolumeView v = view_of(f.data(), ScalarType::F32, g);
        Options o;
        o.iso = 0.0;
        compare(v, o);
        o.iso = 0.05;
        o.inside_below = true;
        compare(v, o);
        o.normals = false;
        compare(v, o);
    }
    const Mesh m = run(view_of(fields[0].data(), ScalarType::F32, g), Options{}, Backend::OpenCL);
    const MeshTopology topo = analyze_topology(m);
    CHECK(topo.closed());
    CHECK(topo.euler == 2);
}

// A gyroid on grid g as every scalar type, each at a threshold between its values and (u8)
// one on them.
void compare_every_scalar_type(const Grid& g) {
    const std::vector<float> f = gyroid(g);  // in [-1.5, 1.5]
    Options o;
    auto check = [&](const void* data, ScalarType type, double iso) {
        INFO("type " << scalar_name(type) << " iso " << iso);
        o.iso = iso;
        compare(view_of(data, type, g), o);
    };
    const auto u8 = to_type<std::uint8_t>(f, 80, 128);
    const auto i8 = to_type<std::int8_t>(f, 80, 0);
    const auto u16 = to_type<std::uint16_t>(f, 20000, 32768);
    const auto i16 = to_type<std::int16_t>(f, 20000, 0);
    const auto u32 = to_type<std::uint32_t>(f, 1.4e9, 2.1e9);  // large values: exact integer differences matter
    const auto i32 = to_type<std::int32_t>(f, 1.4e9, 0);
    std::vector<double> f64(f.begin(), f.end());
    for (double& d : f64) d = d * 1e-3 + 1e-12 * d;  // not representable as floats
    check(u8.data(), ScalarType::U8, 140.5);
    check(u8.data(), ScalarType::U8, 128);
    check(i8.data(), ScalarType::I8, -3.25);
    check(u16.data(), ScalarType::U16, 33000.7);
    check(i16.data(), ScalarType::I16, -1234.5);
    check(u32.data(), ScalarType::U32, 2.3e9 + 0.5);
    check(i32.data(), ScalarType::I32, -1.0e8 - 0.25);
    check(f.data(), ScalarType::F32, 0.3);
    check(f64.data(), ScalarType::F64, 2e-4);
}

TEST_CASE("OpenCL matches the CPU engine for every scalar type", "[opencl]") {
    if (!have_device()) return;
    const Grid g{{29, 31, 27}, {1, 0.5, 2}, {1, 2, 3}};
    compare_every_scalar_type(g);
    // A threshold no sample reaches: an empty mesh, as the CPU engine.
    const auto u8 = to_type<std::uint8_t>(gyroid(g), 80, 128);
    Options o;
    o.iso = 300;
    const Mesh empty = run(view_of(u8.data(), ScalarType::U8, g), o, Backend::OpenCL);
    CHECK(empty.indices.empty());
    CHECK(empty.positions.empty());
}

#ifdef VOXMESH_HAS_OPENCL  // uses test hooks of the OpenCL build
// Turns one of the engine's on/off test hooks on for a scope.
class Pretend {
public:
    explicit Pretend(void (*hook)(bool)) : hook_(hook) { hook_(true); }
    ~Pretend() { hook_(false); }
    Pretend(const Pretend&) = delete;
    Pretend& operator=(const Pretend&) = delete;

private:
    void (*hook_)(bool);
};

// What a GPU compiles: the kernels without the CPU-only hints (row prefetches, and pack16's
// lane masks by multiplies instead of the x86 builtin), which PoCL otherwise never builds, and
// the scans in GPU work-groups (256 items of 8 where PoCL's are 1 of 1024).
// Rows of 70 samples: two whole words (pack_word) and a partial one; 64 x 40 rows, more than
// one GPU scan block of 2048 where the volume is one chunk; with and without copies.
TEST_CASE("OpenCL's kernels as built for a GPU match the CPU engine for every scalar type", "[opencl]") {
    if (!have_device()) return;
    const Pretend gpu(detail::opencl_pretend_gpu_build);
    const Grid g{{70, 64, 40}, {0.5, 1, 1.5}, {-1, 0, 2}};
    compare_every_scalar_type(g);
    const Pretend discrete(detail::opencl_pretend_discrete);
    compare_every_scalar_type(g);
}

// Makes the device and Hybrid's CPU worker slower for a scope (detail::opencl_pretend_slow).
struct Slow {
    Slow(double device_count_s, double device_generate_s, double cpu_count_s, double cpu_start_s = 0) {
        detail::opencl_pretend_slow(device_count_s, device_generate_s, cpu_count_s, cpu_start_s);
    }
    ~Slow() { detail::opencl_pretend_slow(0, 0, 0); }
    Slow(const Slow&) = delete;
    Slow& operator=(const Slow&) = delete;
};

TEST_CASE("OpenCL without fp64 (float interpolation, f64 converted per chunk) matches the CPU engine", "[opencl]") {
    if (!have_device()) return;
    const Pretend no_fp64(detail::opencl_pretend_no_fp64);
    Grid g{{27, 23, 25}, {0.5, 1, 1.5}, {-10, 5, 2}};
    const std::vector<float> f = gyroid(g);
    Options o;
    o.iso = 0.2;
    compare(view_of(f.data(), ScalarType::F32, g), o);
    const auto u32 = to_type<std::uint32_t>(f, 1.4e9, 2.1e9);
    o.iso = 2.3e9 + 0.5;
    compare(view_of(u32.data(), ScalarType::U32, g), o);
    const auto i16 = to_type<std::int16_t>(f, 20000, 0);
    o.iso = -1234.5;
    compare(view_of(i16.data(), ScalarType::I16, g), o);
    // f64 samples a hair either side of iso: the conversion to float must keep every inside bit.
    std::vector<double> f64(f.size());
    for (std::size_t i = 0; i < f.size(); ++i) f64[i] = 0.25 + (f[i] > 0.2f ? 1e-12 : -1e-12) * (1 + f[i]) + 1e-3 * f[i];
    o.iso = 0.25;
    compare(view_of(f64.data(), ScalarType::F64, g), o);
}

// An edge between samples near -max and +max: the difference overflows, and t was NaN.
TEST_CASE("OpenCL gives the CPU engine's vertices for samples near the ends of the float and double range",
          "[opencl]") {
    if (!have_device()) return;
    Grid g{{2, 2, 2}};
    const double dmax = std::numeric_limits<double>::max();
    const float fmax = std::numeric_limits<float>::max();
    std::vector<double> f64(8, -dmax);
    std::vector<float> f32(8, -fmax);
    f64[7] = dmax;
    f32[7] = fmax;
    Options o;
    for (double iso : {0.0, 1e38}) {
        o.iso = iso;
        INFO("iso " << iso);
        compare(view_of(f64.data(), ScalarType::F64, g), o);
        compare(view_of(f32.data(), ScalarType::F32, g), o);
        // In float the gradients overflow too: the normals fall back to the edge's axis where
        // the CPU's double gradients do not, so only positions are compared.
        const Pretend no_fp64(detail::opencl_pretend_no_fp64);
        const Mesh cpu = run(view_of(f32.data(), ScalarType::F32, g), o, Backend::Cpu);
        for (const ScalarType type : {ScalarType::F32, ScalarType::F64}) {
            const Mesh m = run(view_of(type == ScalarType::F32 ? static_cast<const void*>(f32.data()) : f64.data(), type, g),
                               o, Backend::OpenCL);
            CHECK(m.indices == cpu.indices);
            REQUIRE(m.positions.size() == cpu.positions.size());
            for (float n : m.normals) CHECK(std::isfinite(n));
            if (type == ScalarType::F32)  // f64 is clamped to float on the way: other t's
                for (std::size_t i = 0; i < m.positions.size(); ++i) CHECK(m.positions[i] == Approx(cpu.positions[i]).margin(1e-6));
            for (float p : m.positions) CHECK(std::isfinite(p));
        }
    }
}

// Found by a review: |n|^2 overflowed or lost its precision for gradients near the ends of the
// range (f64 samples scaled by 1e160 or 1e-162 on every engine; f32 samples scaled by 1e20 or
// 1e-22 on a device without fp64), and the normals fell back to an edge's axis or came out of
// unit length. Scaled first, they are the unscaled field's directions.
TEST_CASE("normals of gradients near the ends of the range are unit, on the CPU and OpenCL", "[opencl]") {
    Grid g{{24, 24, 24}};
    const std::vector<float> unit_field = sample(g, [](double x, double y, double z) {
        return float(0.35 - std::sqrt((x - 0.5) * (x - 0.5) + (y - 0.45) * (y - 0.45) + (z - 0.55) * (z - 0.55)));
    });
    Options o;
    const Mesh reference = run(view_of(unit_field.data(), ScalarType::F32, g), o, Backend::Cpu);
    REQUIRE(reference.triangle_count() > 500);
    const auto check_normals = [&](const Mesh& m) {
        REQUIRE(m.indices == reference.indices);
        double off = 0;
        for (std::size_t v = 0; v < m.vertex_count(); ++v) {
            const float* n = &m.normals[3 * v];
            CHECK(std::abs(std::hypot(n[0], n[1], n[2]) - 1) < 1e-5);
            for (int d = 0; d < 3; ++d) off = std::max(off, double(std::abs(n[d] - reference.normals[3 * v + d])));
        }
        CHECK(off < 1e-3);
    };
    const bool device = have_device();
    for (const double scale : {1e160, 1e-162, 1e-300}) {
        INFO("f64 samples x " << scale);
        std::vector<double> f64(unit_field.size());
        for (std::size_t i = 0; i < f64.size(); ++i) f64[i] = unit_field[i] * scale;
        const VolumeView v = view_of(f64.data(), ScalarType::F64, g);
        const Mesh cpu = run(v, o, Backend::Cpu);
        check_normals(cpu);
        if (!device) continue;
        const Mesh cl = run(v, o, Backend::OpenCL);
        check_normals(cl);
        if (list_devices()[0].fp64) CHECK(cl.normals == cpu.normals);  // the same operations in double
    }
    if (!device) return;
    const Pretend no_fp64(detail::opencl_pretend_no_fp64);
    for (const float scale : {1e20f, 1e-22f, 1e-30f}) {
        INFO("f32 samples x " << scale << " without fp64");
        std::vector<float> f32(unit_field.size());
        for (std::size_t i = 0; i < f32.size(); ++i) f32[i] = unit_field[i] * scale;
        const VolumeView v = view_of(f32.data(), ScalarType::F32, g);
        check_normals(run(v, o, Backend::Cpu));
        check_normals(run(v, o, Backend::OpenCL));
    }
}

// Found by a review: the kernels took a gradient as (hi - lo) * 0.5 * (1 / spacing), two
// roundings, where the CPU takes (hi - lo) * (0.5 / spacing), one. They differ where hi - lo is
// subnormal (f64 samples near 1e-310) and the spacing is not 1: normals turned by up to 90
// degrees on a device with fp64, whose normals are to be the CPU's bit for bit.
TEST_CASE("OpenCL normals of subnormal gradients with non-unit spacing are the CPU's", "[opencl]") {
    if (!have_device() || !list_devices()[0].fp64) return;
    // Samples a few multiples of the smallest subnormal: central differences in z are odd
    // multiples of it, which halving before the spacing's factor rounds.
    const double dm = std::numeric_limits<double>::denorm_min();
    Grid g{{5, 5, 5}, {0.5, 0.5, 0.5}};
    std::vector<double> f64(g.size());
    for (std::size_t z = 0; z < 5; ++z)
        for (std::size_t y = 0; y < 5; ++y)
            for (std::size_t x = 0; x < 5; ++x) f64[x + 5 * (y + 5 * z)] = dm * double(4 * x + z * (z + 1) / 2);
    const VolumeView v = view_of(f64.data(), ScalarType::F64, g);
    Options o;
    o.iso = 9 * dm;
    const Mesh cpu = run(v, o, Backend::Cpu);
    REQUIRE(cpu.vertex_count() == 35);
    const Mesh cl = run(v, o, Backend::OpenCL);
    REQUIRE(cl.indices == cpu.indices);
    CHECK(cl.positions == cpu.positions);
    CHECK(cl.normals == cpu.normals);  // the same operations in double (25 of 35 differed by 4 degrees)
}

// Found by a review: the kernels count a chunk's vertices and triangles in 32 bits (the scans),
// and the host took any chunk of up to 2^31 samples: one with more than 2^32 - 1 triangles or
// vertices (a dense surface in 860 M cells) wrapped its counts and came out short, silently.
// A chunk is now cut until no surface can overflow them: 1024^3 samples asked for as one chunk
// (5.4 G triangles at most) run as smaller ones.
TEST_CASE("OpenCL cuts a chunk whose triangles could overflow the kernels' 32-bit counts", "[opencl][large]") {
    if (!have_device()) return;
    const std::size_t n = 1024;
    const ZeroVolume zeros({n, n, n});
    Options o;
    o.iso = 0.5;
    o.normals = false;
    o.chunk_planes = n;
    o.devices = {0};
    Stats stats;
    const Mesh m = run(zeros.view(), o, Backend::OpenCL, &stats);
    CHECK(m.triangle_count() == 0);
    CHECK(stats.backend == Backend::OpenCL);
    CHECK(has_warning(stats, "1024-plane chunk does not fit"));
}

// Found by a review: a one-plane chunk cut for its 32-bit counts alone (27000^2 samples a plane,
// two planes: 1.4 GB, which the device holds) ran on the CPU with a warning blaming memory.
TEST_CASE("OpenCL names the 32-bit counts when even one plane cannot be meshed on the device", "[opencl][large]") {
    if (!have_device()) return;
    const std::size_t n = 27000;
    const ZeroVolume zeros({n, n, 2});
    Options o;
    o.iso = 0.5;
    o.normals = false;
    o.devices = {0};
    Stats stats;
    const Mesh m = run(zeros.view(), o, Backend::OpenCL, &stats);
    CHECK(m.triangle_count() == 0);
    CHECK(has_warning(stats, "cannot hold even one z-plane of this volume within the kernels' 32-bit vertex and triangle counts"));
    CHECK(!has_warning(stats, "memory limits"));
}

// Found by a review: without fp64 the kernels took iso as a float, so an iso between two
// adjacent floats (1 + 2^-24, between 1 and its next float) was rounded onto one of them and a
// vertex moved by half a cell. What rounding left is now added back.
TEST_CASE("OpenCL without fp64 places an iso between two adjacent floats where it lies", "[opencl]") {
    if (!have_device()) return;
    const Pretend no_fp64(detail::opencl_pretend_no_fp64);
    Grid g{{4, 4, 4}};
    std::vector<float> f(g.size());
    for (std::size_t i = 0; i < f.size(); ++i) f[i] = i % 4 < 2 ? 1.0f : std::nextafter(1.0f, 2.0f);
    Options o;
    o.iso = 1 + std::ldexp(1.0, -24);
    o.inside_below = true;
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, o, Backend::Cpu);
    REQUIRE(cpu.vertex_count() > 0);
    CHECK(cpu.positions[0] == 1.5f);
    require_same(cpu, run(v, o, Backend::OpenCL), v);
}

// Copies go through two pinned blocks in turns: with the default blocks (one per copy here)
// and with blocks of 1000 bytes, not a multiple of a sample or a vertex, so that every upload
// and read-back runs through many of them.
TEST_CASE("OpenCL with copies in and out (a discrete GPU's path) matches the CPU engine", "[opencl]") {
    if (!have_device()) return;
    const Pretend discrete(detail::opencl_pretend_discrete);
    struct Blocks {
        ~Blocks() { detail::opencl_staging_block_bytes(0); }
    } restore;
    Grid g{{45, 38, 41}, {1, 0.75, 1.25}, {2, -3, 1}};
    const std::vector<float> f = torus(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    for (std::size_t block : {0, 1000}) {
        detail::opencl_staging_block_bytes(block);
        for (std::size_t planes : {0, 6}) {  // one chunk; several, each copied out into its place
            INFO("pinned block bytes " << block << ", chunk_planes " << planes);
            Options o;
            o.chunk_planes = planes;
            compare(v, o);
            const auto u16 = to_type<std::uint16_t>(f, 3000, 1000);
            o.iso = 1100.5;
            compare(view_of(u16.data(), ScalarType::U16, g), o);
            o.normals = false;
            compare(view_of(u16.data(), ScalarType::U16, g), o);
            const auto u8 = to_type<std::uint8_t>(f, 100, 120);
            o.iso = 120.5;
            compare(view_of(u8.data(), ScalarType::U8, g), o);
        }
        Options o;
        o.devices = {0};
        o.chunk_planes = 3;
        require_same(run(v, Options{}, Backend::Cpu), run(v, o, Backend::Hybrid), v);
    }
    // A budget of about 10 planes a chunk: the first chunks stay resident between counting
    // and generating, the later ones do not fit beside them and are uploaded and packed again.
    detail::opencl_staging_block_bytes(0);
    Options o;
    o.memory_budget = 45 * 38 * 4 * 2 * 12;
    Stats stats;
    require_same(run(v, o, Backend::Cpu), run(v, o, Backend::OpenCL, &stats), v);
    REQUIRE(stats.devices.size() == 1);
    CHECK(stats.devices[0].chunks >= 4);
}

// The devices keep their buffers (and, copying in and out, two pinned blocks) from call to
// call; release_scratch_memory() lets them go, and the next call makes them again.
TEST_CASE("release_scratch_memory frees what the OpenCL devices keep between calls", "[opencl]") {
    if (!have_device()) return;
    const Pretend discrete(detail::opencl_pretend_discrete);
    Grid g{{45, 38, 41}};
    const std::vector<float> f = torus(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    require_same(cpu, run(v, Options{}, Backend::OpenCL), v);
    const std::size_t kept = detail::opencl_kept_bytes();
    CHECK(kept >= g.size() * sizeof(float));  // the samples' buffer at least
    release_scratch_memory();
    CHECK(detail::opencl_kept_bytes() == 0);
    require_same(cpu, run(v, Options{}, Backend::OpenCL), v);
    CHECK(detail::opencl_kept_bytes() > 0);

    // From a log callback (the engine's last step) the device is still this call's: it keeps
    // its buffers, and the call neither waits on itself nor loses what it is using.
    Options o;
    o.chunk_planes = 31;
    o.memory_budget = 45 * 38 * 4 * 2 * 8;  // cut smaller than asked, with a warning
    int logged = 0;
    o.log = [&](const std::string&) {
        ++logged;
        release_scratch_memory();
    };
    require_same(cpu, run(v, o, Backend::OpenCL), v);
    CHECK(logged > 0);
    CHECK(detail::opencl_kept_bytes() > 0);
    release_scratch_memory();
    CHECK(detail::opencl_kept_bytes() == 0);
}
#endif  // VOXMESH_HAS_OPENCL

TEST_CASE("OpenCL matches the CPU engine on random odd-sized volumes", "[opencl]") {
    if (!have_device()) return;
    std::mt19937 rng(12345);
    for (int round = 0; round < 12; ++round) {
        Grid g{{2 + rng() % 22, 2 + rng() % 22, 2 + rng() % 22}};
        INFO("dims " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2]);
        Options o;
        o.chunk_planes = 1 + rng() % 5;
        if (round % 2) {
            std::vector<std::uint8_t> v(g.size());
            for (auto& x : v) x = static_cast<std::uint8_t>(rng() % 4);
            o.iso = 1.5;
            compare(view_of(v.data(), ScalarType::U8, g), o);
        } else {
            std::vector<float> v(g.size());
            std::uniform_real_distribution<float> u(-1, 1);
            for (auto& x : v) x = u(rng);
            compare(view_of(v.data(), ScalarType::F32, g), o);
        }
    }
}

// The kernels pack rows 32 samples to a word: a cell whose +x corner opens the next word, a
// last word with 1 or 31 samples, rows of exactly one or two words.
TEST_CASE("OpenCL matches the CPU engine on rows around 32-bit word lengths", "[opencl]") {
    if (!have_device()) return;
    std::mt19937 rng(777);
    for (std::size_t nx : {31, 32, 33, 63, 64, 65, 95, 97}) {
        Grid g{{nx, 3 + rng() % 9, 3 + rng() % 9}};
        INFO("dims " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2]);
        Options o;
        o.chunk_planes = 1 + rng() % 4;
        std::vector<float> v(g.size());
        std::uniform_real_distribution<float> u(-1, 1);
        for (auto& x : v) x = u(rng);
        compare(view_of(v.data(), ScalarType::F32, g), o);
        std::vector<std::uint8_t> b(g.size());
        for (auto& x : b) x = static_cast<std::uint8_t>(rng() % 3);
        o.iso = 1;
        compare(view_of(b.data(), ScalarType::U8, g), o);
    }
}

TEST_CASE("OpenCL matches the CPU engine on rows around the width where 16-bit word bases give way to 32-bit",
          "[opencl]") {
    // generate_vertices stores each 32-sample word's first vertex id, counted from its row's
    // first, in 16 bits while the last word starts at most 65535 edges in (683 words, nx up
    // to 21856), in 32 bits beyond.
    if (!have_device()) return;
    for (std::size_t nx : {21856u, 21857u}) {
        Grid g{{nx, 2, 2}};
        INFO("nx " << nx);
        // A 3-d checkerboard: every edge crosses, so row (0, 0) owns 3 * nx - 1 vertices.
        std::vector<std::uint8_t> b(g.size());
        for (std::size_t i = 0; i < b.size(); ++i) b[i] = ((i % nx + i / nx % 2 + i / nx / 2) % 2) ? 9 : 0;
        Options o;
        o.iso = 4.5;
        compare(view_of(b.data(), ScalarType::U8, g), o);
    }
}

TEST_CASE("OpenCL matches the CPU engine on all 256 cube cases", "[opencl]") {
    if (!have_device()) return;
    // Each case in a 4x3x3 volume: the cube at (1,1,1)..(2,2,2) set by the case bits, the
    // rest outside, so every border rule is exercised too.
    Grid g{{4, 4, 4}};
    for (int c = 0; c < 256; ++c) {
        INFO("case " << c);
        std::vector<float> v(g.size(), 0.f);
        for (int k = 0; k < 8; ++k) {
            const auto* o = detail::kCornerOffset[k];
            v[(1 + o[0]) + 4 * ((1 + o[1]) + 4 * (1 + o[2]))] = (c >> k & 1) ? 1.f + 0.1f * k : 0.f;
        }
        Options o;
        o.iso = 0.5;
        compare(view_of(v.data(), ScalarType::F32, g), o);
    }
}

TEST_CASE("OpenCL tiny chunks and a small memory budget give the same mesh", "[opencl]") {
    if (!have_device()) return;
    Grid g{{33, 35, 31}, {1, 1, 1}, {0, 0, 0}};
    const auto f = torus(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    for (std::size_t planes : {2, 3, 7}) {
        INFO("chunk_planes " << planes);
        Options o;
        o.chunk_planes = planes;
        require_same(cpu, run(v, o, Backend::OpenCL), v);
    }
    // About 8 planes' worth of chunk memory: the engine must cut the volume to fit.
    Options o;
    o.memory_budget = 33 * 35 * 40 * 2;
    Stats stats;
    require_same(cpu, run(v, o, Backend::OpenCL, &stats), v);
    REQUIRE(!stats.devices.empty());
    CHECK(stats.devices[0].chunks > 2);
    // Forced big chunks under that budget: cut smaller, with a warning. Stats count the chunks
    // asked for: the halves of a split one were each counted as a chunk.
    o.chunk_planes = 31;
    require_same(cpu, run(v, o, Backend::OpenCL, &stats), v);
    CHECK(!stats.warnings.empty());
    std::size_t chunks = 0, voxels = 0;
    for (const DeviceStats& d : stats.devices) {
        chunks += d.chunks;
        voxels += d.voxels;
    }
    CHECK(chunks == (v.dims[2] + 30) / 31);
    CHECK(voxels == v.dims[0] * v.dims[1] * v.dims[2]);
    // A budget too small for a single plane: the CPU engine does those chunks.
    o.chunk_planes = 0;
    o.memory_budget = 100;
    require_same(cpu, run(v, o, Backend::OpenCL, &stats), v);
    CHECK(!stats.warnings.empty());
}

TEST_CASE("OpenCL on a host-memory device keeps its working buffers to a share of the volume", "[opencl]") {
    if (!have_device()) return;
    if (!list_devices()[0].host_memory) {
        WARN("device 0 does not share host memory: this test is SKIPPED");
        return;
    }
    // 8-bit samples: the inside bits alone are 1/8 of the volume, and with the word bases and
    // row counts more than one chunk may hold; the device counts several chunks, then packs
    // each again (but the last) to generate it straight into its place in the mesh.
    Grid g{{512, 256, 256}};
    std::vector<std::uint8_t> u8(g.size());
    std::size_t i = 0;
    for (std::size_t z = 0; z < g.dims[2]; ++z)
        for (std::size_t y = 0; y < g.dims[1]; ++y)
            for (std::size_t x = 0; x < g.dims[0]; ++x) {
                const double dx = double(x) - 255.5, dy = double(y) - 130.0, dz = double(z) - 126.0;
                const double r = std::sqrt(dx * dx + 4 * dy * dy + 4 * dz * dz);  // an ellipsoid
                u8[i++] = static_cast<std::uint8_t>(std::clamp(128.0 + 2.0 * (200.0 - r), 0.0, 255.0));
            }
    const VolumeView v = view_of(u8.data(), ScalarType::U8, g);
    Options o;
    o.iso = 127.5;
    const Mesh cpu = run(v, o, Backend::Cpu);
    REQUIRE(cpu.triangle_count() > 100000);
    for (bool normals : {true, false}) {
        INFO("normals " << normals);
        o.normals = normals;
        Stats stats;
        const Mesh cl = run(v, o, Backend::OpenCL, &stats);
        REQUIRE(stats.devices.size() == 1);
        CHECK(stats.devices[0].chunks >= 2);
        require_same(normals ? cpu : run(v, o, Backend::Cpu), cl, v);
    }
}

TEST_CASE("Hybrid runs the CPU engine and OpenCL on one queue", "[opencl]") {
    if (!have_device()) return;
    Grid g{{48, 48, 96}};
    const auto f = gyroid(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    Options o;
    o.chunk_planes = 2;
    o.devices = {0};  // named: a CPU device (PoCL) joins Hybrid only when asked for
#ifdef VOXMESH_HAS_OPENCL
    // Both must take chunks whatever the machine's load: on a busy machine one side could
    // otherwise count all 48 chunks before the other's thread starts (PoCL runs on the same
    // cores). 2 ms more per chunk counted, on both sides alike.
    const Slow paced(0.002, 0, 0.002);
#endif
    Stats stats;
    require_same(cpu, run(v, o, Backend::Hybrid, &stats), v);
    CHECK(stats.backend == Backend::Hybrid);
    CHECK(stats.threads >= 1);
    CHECK(stats.workers == std::min(stats.threads, detail::resolve_threads(0)));
    REQUIRE(stats.devices.size() >= 2);
    std::size_t voxels = 0;
    for (const DeviceStats& d : stats.devices) {
        INFO("device " << d.name);
        CHECK(d.chunks > 0);
        voxels += d.voxels;
    }
    CHECK(voxels == g.size());
}

TEST_CASE("Hybrid meshes small volumes whole, whoever takes the last plane", "[opencl]") {
    if (!have_device()) return;
    // On a small volume Hybrid's CPU worker often takes the last chunk alone: its vertices
    // once stayed at 0 (the index buffer was right), every time on these shapes.
    for (const std::array<std::size_t, 3> dims : {std::array<std::size_t, 3>{2, 2, 2}, {3, 2, 5}, {2, 17, 2}, {65, 3, 3}}) {
        Grid g{dims};
        g.origin = {10, 20, 30};
        std::vector<float> f(g.size());
        for (std::size_t i = 0; i < f.size(); ++i) f[i] = static_cast<float>(i * 7919 % 13) / 6.0f - 1.0f;
        const VolumeView v = view_of(f.data(), ScalarType::F32, g);
        Options o;
        o.iso = 0.05;
        o.devices = {0};
        INFO("dims " << dims[0] << "x" << dims[1] << "x" << dims[2]);
        const Mesh cpu = run(v, o, Backend::Cpu);
        REQUIRE(cpu.vertex_count() > 0);
        // Five calls: the split twice, then the CPU engine alone and the device alone (each
        // measured once before Hybrid picks the quickest), all with the CPU engine's mesh.
        for (int round = 0; round < 5; ++round) require_same(cpu, run(v, o, Backend::Hybrid), v);
    }
}

#ifdef VOXMESH_HAS_OPENCL  // uses test hooks of the OpenCL build
// A device far slower than the CPU worker, in counting (a slow bus) or in generating (slow
// reads back): the device stops taking chunks and the CPU worker takes its counted pieces
// over. Whoever meshes a chunk, the mesh is the CPU engine's.
TEST_CASE("Hybrid hands chunks between a slow device and the CPU worker", "[opencl]") {
    if (!have_device()) return;
    Grid g{{48, 48, 96}};
    const auto f = gyroid(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    const Pretend discrete(detail::opencl_pretend_discrete);
    const auto hybrid = [&](Stats& stats) {
        Options o;
        o.chunk_planes = 2;  // 48 chunks
        o.devices = {0};
        require_same(cpu, run(v, o, Backend::Hybrid, &stats), v);
        REQUIRE(stats.devices.size() == 2);
        CHECK(stats.devices[1].name == "cpu");
        CHECK(stats.devices[0].voxels + stats.devices[1].voxels == g.size());
        CHECK(stats.devices[0].chunks + stats.devices[1].chunks == 48);  // handed-over chunks are the CPU's
    };
    const auto shares = [](const Stats& stats) {
        return "device chunks " + std::to_string(stats.devices[0].chunks) + ", handed over " +
               std::to_string(stats.devices[0].chunks_handed_over) + ", cpu chunks " +
               std::to_string(stats.devices[1].chunks);
    };
    SECTION("counting on the device is slow: it stops taking chunks") {
        const Slow slow(0.02, 0, 0);
        Stats stats;
        hybrid(stats);
        CHECK(stats.devices[0].chunks + stats.devices[0].chunks_handed_over < 24);
    }
    SECTION("generating on the device is slow: the CPU worker takes its pieces over") {
        // The CPU worker takes its first run (12 chunks, 10 ms each) before the device may take
        // a second chunk; while that run lasts, the device counts several. Without the deal, on
        // a loaded machine the device once took all 48 chunks before the CPU worker started,
        // and a CPU worker that has counted nothing has no rate to weigh a take-over with.
        const Pretend deal(detail::opencl_deal_first_chunks);
        const Slow slow(0, 0.02, 0.01);
        Stats stats;
        hybrid(stats);
        INFO(shares(stats));
        CHECK(stats.devices[0].chunks >= 1);  // the piece it was generating when the CPU came
        CHECK(stats.devices[0].chunks_handed_over >= 1);
    }
    SECTION("the CPU worker starts after the device has counted every chunk: it still takes pieces over") {
        // It has counted nothing, so it has no rate of its own to weigh a take-over with: it
        // takes one piece to measure, then goes on while that is quicker than the device.
        const Slow slow(0, 0.05, 0, 0.5);
        Stats stats;
        hybrid(stats);
        INFO(shares(stats));
        CHECK(stats.devices[0].chunks_handed_over >= 2);
    }
    SECTION("both sides slow") {
        const Slow slow(0.003, 0.003, 0.003);
        Stats stats;
        hybrid(stats);
    }
}

// Found by a review: the CPU worker counts a device's piece again to take it over, and counts
// that differ were reported as an "internal error" where the caller's thread had written to
// the volume in between (voxmesh.hpp promises the volume-changed Error then).
TEST_CASE("Hybrid: a volume changed before a piece is taken over is the volume-changed Error", "[opencl]") {
    if (!have_device()) return;
    Grid g{{48, 48, 96}};
    const auto original = gyroid(g);
    std::vector<float> f = original;
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Pretend discrete(detail::opencl_pretend_discrete);
    Options o;
    o.chunk_planes = 2;
    o.devices = {0};
    // The CPU worker starts after the device has counted every chunk and takes pieces over
    // (the hand-over test's last section); before its first, every sample moves inside.
    const Slow slow(0, 0.05, 0, 0.5);
    std::atomic<int> take_overs{0};
    detail::opencl_before_take_over([&] {
        if (take_overs++ == 0)
            for (float& x : f) x = 1e6f;
    });
    CHECK_THROWS_WITH(run(v, o, Backend::Hybrid), Catch::Contains("changed while it was being meshed"));
    detail::opencl_before_take_over({});
    CHECK(take_overs >= 1);
    f = original;
    require_same(run(v, Options{}, Backend::Cpu), run(v, o, Backend::Hybrid), v);
}

// Runs f(recounted) before each piece a device counted is generated, for a scope
// (detail::opencl_before_generate).
struct BeforeGenerate {
    explicit BeforeGenerate(std::function<void(bool)> f) { detail::opencl_before_generate(std::move(f)); }
    ~BeforeGenerate() { detail::opencl_before_generate({}); }
    BeforeGenerate(const BeforeGenerate&) = delete;
    BeforeGenerate& operator=(const BeforeGenerate&) = delete;
};

// Samples written to between classify and generate (a data race, for which the API promises a
// mix of old and new samples) can leave a crossed edge with both ends on iso: t = 0 / 0. A
// device reading the caller's samples in place kept that NaN in the vertex's position; t is
// kept on the edge now, as on the CPU engine (edge_vertex.hpp).
TEST_CASE("OpenCL: an edge whose samples changed since classify keeps its vertex finite and on the edge", "[opencl]") {
    if (!have_device()) return;
    Grid g{{24, 20, 18}};
    const std::vector<float> field = sphere(g);
    std::vector<float> f32 = field;
    const std::vector<std::uint16_t> u16_field = to_type<std::uint16_t>(field, 1000, 2000);
    std::vector<std::uint16_t> u16 = u16_field;
    const std::vector<std::pair<VolumeView, double>> volumes = {{view_of(f32.data(), ScalarType::F32, g), 0.0},
                                                                {view_of(u16.data(), ScalarType::U16, g), 2000.0}};
    for (const auto& [volume, iso] : volumes) {
        INFO(scalar_name(volume.type));
        std::copy(field.begin(), field.end(), f32.begin());  // in place: the views keep pointing there
        std::copy(u16_field.begin(), u16_field.end(), u16.begin());
        Options o;
        o.iso = iso;
        o.devices = {0};
        const Mesh before = run(volume, o, Backend::Cpu);
        REQUIRE(!before.positions.empty());
        int generated = 0;
        const BeforeGenerate every_sample_on_iso([&](bool) {
            ++generated;
            std::fill(f32.begin(), f32.end(), 0.f);
            std::fill(u16.begin(), u16.end(), std::uint16_t{2000});
        });
        const Mesh after = run(volume, o, Backend::OpenCL);  // the device reads the samples in place
        CHECK(generated >= 1);
        REQUIRE(after.positions.size() == before.positions.size());
        REQUIRE(after.indices == before.indices);
        // t = 0: every vertex on the sample its edge starts at, a grid point.
        std::size_t off_grid = 0;
        for (const float c : after.positions)
            if (!std::isfinite(c) || c != std::round(c)) ++off_grid;
        CHECK(off_grid == 0);
        for (const float c : after.normals) REQUIRE(std::isfinite(c));
    }
}

#endif  // VOXMESH_HAS_OPENCL

// Found by a review: a chunk cut in halves to fit a device counts where it starts, so when only
// its upper half ran on the CPU engine the "cpu (fallback)" entry had voxels but no chunk, and
// was left out: the devices' voxels no longer added up to the volume.
TEST_CASE("OpenCL and Hybrid stats account for every voxel when half a chunk falls back to the CPU", "[opencl]") {
    if (!have_device()) return;
    Grid g{{32, 32, 4}};
    std::vector<float> f(g.size());
    for (std::size_t i = 0; i < f.size(); ++i)
        f[i] = static_cast<float>(std::sin(0.3 * double(i % 32)) + std::cos(0.3 * double(i / 32 % 32)) -
                                  0.2 * double(i / (32 * 32)));
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    for (const Backend backend : {Backend::OpenCL, Backend::Hybrid}) {
        for (const std::size_t budget : {12000u, 16000u, 20000u, 30000u}) {
            Options o;
            o.devices = {0};
            o.chunk_planes = 2;
            o.memory_budget = budget;
            o.threads = 1;
            Stats stats;
            require_same(cpu, run(v, o, backend, &stats), v);
            std::size_t voxels = 0;
            std::string entries;
            for (const DeviceStats& d : stats.devices) {
                voxels += d.voxels;
                entries += " [" + d.name + " chunks " + std::to_string(d.chunks) + " voxels " + std::to_string(d.voxels) + "]";
            }
            INFO(backend_name(backend) << ", budget " << budget << ":" << entries);
            CHECK(voxels == g.size());
        }
    }
}

// Stats::backend is what ran: with a budget no plane fits in, every chunk runs on the CPU
// engine, and the OpenCL backend says Cpu (it said OpenCL); with one that fits some chunks it
// says OpenCL; Hybrid always says Hybrid.
TEST_CASE("OpenCL's stats say Cpu when every chunk fell back to the CPU engine", "[opencl]") {
    if (!have_device()) return;
    Grid g{{32, 32, 4}};
    const std::vector<float> f = gyroid(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    REQUIRE(cpu.triangle_count() > 0);
    Options o;
    o.devices = {0};
    o.chunk_planes = 2;
    o.threads = 1;
    for (const Backend backend : {Backend::OpenCL, Backend::Hybrid}) {
        for (const std::size_t budget : {1000u, 30000u}) {
            o.memory_budget = budget;
            Stats stats;
            require_same(cpu, run(v, o, backend, &stats), v);
            std::size_t device_voxels = 0;
            for (const DeviceStats& d : stats.devices)
                if (d.name != "cpu" && d.name != "cpu (fallback)") device_voxels += d.voxels;
            INFO(backend_name(backend) << ", budget " << budget << ", device voxels " << device_voxels);
            CHECK((budget == 1000u) == (device_voxels == 0));
            const Backend ran = backend == Backend::Hybrid ? Backend::Hybrid
                                : device_voxels == 0       ? Backend::Cpu
                                                           : Backend::OpenCL;
            CHECK(stats.backend == ran);
            if (budget == 1000u && backend == Backend::OpenCL) CHECK(!stats.warnings.empty());
        }
    }
}

#ifdef VOXMESH_HAS_OPENCL  // uses test hooks of the OpenCL build
// With automatic chunks, a call plans its split from what the previous call on the same
// device and volume shape measured; the plan only moves work, never the mesh.
TEST_CASE("Hybrid's planned split from earlier calls gives the same mesh", "[opencl]") {
    if (!have_device()) return;
    // Each volume has 8 automatic chunks and rates of its own (the plan is per volume shape).
    struct Volume {
        explicit Volume(Grid grid) : g(grid), f(gyroid(g)), v(view_of(f.data(), ScalarType::F32, g)) {
            cpu = run(v, Options{}, Backend::Cpu);
        }
        Grid g;
        std::vector<float> f;
        VolumeView v;
        Mesh cpu;
    };
    Options o;
    o.devices = {0};
    const Pretend split_only(detail::opencl_hybrid_split_only);  // the plan is what is tested
    const auto hybrid = [&](const Volume& vol, double device_count_s, double device_generate_s, double cpu_count_s) {
        Stats stats;
        Mesh m;
        {
            const Slow slow(device_count_s, device_generate_s, cpu_count_s);
            m = run(vol.v, o, Backend::Hybrid, &stats);
        }
        require_same(vol.cpu, m, vol.v);
        REQUIRE(stats.devices.size() == 2);
        CHECK(stats.devices[0].voxels + stats.devices[1].voxels == vol.g.size());
        return stats;
    };
    SECTION("a slow CPU worker: the plan gives the device most chunks, until the CPU is hoped for again") {
        // 200 ms a chunk, so that a PoCL device sharing the two cores with a parallel ctest
        // still counts faster (at 10 ms it once was slower, and its plan 2 of 8).
        const Volume vol(Grid{{48, 40, 120}});
        {
            // The first call must measure the CPU worker's counting for the next to plan: on a
            // loaded machine its thread once started after the device had counted every chunk.
            const Pretend deal(detail::opencl_deal_first_chunks);
            hybrid(vol, 0, 0, 0.2);
        }
        for (int call = 1; call < 3; ++call) {
            INFO("call " << call);
            CHECK(hybrid(vol, 0, 0, 0.2).devices[0].chunks >= 4);
        }
        // Without the hook the CPU worker is fast again, but planned out it measures nothing:
        // its rates grow more hopeful each call until it gets chunks again (about 30 calls
        // from 200 ms down to a PoCL device's fraction of a millisecond).
        int calls = 0;
        while (hybrid(vol, 0, 0, 0).devices[1].chunks == 0 && calls < 80) ++calls;
        INFO("calls without a chunk for the CPU worker: " << calls);
        CHECK(calls < 80);
    }
    SECTION("a plan made for a fast device that has turned slow is mended by the CPU worker") {
        // Planned with the CPU worker at 10 ms a chunk, then the device far slower than that
        // plan assumed (50 ms a piece): the CPU worker takes its planned run, then the
        // device's last chunks one at a time while it is behind.
        const Volume vol(Grid{{48, 40, 112}});
        for (int call = 0; call < 3; ++call) hybrid(vol, 0, 0, 0.01);
        const Stats mended = hybrid(vol, 0.05, 0, 0);
        CHECK(mended.devices[1].chunks >= 1);
        CHECK(mended.devices[0].chunks < 8);
    }
}

// With one device and automatic chunks, Hybrid times the split, the CPU engine alone and the
// device alone in its first calls on a volume shape, then runs the quickest (and now and then
// another again). A device made far slower than the CPU must not be run alone once measured
// (once more where its first call made the device's buffers).
TEST_CASE("Hybrid runs the quickest of the split, the CPU engine alone and the device alone", "[opencl]") {
    if (!have_device()) return;
    Grid g{{44, 40, 104}};  // a shape no other test meshes: the choice is per shape
    const auto f = gyroid(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    Options o;
    o.devices = {0};
    const Slow slow(0.1, 0, 0);  // 100 ms for each chunk the device counts
    enum Ran { SplitOrCpu, CpuAlone, DeviceAlone };
    const auto hybrid = [&] {
        Stats stats;
        require_same(cpu, run(v, o, Backend::Hybrid, &stats), v);
        CHECK(stats.backend == Backend::Hybrid);
        REQUIRE(stats.devices.size() == 2);  // the device, then the CPU, whatever ran
        CHECK(stats.devices[1].name == "cpu");
        CHECK(stats.devices[0].voxels + stats.devices[1].voxels == g.size());
        if (stats.devices[1].chunks == 0) return DeviceAlone;
        if (stats.devices[0].chunks == 0 && stats.devices[1].chunks == 1) return CpuAlone;
        return SplitOrCpu;
    };
    hybrid();  // the split, untimed
    hybrid();  // the split, timed
    CHECK(hybrid() == CpuAlone);
    // The device's kept buffers freed: its first call alone makes them again, and a GPU pays
    // for its buffers on first use, so that call's time says little, and it is run once more
    // (on a GPU the timed split may have made buffers too, and be run again in between).
    release_scratch_memory();
    CHECK(hybrid() == DeviceAlone);
    int device_alone = 1;
    for (int call = 0; call < 2; ++call) device_alone += hybrid() == DeviceAlone;
    CHECK(device_alone == 2);
    for (int call = 0; call < 6; ++call) {
        INFO("call " << call << " after each mode was measured");
        CHECK(hybrid() != DeviceAlone);
    }
}

#endif  // VOXMESH_HAS_OPENCL

TEST_CASE("Hybrid leaves out OpenCL devices that are the CPU itself unless they are named", "[opencl]") {
    if (!have_device()) return;
    const auto devices = list_devices();
    const bool only_cpus = std::all_of(devices.begin(), devices.end(),
                                       [](const DeviceInfo& d) { return d.type == DeviceType::Cpu; });
    Grid g{{40, 40, 40}};
    const auto f = gyroid(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    Stats stats;
    require_same(cpu, run(v, Options{}, Backend::Hybrid, &stats), v);
    for (const DeviceStats& d : stats.devices) {
        INFO("device " << d.name);
        const bool is_cpu_device = std::any_of(devices.begin(), devices.end(), [&](const DeviceInfo& info) {
            return info.name == d.name && info.type == DeviceType::Cpu;
        });
        CHECK_FALSE(is_cpu_device);
    }
    if (only_cpus) {
        REQUIRE(stats.warnings.size() == 1);
        CHECK_THAT(stats.warnings[0], Catch::Contains("would compete with the CPU engine"));
    }
    // Asked for by type, the CPU device takes chunks again.
    Options by_type;
    by_type.device_type = DeviceType::Cpu;
    by_type.chunk_planes = 4;
    Stats typed;
    require_same(cpu, run(v, by_type, Backend::Hybrid, &typed), v);
    if (std::any_of(devices.begin(), devices.end(), [](const DeviceInfo& d) { return d.type == DeviceType::Cpu; }))
        CHECK(typed.devices.size() >= 2);
}

TEST_CASE("OpenCL programs are built once per device: a second extract builds nothing", "[opencl]") {
    if (!have_device()) return;
    Grid g{{24, 20, 18}};
    const auto f = gyroid(g);
    std::vector<std::uint16_t> u16(f.size());  // a sample type no other test case meshes first
    for (std::size_t i = 0; i < f.size(); ++i) u16[i] = static_cast<std::uint16_t>(30000 + 20000 * f[i]);
    const VolumeView v = view_of(u16.data(), ScalarType::U16, g);
    Options o;
    o.iso = 30000.5;
    o.devices = {0};
    Stats first, second;
    const Mesh a = run(v, o, Backend::OpenCL, &first);
    const Mesh b = run(v, o, Backend::OpenCL, &second);
    CHECK(a.indices == b.indices);
    REQUIRE(first.devices.size() == 1);
    REQUIRE(second.devices.size() == 1);
    CHECK(first.devices[0].programs_built <= 2);  // marching_cubes.cl for u16, scan.cl if not yet built
    CHECK(second.devices[0].programs_built == 0);  // what set-up costs is for bench/, not a timed test
}

#ifdef VOXMESH_HAS_OPENCL  // uses a test hook of the OpenCL build
TEST_CASE("Two OpenCL devices share the chunks", "[opencl]") {
    if (!have_device()) return;
    Grid g{{40, 44, 90}};
    const auto f = sphere(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    Options o;
    o.chunk_planes = 2;
    Stats stats;
    Mesh cl;
    std::size_t device_count = 0;
    {
        const Pretend split(detail::opencl_split_devices);
        device_count = list_devices().size();
        if (device_count < 2) {
            WARN("fewer than two OpenCL devices even with device fission: two-device test SKIPPED");
            return;
        }
        // Chunks are pulled by whichever device is free, so one sub-device can take all 45
        // before the other has finished its first (it happened once, under ASan in a
        // clean-clone CI run): the hook deals each device its first chunk before any takes a
        // second.
        const Pretend deal(detail::opencl_deal_first_chunks);
        cl = run(v, o, Backend::OpenCL, &stats);
    }
    require_same(run(v, Options{}, Backend::Cpu), cl, v);
    REQUIRE(stats.devices.size() == device_count);
    for (const DeviceStats& d : stats.devices) {
        INFO("device " << d.name);
        CHECK(d.chunks > 0);
    }
}

TEST_CASE("NaN samples name the volume's first plane with one on every engine, whatever chunk failed first", "[opencl]") {
    if (!have_device()) return;
    Grid g{{40, 44, 90}};
    auto f = sphere(g);
    const std::size_t plane = g.dims[0] * g.dims[1];
    for (const std::size_t z : {std::size_t{1}, std::size_t{3}, std::size_t{40}, std::size_t{88}})
        f[z * plane + 100] = std::numeric_limits<float>::quiet_NaN();
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const std::string first = "first seen in z-plane 1)";
    Options o;
    o.chunk_planes = 2;
    // Hybrid with the CPU device named: PoCL meshes chunks from the bottom and the CPU worker
    // from the top, where it meets plane 88 first.
    for (const Backend b : {Backend::Cpu, Backend::OpenCL, Backend::Hybrid})
        for (int repeat = 0; repeat < 5; ++repeat) {
            INFO(backend_name(b));
            o.backend = b;
            o.devices = {0};
            CHECK_THROWS_WITH(extract(v, o), Catch::Contains(first));
        }
    // Two devices, each dealt a first chunk (planes 0-2 and 2-4), fail at once.
    const Pretend split(detail::opencl_split_devices);
    const Pretend deal(detail::opencl_deal_first_chunks);
    o.devices.clear();
    for (const Backend b : {Backend::OpenCL, Backend::Hybrid})
        for (int repeat = 0; repeat < 10; ++repeat) {
            INFO(backend_name(b) << " on " << list_devices().size() << " devices");
            o.backend = b;
            CHECK_THROWS_WITH(extract(v, o), Catch::Contains(first));
        }
}

TEST_CASE("OpenCL scan kernel matches std::exclusive_scan", "[opencl]") {
    if (!have_device()) return;
    std::mt19937 rng(7);
    // Block edges of both launch shapes (2048 elements a GPU work-group, 1024 a CPU one) and
    // lengths that take two and three levels of block sums in each.
    for (const bool gpu_shape : {false, true})
        for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(255), std::size_t(256), std::size_t(257),
                              std::size_t(1023), std::size_t(1024), std::size_t(1025), std::size_t(2047),
                              std::size_t(2048), std::size_t(2049), std::size_t(1000003), std::size_t(1048577),
                              std::size_t(4194305)}) {
            INFO("length " << n << (gpu_shape ? ", GPU launch shape" : ", the device's launch shape"));
            std::vector<std::uint32_t> values(n);
            for (auto& x : values) x = rng() % 16;
            std::vector<std::uint32_t> expected(n);
            std::exclusive_scan(values.begin(), values.end(), expected.begin(), std::uint32_t(0));
            const auto got = detail::opencl_exclusive_scan(values, 0, gpu_shape);
            REQUIRE(got.size() == n + 1);
            CHECK(std::equal(expected.begin(), expected.end(), got.begin()));
            CHECK(got.back() == std::accumulate(values.begin(), values.end(), std::uint32_t(0)));
        }
}
#endif  // VOXMESH_HAS_OPENCL

TEST_CASE("OpenCL errors are clear", "[opencl]") {
    if (!have_device()) return;
    Grid g{{5, 5, 5}};
    std::vector<float> v(g.size(), 0.f);
    v[62] = 1.f;
    Options o;
    o.backend = Backend::OpenCL;
    o.iso = 0.5;
    o.devices = {static_cast<int>(list_devices().size())};
    CHECK_THROWS_WITH(extract(view_of(v.data(), ScalarType::F32, g), o), Catch::Contains("does not exist"));
    o.devices.clear();
    v[10] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(extract(view_of(v.data(), ScalarType::F32, g), o), Catch::Contains("NaN"));
    v[10] = -std::numeric_limits<float>::infinity();  // refused like NaN, as by the CPU engine
    CHECK_THROWS_WITH(extract(view_of(v.data(), ScalarType::F32, g), o), Catch::Contains("infinite"));
    std::vector<double> w(g.size(), 0.0);
    w[62] = std::numeric_limits<double>::infinity();
    CHECK_THROWS_WITH(extract(view_of(w.data(), ScalarType::F64, g), o), Catch::Contains("infinite"));
    o.devices.clear();
    o.device_type = DeviceType::Accelerator;
    v[10] = 0;
    const auto devices = list_devices();  // one vector: begin and end of two temporaries is UB
    if (std::none_of(devices.begin(), devices.end(), [](const DeviceInfo& d) { return d.type == DeviceType::Accelerator; })) {
        CHECK_THROWS_AS(extract(view_of(v.data(), ScalarType::F32, g), o), Error);
        // Auto with a device type nobody has: the advice is not "use Backend::Auto".
        o.backend = Backend::Auto;
        CHECK_THROWS_WITH(extract(view_of(v.data(), ScalarType::F32, g), o),
                          Catch::Contains("no OpenCL device matches") && Catch::Contains("leave devices and device_type unset"));
    }
}

#ifdef VOXMESH_HAS_OPENCL  // uses a test hook of the OpenCL build
TEST_CASE("An OpenCL build failure names the device and carries the build log", "[opencl]") {
    if (!have_device()) return;
    const std::string name = list_devices()[0].name;
    CHECK_NOTHROW(detail::opencl_build_program("__kernel void ok(__global int* a) { a[0] = 1; }", ""));
    try {
        detail::opencl_build_program("__kernel void broken(__global int* a) { a[0] = undeclared_thing; }", "");
        FAIL("a broken program built");
    } catch (const Error& e) {
        const std::string what = e.what();
        CHECK_THAT(what, Catch::Contains(name));
        CHECK_THAT(what, Catch::Contains("undeclared_thing"));
    }
}
#endif  // VOXMESH_HAS_OPENCL

TEST_CASE("list_devices describes the OpenCL devices", "[opencl]") {
    if (!have_device()) return;
    for (const DeviceInfo& d : list_devices()) {
        CHECK(!d.name.empty());
        CHECK(!d.platform.empty());
        CHECK(d.compute_units > 0);
        CHECK(d.max_allocation > 0);
        CHECK(d.global_memory >= d.max_allocation);
    }
    CHECK(opencl_available());
}

// Run by ctest with OCL_ICD_VENDORS pointing at an empty directory (tests/opencl.cmake).
TEST_CASE("Without an OpenCL platform Auto and Hybrid fall back to the CPU engine", "[opencl][fallback]") {
    if (!list_devices().empty()) {
        WARN("an OpenCL device is present: the fallback test only runs with OCL_ICD_VENDORS=<empty dir> (ctest)");
        return;
    }
    Grid g{{20, 21, 22}};
    const auto f = sphere(g);
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    const Mesh cpu = run(v, Options{}, Backend::Cpu);
    for (Backend b : {Backend::Auto, Backend::Hybrid}) {
        std::vector<std::string> logged;
        Options o;
        o.log = [&](const std::string& m) { logged.push_back(m); };
        Stats stats;
        const Mesh m = run(v, o, b, &stats);
        CHECK(m.indices == cpu.indices);
        CHECK(stats.backend == Backend::Cpu);
        REQUIRE(stats.warnings.size() == 1);
        CHECK_THAT(stats.warnings[0], Catch::Contains("OpenCL"));
        CHECK(logged == stats.warnings);
    }
    Options o;
    CHECK_FALSE(opencl_available());
    CHECK_THROWS_WITH(run(v, o, Backend::OpenCL),
                      Catch::Contains("no OpenCL platform") || Catch::Contains("built without OpenCL"));
}

TEST_CASE("A 256^3 volume meshes identically through OpenCL, Hybrid and CPU", "[opencl][large]") {
    if (!have_device()) return;
    Grid g{{256, 256, 256}, {1, 1, 1}, {0, 0, 0}};
    const auto f = sample(g, [](double x, double y, double z) {  // a torus with gyroid ripples
        const double q = std::sqrt((x - .5) * (x - .5) + (y - .5) * (y - .5)) - 0.3;
        return float(0.12 - std::sqrt(q * q + (z - .5) * (z - .5)) +
                     0.02 * std::sin(40 * x) * std::cos(40 * y) * std::sin(40 * z));
    });
    const VolumeView v = view_of(f.data(), ScalarType::F32, g);
    Stats cpu_stats, cl_stats, hybrid_stats;
    const Mesh cpu = run(v, Options{}, Backend::Cpu, &cpu_stats);
    const Mesh cl = run(v, Options{}, Backend::OpenCL, &cl_stats);
    const Mesh hybrid = run(v, Options{}, Backend::Hybrid, &hybrid_stats);
    REQUIRE(cpu.triangle_count() > 100000);
    require_same(cpu, cl, v);
    require_same(cpu, hybrid, v);
    WARN("256^3: " << cpu.triangle_count() << " triangles; cpu " << cpu_stats.times.total << " s, opencl "
                   << cl_stats.times.total << " s (kernels " << cl_stats.devices[0].kernel_s << " s, transfers "
                   << cl_stats.devices[0].transfer_s << " s), hybrid " << hybrid_stats.times.total << " s");
}

TEST_CASE("OpenCL extract_into gives extract()'s mesh in a reused mesh's storage", "[opencl]") {
    if (!have_device()) return;
    Grid g{{41, 37, 33}};
    std::vector<float> v(g.size());
    std::mt19937 rng(31);
    std::uniform_real_distribution<float> u(-1, 1);
    for (auto& x : v) x = u(rng);
    const VolumeView view = view_of(v.data(), ScalarType::F32, g);
    Mesh mesh;
    mesh.positions.assign(900000, -7.f);
    mesh.normals.assign(900000, 3.f);
    mesh.indices.assign(1200000, 0xdeadbeefu);
    for (std::size_t chunk_planes : {0u, 5u}) {  // one chunk, several (each written at its offsets)
        for (bool normals : {true, false}) {
            INFO("chunk_planes " << chunk_planes << " normals " << normals);
            Options o;
            o.backend = Backend::OpenCL;
            o.chunk_planes = chunk_planes;
            o.normals = normals;
            Stats stats;
            extract_into(view, o, mesh, stats);
            CHECK(stats.backend == Backend::OpenCL);
            REQUIRE(mesh.triangle_count() > 10000);
            require_same(run(view, o, Backend::Cpu), mesh, view);
        }
    }
}

// In a forked child: that it lists no devices, Auto meshes `expected` on the CPU, and then
// what OpenCL says (its Error's text), or what went wrong instead.
std::string what_a_forked_child_meshes(const VolumeView& view, const Mesh& expected) {
    if (!list_devices().empty() || opencl_available()) return "devices listed in the child";
    Options o;
    o.backend = Backend::Auto;
    Stats stats;
    const Mesh mesh = extract(view, o, stats);
    if (stats.backend != Backend::Cpu || mesh.indices != expected.indices || mesh.positions != expected.positions)
        return "Auto gave another mesh or backend";
    o.backend = Backend::OpenCL;
    try {
        (void)extract(view, o);
        return "OpenCL ran in the child";
    } catch (const Error& e) {
        return e.what();
    }
}

// A child forked after the parent opened its OpenCL devices has none: PoCL's worker threads
// stayed in the parent, and a kernel run in the child waited for them for ever. Auto meshes on
// the CPU there, and OpenCL says why it cannot run.
TEST_CASE("a forked child of a process using OpenCL meshes on the CPU and says why OpenCL cannot", "[opencl]") {
    if (!have_device()) return;
    if (!vmtest::threads_after_fork_or_warn()) return;
    Grid g{{33, 30, 28}};
    const std::vector<float> v = sphere(g);
    const VolumeView view = view_of(v.data(), ScalarType::F32, g);
    const Mesh on_device = run(view, Options{}, Backend::OpenCL);  // the devices opened here
    const Mesh expected = run(view, Options{}, Backend::Cpu);
    const std::string child = vmtest::output_of_child([&] { return what_a_forked_child_meshes(view, expected); }, 60);
    CHECK(child ==
          "the OpenCL devices were opened before this process was forked, and a forked child cannot use them (the "
          "OpenCL runtime's threads stay in the parent); use Backend::Cpu or Backend::Auto in the child, or OpenCL in "
          "the parent only after it forks");
    CHECK(run(view, Options{}, Backend::OpenCL).indices == on_device.indices);  // the parent's devices still work
}

#ifdef VOXMESH_HAS_OPENCL
// Another thread inside the device registry when this one forks (listing devices, or caught
// discovering them): the child must not wait for that thread's lock, which it will never see
// let go of, and a half-built device list must not be used.
TEST_CASE("a child forked while another thread holds the device registry does not hang", "[opencl]") {
    if (!have_device()) return;
    if (!vmtest::threads_after_fork_or_warn()) return;
    Grid g{{20, 22, 18}};
    const std::vector<float> v = sphere(g);
    const VolumeView view = view_of(v.data(), ScalarType::F32, g);
    const Mesh expected = run(view, Options{}, Backend::Cpu);
    const std::size_t listed = list_devices().size();
    for (const bool discovering : {false, true}) {
        INFO((discovering ? "caught discovering" : "caught listing"));
        std::promise<void> locked, forked;
        std::thread holder([&] {
            detail::opencl_with_registry_locked(discovering, [&] {
                locked.set_value();
                forked.get_future().wait();
            });
        });
        locked.get_future().wait();
        const std::string child =
            vmtest::output_of_child([&] { return what_a_forked_child_meshes(view, expected); }, 30);
        forked.set_value();
        holder.join();
        CHECK(child.find("before this process was forked") != std::string::npos);
        CHECK(list_devices().size() == listed);  // the parent's registry is as it was
    }
}

// Two threads forking at once: each must take back only what its own fork took of the
// registry, or one fork leaves the parent's registry locked for good.
TEST_CASE("threads forking at once leave the device registry usable", "[opencl]") {
    if (!have_device()) return;
    if (!vmtest::threads_after_fork_or_warn()) return;
    const std::size_t listed = list_devices().size();
    std::atomic<int> children_without_devices{0};
    const auto forker = [&] {
        for (int i = 0; i < 25; ++i)
            if (vmtest::output_of_child([] { return std::to_string(list_devices().size()); }, 30) == "0")
                ++children_without_devices;
    };
    std::thread a(forker), b(forker);
    for (int i = 0; i < 200; ++i) (void)list_devices();  // the parent's own callers, meanwhile
    a.join();
    b.join();
    CHECK(children_without_devices == 50);
    // On a thread of its own: a lock left held would hang there, not here.
    const auto after = std::make_shared<std::promise<std::size_t>>();
    auto listed_after = after->get_future();
    std::thread([after] { after->set_value(list_devices().size()); }).detach();
    REQUIRE(listed_after.wait_for(std::chrono::seconds(30)) == std::future_status::ready);
    CHECK(listed_after.get() == listed);
}
#endif

#ifdef VOXMESH_HAS_OPENCL
// Run by ctest as voxmesh_opencl_faults, with the fault layer loaded (tests/opencl.cmake):
// a device that runs out of memory counting or generating hands its chunks to the CPU engine
// (or cuts them smaller) and the mesh is the same; any other OpenCL error ends the call with
// an Error naming it, and the next call on the same devices is whole again.
TEST_CASE("the OpenCL engine recovers from a device out of memory, and names other errors", "[.clfault]") {
    if (!vmtest::fault_layer_named()) return;  // run by name without the layer: skipped, with a warning
    const vmtest::FaultLayer layer = vmtest::fault_layer();
    REQUIRE(layer.loaded());
    REQUIRE(!list_devices().empty());
    const vmtest::ClearFaults clear{layer};

    Grid g{{45, 38, 41}};
    const std::vector<float> f32 = torus(g);
    const auto u8 = to_type<std::uint8_t>(f32, 100, 120);  // 8-bit: the CPU generates a device's piece in its own room
    const std::vector<std::pair<VolumeView, double>> volumes = {{view_of(f32.data(), ScalarType::F32, g), 0.0},
                                                                {view_of(u8.data(), ScalarType::U8, g), 120.5}};
    struct Fault {
        const char* what;
        const char* kernel;
        int error;
        unsigned long long buffer_over;
        unsigned long long skip;
        long long times;
        const char* warning;  // what the OpenCL engine alone must say
        bool discrete_only = false;  // a device sharing host memory makes no such call
    };
    const std::vector<Fault> faults = {
        {"generating vertices", "generate_vertices", CL_OUT_OF_RESOURCES, 0, 0, -1, "ran out of memory generating"},
        {"generating triangles, the second piece", "generate_triangles", CL_MEM_OBJECT_ALLOCATION_FAILURE, 0, 1, 1,
         "ran out of memory generating"},
        {"counting", "classify_pack", CL_MEM_OBJECT_ALLOCATION_FAILURE, 0, 0, -1, "cannot hold even one z-plane"},
        {"counting, twice", "classify_rows", CL_OUT_OF_RESOURCES, 0, 0, 2, "using smaller chunks"},
        {"buffers over 20 kB", "", 0, 20000, 0, -1, "out of memory"},
        // Transfers: a device that runs out of memory for them (pinned staging, a mapping).
        {"uploads", "clEnqueueWriteBuffer", CL_MEM_OBJECT_ALLOCATION_FAILURE, 0, 0, -1, "cannot hold even one z-plane",
         true},
        {"copies, the third", "clEnqueueCopyBuffer", CL_OUT_OF_RESOURCES, 0, 2, 1, "out of memory"},
        {"downloads, the third", "clEnqueueReadBuffer", CL_OUT_OF_RESOURCES, 0, 2, 1, "out of memory"},
        {"mappings, the second", "clEnqueueMapBuffer", CL_OUT_OF_HOST_MEMORY, 0, 1, 1, "out of memory"},
    };
    for (const bool discrete : {false, true}) {
        detail::opencl_pretend_discrete(discrete);
        for (const auto& [volume, iso] : volumes) {
            Options o;
            o.iso = iso;
            o.chunk_planes = 8;
            const Mesh cpu = run(volume, o, Backend::Cpu);
            for (const Fault& fault : faults) {
                if (fault.discrete_only && !discrete) continue;
                for (const Backend backend : {Backend::OpenCL, Backend::Hybrid}) {
                    INFO((discrete ? "discrete, " : "host memory, ") << scalar_name(volume.type) << ", " << fault.what
                                                                      << (backend == Backend::OpenCL ? ", OpenCL" : ", Hybrid"));
                    release_scratch_memory();  // buffers kept from the last call would not be made again
                    layer.set(fault.kernel, fault.error, fault.buffer_over, fault.skip, fault.times);
                    Stats stats;
                    require_same(cpu, run(volume, o, backend, &stats), volume);
                    if (backend == Backend::OpenCL) {  // Hybrid's CPU worker may leave the device nothing to fail
                        CHECK(layer.given() > 0);
                        CHECK(has_warning(stats, fault.warning));
                    }
                    layer.clear();
                    require_same(cpu, run(volume, o, backend), volume);  // whole again
                }
            }
            // Another error ends the call with an Error that names it; the next call is whole.
            for (const char* kernel : {"classify_pack", "generate_triangles"}) {
                INFO(kernel);
                layer.set(kernel, CL_INVALID_COMMAND_QUEUE, 0, 0, 1);
                try {
                    (void)run(volume, o, Backend::OpenCL);
                    FAIL("no Error");
                } catch (const Error& e) {
                    CHECK_THAT(e.what(), Catch::Contains("CL_INVALID_COMMAND_QUEUE (-36)"));
                }
                CHECK(layer.given() == 1);
                layer.clear();
                require_same(cpu, run(volume, o, Backend::OpenCL), volume);
            }
        }
    }
    detail::opencl_pretend_discrete(false);
}
#endif  // VOXMESH_HAS_OPENCL

#ifdef VOXMESH_HAS_OPENCL
// Found by a review (forty-sixth session): a device that runs out of memory generating hands
// its piece to the CPU engine, which counts it again and generates it. For 8-bit samples the
// CPU's generate packs rows again and checks a row's vertices once written, so a row the
// caller's thread changed after that count writes past the counts first: into the row of
// spare room every device piece of an 8-bit volume gets. Without it, past the mesh (ASan).
TEST_CASE("a device's piece the CPU engine generates after a write stays within the mesh", "[.clfault]") {
    if (!vmtest::fault_layer_named()) return;
    const vmtest::FaultLayer layer = vmtest::fault_layer();
    REQUIRE(layer.loaded());
    REQUIRE(!list_devices().empty());
    const vmtest::ClearFaults clear{layer};

    Grid g{{64, 24, 20}};
    auto original = to_type<std::uint8_t>(sphere(g), 100, 100);  // 47..135
    // The last row of the last plane, outside but for its last sample (generate reads only rows
    // with crossings), becomes a comb of nx - 1 crossed x-edges.
    const std::size_t last_row = g.size() - g.dims[0];
    original.back() = 255;
    std::vector<std::uint8_t> u8 = original;
    const VolumeView volume = view_of(u8.data(), ScalarType::U8, g);
    for (const bool discrete : {false, true}) {
        INFO((discrete ? "discrete" : "host memory"));
        detail::opencl_pretend_discrete(discrete);
        Options o;
        o.iso = 100.5;
        o.devices = {0};
        o.chunk_planes = g.dims[2];  // one piece: the one with the last row
        int recounted = 0;
        {
            const BeforeGenerate comb([&](bool on_cpu) {
                if (!on_cpu || recounted++ > 0) return;
                for (std::size_t x = 0; x < g.dims[0]; ++x) u8[last_row + x] = x % 2 ? 255 : 0;
            });
            release_scratch_memory();
            layer.set("generate_vertices", CL_OUT_OF_RESOURCES, 0, 0, -1);
            CHECK_THROWS_WITH(run(volume, o, Backend::OpenCL), Catch::Contains("changed while it was being meshed"));
            layer.clear();
        }
        CHECK(recounted == 1);
        u8 = original;
        require_same(run(volume, o, Backend::Cpu), run(volume, o, Backend::OpenCL), volume);
    }
    detail::opencl_pretend_discrete(false);
}
#endif  // VOXMESH_HAS_OPENCL
