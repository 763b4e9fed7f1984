// Schedule stress: random volumes, options and OpenCL schedules; every engine must give the
// canonical mesh, taken from the CPU engine on one thread.
//
// What is compared is what DESIGN.md "The canonical mesh" promises:
//   - the CPU engine on any thread count: bit for bit (as tests/test_core_determinism.cpp);
//   - OpenCL and Hybrid: the same index buffer; positions and normals within the bounds of
//     tests/test_opencl.cpp (devices may round differently: "a few ulps");
//   - f64 samples on a device without fp64 are converted to float on the way, which moves
//     t (as test_opencl.cpp's range test notes): the index buffer only.
// VOXMESH_STRESS_SEED and VOXMESH_STRESS_ITERATIONS override the seed and the case count;
// VOXMESH_STRESS_SPLIT=0 leaves out the cases on split devices (see draw_case).
// Under ctest's voxmesh_opencl_faults_stress the fault layer (tests/cl_fault_layer) is loaded:
// each case then also fails one OpenCL call as a device out of memory would, drawn apart from
// the case (the same seed draws the same case with or without it), and the mesh must not change.
// Case i draws everything from seed + i, so a failure's case seed replays that case alone:
//   VOXMESH_STRESS_SEED=<case seed> VOXMESH_STRESS_ITERATIONS=1 voxmesh_tests "[stress]"
// (its settings replay; the timing of its schedule may not).
#include <catch2/catch.hpp>
#include <voxmesh/voxmesh.hpp>

#include "support/mesh_checks.hpp"
#ifdef VOXMESH_HAS_OPENCL
#include "support/cl_fault.hpp"
#endif

#include "core/opencl_hook.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

using namespace voxmesh;
using vmtest::Dims;

namespace {

constexpr std::uint64_t kDefaultSeed = 20250607;
constexpr std::uint64_t kDefaultIterations = 300;

std::uint64_t env_number(const char* name, std::uint64_t fallback) {
    const char* text = std::getenv(name);
    if (!text || !*text) return fallback;
    const char* end = text + std::strlen(text);
    std::uint64_t value = 0;
    const auto [stop, error] = std::from_chars(text, end, value);
    if (error != std::errc() || stop != end) FAIL(name << " is not a number: '" << text << "'");
    return value;
}

// mt19937_64's sequence is fixed by the standard, the std distributions' is not: plain
// arithmetic on it draws a seed's cases alike under every standard library.
class Draw {
public:
    explicit Draw(std::uint64_t seed) : rng_(seed) {}
    std::size_t between(std::size_t lo, std::size_t hi) { return lo + static_cast<std::size_t>(rng_() % (hi - lo + 1)); }
    double uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
    bool chance(double p) { return uniform(0, 1) < p; }
    std::uint32_t seed32() { return static_cast<std::uint32_t>(rng_()); }

private:
    std::mt19937_64 rng_;
};

using Samples = std::variant<std::vector<std::uint8_t>, std::vector<std::int16_t>, std::vector<float>, std::vector<double>>;

// Which OpenCL devices a case names: Hybrid leaves a CPU device (PoCL) out unless named.
enum class Pick { All, First, Last, CpuType };
const char* pick_name(Pick p) {
    return p == Pick::All ? "all named" : p == Pick::First ? "first" : p == Pick::Last ? "last" : "device_type cpu";
}

struct Case {
    std::uint64_t seed = 0;
    Dims dims{2, 2, 2};
    std::array<double, 3> spacing{1, 1, 1}, origin{0, 0, 0};
    std::string field;
    Samples samples;
    Options options;             // iso, normals, inside_below, chunk_planes, memory_budget
    unsigned threads = 1;        // of the second CPU run and of the OpenCL and Hybrid runs
    bool reuse_storage = false;  // extract_into a mesh left over from earlier runs
    // Schedule hooks (core/opencl_hook.hpp).
    bool split = false, deal = false, discrete = false, no_fp64 = false;
    std::size_t staging_bytes = 0;
    std::array<double, 4> slow{0, 0, 0, 0};  // device count, device generate, CPU count, CPU start (s)
    Pick pick = Pick::All;

    VolumeView view() const {
        return std::visit([&](const auto& v) { return vmtest::view_of(v, dims, spacing, origin); }, samples);
    }
    std::string describe() const {
        std::ostringstream s;
        s.precision(17);
        s << "case seed " << seed << " (replay: VOXMESH_STRESS_SEED=" << seed << " VOXMESH_STRESS_ITERATIONS=1"
          << (split ? " VOXMESH_STRESS_SPLIT=1" : "") << ")\n"
          << "  volume " << dims[0] << "x" << dims[1] << "x" << dims[2] << " " << scalar_name(view().type) << " "
          << field << ", spacing " << spacing[0] << "," << spacing[1] << "," << spacing[2] << ", origin " << origin[0]
          << "," << origin[1] << "," << origin[2] << "\n  options: iso " << options.iso << ", threads " << threads
          << ", normals " << options.normals << ", inside_below " << options.inside_below << ", chunk_planes "
          << options.chunk_planes << ", memory_budget " << options.memory_budget << ", reuse storage "
          << reuse_storage << "\n  hooks: split " << split << ", deal " << deal << ", discrete " << discrete
          << ", staging bytes " << staging_bytes << ", no_fp64 " << no_fp64 << ", devices " << pick_name(pick);
        s.precision(3);
        s << ", slow (ms: device count/generate, CPU count/start) " << 1e3 * slow[0] << "/" << 1e3 * slow[1] << "/"
          << 1e3 * slow[2] << "/" << 1e3 * slow[3];
        return s.str();
    }
};

// A field in index coordinates: most cut or touch the border somewhere; "constant" has no surface.
vmtest::FieldFn draw_field(Draw& d, const Dims& n, std::string& name) {
    const std::array<double, 3> size{double(n[0]), double(n[1]), double(n[2])};
    const double big = std::max({size[0], size[1], size[2]});
    auto point = [&](double lo, double hi) {  // in units of the volume's size: may lie outside
        return std::array<double, 3>{d.uniform(lo, hi) * size[0], d.uniform(lo, hi) * size[1], d.uniform(lo, hi) * size[2]};
    };
    switch (d.between(0, 6)) {
    case 0:
        name = "sphere";
        return vmtest::sphere(point(-0.25, 1.25), d.uniform(0.3, big));
    case 1:
        name = "torus";
        return vmtest::torus(point(0.2, 0.8), d.uniform(1, big / 2), d.uniform(0.4, 3));
    case 2:
        name = "two spheres";
        return vmtest::two_spheres(point(0, 1), d.uniform(0.5, big / 3), point(0, 1), d.uniform(0.5, big / 3));
    case 3:
        name = "wavy";
        return vmtest::wavy(d.uniform(0.2, 1.5));
    case 4: {  // a tilted plane: the surface runs into the border
        name = "plane";
        const double a = d.uniform(-1, 1), b = d.uniform(-1, 1), c = d.uniform(-1, 1), at = d.uniform(0, big);
        return [=](double x, double y, double z) { return a * (x - at) + b * y + c * z; };
    }
    case 5: {  // integer noise: crossings in most cells, every cube case
        name = "noise";
        const int span = static_cast<int>(d.between(1, 40));
        const auto values = std::make_shared<const std::vector<double>>(vmtest::random_doubles(n, d.seed32(), -span, span));
        return [values, n](double x, double y, double z) {
            return (*values)[std::size_t(x) + n[0] * (std::size_t(y) + n[1] * std::size_t(z))];
        };
    }
    default: {
        name = "constant";
        const double value = d.uniform(-3, 3);
        return [value](double, double, double) { return value; };
    }
    }
}

template <class T>
Samples typed(const Dims& dims, const vmtest::FieldFn& f, double offset, double scale) {
    return vmtest::sample_field<T>(dims, [&](double x, double y, double z) { return offset + scale * f(x, y, z); });
}

// An iso between the samples' extremes; sometimes one no sample reaches, everything inside,
// or (integers) exactly a sample value, where vertices sit on samples.
double draw_iso(Draw& d, const Samples& samples, bool integer) {
    const auto [lo, hi] = std::visit(
        [](const auto& v) {
            const auto [a, b] = std::minmax_element(v.begin(), v.end());
            return std::pair<double, double>(double(*a), double(*b));
        },
        samples);
    const std::size_t kind = d.between(0, 19);
    if (kind == 0) return hi + d.uniform(0.25, 10);  // nothing inside
    if (kind == 1) return lo;                        // everything inside (value >= iso)
    if (kind == 2 && !integer) return d.chance(0.5) ? 1e300 : -1e300;  // past float's range
    const double iso = lo + d.uniform(0, 1) * (hi - lo);
    return integer && d.chance(0.3) ? std::round(iso) : iso;
}

Case draw_case(std::uint64_t seed, bool allow_split) {
    Draw d(seed);
    Case c;
    c.seed = seed;
    for (auto& n : c.dims) n = d.between(2, 48);
    if (d.chance(0.25)) c.dims[d.between(0, 2)] = 2;  // a single layer of cells
    for (int a = 0; a < 3; ++a) {
        c.spacing[a] = d.chance(0.5) ? 1.0 : d.uniform(0.25, 3);
        c.origin[a] = d.chance(0.5) ? 0.0 : d.uniform(-10, 10);
    }
    const vmtest::FieldFn f = draw_field(d, c.dims, c.field);
    // Scaled into each type's range; integers clamp, and plateaus at the ends are cases too.
    const std::size_t type = d.between(0, 3);
    if (type == 0) c.samples = typed<std::uint8_t>(c.dims, f, 128, d.uniform(5, 60));
    else if (type == 1) c.samples = typed<std::int16_t>(c.dims, f, 0, d.uniform(50, 5000));
    else if (type == 2) c.samples = typed<float>(c.dims, f, 0, d.uniform(0.01, 100));
    else c.samples = typed<double>(c.dims, f, 0, d.uniform(0.01, 100));

    Options& o = c.options;
    o.iso = draw_iso(d, c.samples, type < 2);
    o.normals = d.chance(0.7);
    o.inside_below = d.chance(0.25);
    o.chunk_planes = d.chance(0.4) ? 0 : d.between(1, c.dims[2]);
    const std::size_t budget = d.between(0, 19);  // bytes a device may use for one chunk
    if (budget == 0) o.memory_budget = 100;     // not one plane: those chunks go to the CPU engine
    else if (budget <= 3) o.memory_budget = c.dims[0] * c.dims[1] * d.between(8, 200);
    c.threads = static_cast<unsigned>(d.between(1, 6));
    c.reuse_storage = d.chance(0.3);

    // Sub-devices made and undone between cases: undoing them used to crash PoCL's worker
    // thread (src/cl/cl_runtime.cpp, split_devices). Drawn either way, so that a seed draws
    // the same case with or without them.
    c.split = d.chance(0.2) && allow_split;
    c.deal = d.chance(0.5);
    c.discrete = d.chance(0.35);
    c.no_fp64 = d.chance(0.3);
    c.staging_bytes = d.chance(0.5) ? 0 : d.between(200, 5000);  // odd sizes: samples straddle blocks
    for (double& s : c.slow) s = d.chance(0.3) ? d.uniform(0, 0.002) : 0;  // tiny: the order changes, the test stays quick
    c.pick = static_cast<Pick>(d.between(0, 3));
    return c;
}

#ifdef VOXMESH_HAS_OPENCL
// One OpenCL call a case fails as out of memory: a kernel's launch or a transfer (after `skip`
// such calls went through; `times` of them, negative for all), or buffers over some size.
struct Fault {
    const char* call = "";
    int error = CL_MEM_OBJECT_ALLOCATION_FAILURE;
    unsigned long long buffer_over = 0, skip = 0;
    long long times = 0;

    std::string describe() const {
        std::ostringstream s;
        s << "  fault: " << (*call ? call : "buffers over ") << (*call ? "" : std::to_string(buffer_over)) << " fails ("
          << error << ") after " << skip << " calls, " << (times < 0 ? std::string("every time") : std::to_string(times) + " times");
        return s.str();
    }
};

Fault draw_fault(std::uint64_t seed) {
    static const char* const kCalls[] = {"classify_pack",       "classify_rows",        "classify_repack",
                                         "generate_vertices",   "generate_triangles",   "clEnqueueWriteBuffer",
                                         "clEnqueueCopyBuffer", "clEnqueueReadBuffer",  "clEnqueueMapBuffer",
                                         ""};
    static const int kErrors[] = {CL_MEM_OBJECT_ALLOCATION_FAILURE, CL_OUT_OF_RESOURCES, CL_OUT_OF_HOST_MEMORY};
    Draw d(seed ^ 0x5eedfau);  // apart from draw_case's sequence
    Fault f;
    f.call = kCalls[d.between(0, std::size(kCalls) - 1)];
    f.error = kErrors[d.between(0, std::size(kErrors) - 1)];
    if (!*f.call) f.buffer_over = d.between(200, 40000);
    f.skip = d.between(0, 3);
    f.times = d.chance(0.25) ? -1 : static_cast<long long>(d.between(1, 3));
    return f;
}
#endif

// "" when `got` is `want` as promised, else the first difference. bitwise: every float bit
// equal; else positions within pos_tol and normals within 1e-3; indices_only: the index
// buffer and the array sizes alone.
std::string difference(const Mesh& want, const Mesh& got, bool bitwise, bool indices_only, double pos_tol) {
    std::ostringstream s;
    s.precision(9);
    if (got.indices.size() != want.indices.size() || got.positions.size() != want.positions.size() ||
        got.normals.size() != want.normals.size()) {
        s << "sizes differ: triangles " << got.triangle_count() << " (want " << want.triangle_count() << "), vertices "
          << got.vertex_count() << " (want " << want.vertex_count() << "), normal floats " << got.normals.size()
          << " (want " << want.normals.size() << ")";
        return s.str();
    }
    const auto at = std::mismatch(want.indices.begin(), want.indices.end(), got.indices.begin());
    if (at.first != want.indices.end()) {
        const std::size_t i = static_cast<std::size_t>(at.first - want.indices.begin());
        s << "index buffer differs first at " << i << " (triangle " << i / 3 << " of " << want.triangle_count()
          << "): " << *at.second << ", want " << *at.first;
        return s.str();
    }
    if (indices_only) return "";
    struct Worst {
        double error = 0;
        std::size_t at = 0;
    };
    auto worst = [&](const std::vector<float>& a, const std::vector<float>& b) {
        Worst w;
        for (std::size_t i = 0; i < a.size(); ++i) {
            const double e = bitwise ? (std::memcmp(&a[i], &b[i], sizeof(float)) != 0 ? 1.0 : 0.0)
                                     : std::abs(double(a[i]) - double(b[i]));
            if (!std::isnan(w.error) && !(e <= w.error)) w = {e, i};  // a NaN is the worst, and stays
            if (bitwise && w.error > 0) break;
        }
        return w;
    };
    const Worst p = worst(want.positions, got.positions), n = worst(want.normals, got.normals);
    const bool positions_bad = bitwise ? p.error > 0 : !(p.error <= pos_tol);
    const bool normals_bad = bitwise ? n.error > 0 : !(n.error <= 1e-3);
    if (positions_bad || normals_bad) {
        const bool pos = positions_bad;
        const std::size_t i = pos ? p.at : n.at;
        const std::vector<float>& a = pos ? want.positions : want.normals;
        const std::vector<float>& b = pos ? got.positions : got.normals;
        s << (pos ? "position" : "normal") << " of vertex " << i / 3 << " of " << want.vertex_count() << ", axis "
          << i % 3 << ": " << b[i] << ", want " << a[i];
        if (!bitwise) s << " (difference " << (pos ? p.error : n.error) << ", allowed " << (pos ? pos_tol : 1e-3) << ")";
    }
    return s.str();
}

#ifdef VOXMESH_HAS_OPENCL
// Puts every schedule hook back to its default when a case ends, on a failure or an
// exception too: the tests after this one run in the same process.
struct RestoreHooks {
    RestoreHooks() = default;
    RestoreHooks(const RestoreHooks&) = delete;
    RestoreHooks& operator=(const RestoreHooks&) = delete;
    ~RestoreHooks() {
        detail::opencl_pretend_slow(0, 0, 0, 0);
        detail::opencl_deal_first_chunks(false);
        detail::opencl_pretend_discrete(false);
        detail::opencl_pretend_no_fp64(false);
        detail::opencl_staging_block_bytes(0);
        detail::opencl_split_devices(false);
    }
};
#endif

}  // namespace

TEST_CASE("Every engine gives the one-thread CPU mesh under random volumes, options and schedules",
          "[stress][hybrid]") {
    const std::uint64_t seed = env_number("VOXMESH_STRESS_SEED", kDefaultSeed);
    const std::uint64_t iterations = env_number("VOXMESH_STRESS_ITERATIONS", kDefaultIterations);
    const bool allow_split = env_number("VOXMESH_STRESS_SPLIT", 1) != 0;
    const bool opencl = !list_devices().empty();
#ifdef VOXMESH_HAS_OPENCL
    const vmtest::FaultLayer faults = vmtest::fault_layer();
    // Named but not loaded (ocl-icd without layers): the cases would run without one fault.
    if (std::getenv("OPENCL_LAYERS") != nullptr) REQUIRE(faults.loaded());
    const vmtest::ClearFaults clear_faults{faults};
    if (faults.loaded()) WARN("the fault layer is loaded: every case fails an OpenCL call as out of memory");
#endif
    if (!opencl) WARN("no OpenCL device found: the OpenCL and Hybrid comparisons of this [stress] test are SKIPPED");
    Mesh leftover;  // storage reused by extract_into, dirty from earlier runs
#ifdef VOXMESH_HAS_OPENCL
    std::size_t runs_faulted = 0;  // OpenCL and Hybrid runs the fault layer failed a call of
#endif
    std::size_t failed_cases = 0;
    double slowest_s = 0;
    std::string slowest;
    for (std::uint64_t i = 0; i < iterations && failed_cases < 5; ++i) {
        const Case c = draw_case(seed + i, allow_split);
        std::string description = c.describe();
#ifdef VOXMESH_HAS_OPENCL
        const Fault fault = draw_fault(seed + i);
        if (faults.loaded()) description += "\n" + fault.describe();
#endif
        INFO(description);
        const auto started = std::chrono::steady_clock::now();
        const VolumeView view = c.view();
        bool failed = false;
        // One engine's mesh, compared; an exception is that engine's failure, not the test's.
        auto check = [&](const char* label, Options o, Backend backend, unsigned threads, const Mesh& want,
                         bool bitwise, bool indices_only, double pos_tol) {
            o.backend = backend;
            o.threads = threads;
            Mesh got = c.reuse_storage ? std::move(leftover) : Mesh{};
            Stats stats;
            std::string problem;
            try {
#ifdef VOXMESH_HAS_OPENCL
                if (faults.loaded() && backend != Backend::Cpu)
                    faults.set(fault.call, fault.error, fault.buffer_over, fault.skip, fault.times);
                const vmtest::ClearFaults clear{faults};
#endif
                extract_into(view, o, got, stats);
#ifdef VOXMESH_HAS_OPENCL
                if (faults.loaded() && faults.given() > 0) ++runs_faulted;
#endif
                problem = difference(want, got, bitwise, indices_only, pos_tol);
                // The engine really ran (an iso no sample can cross is answered by the CPU
                // engine alone: cl_engine.cpp), or the comparison would be vacuous. An OpenCL
                // call whose every chunk fell back (a budget no plane fits) says Cpu, and lists
                // the fallback.
                const bool all_fell_back =
                    backend == Backend::OpenCL && stats.backend == Backend::Cpu &&
                    std::any_of(stats.devices.begin(), stats.devices.end(),
                                [](const DeviceStats& d) { return d.name == "cpu (fallback)"; });
                if (problem.empty() && stats.backend != backend && !all_fell_back && !want.indices.empty())
                    problem = std::string("ran as backend ") + backend_name(stats.backend);
            } catch (const std::exception& e) {
                problem = std::string("threw: ") + e.what();
            }
            if (!problem.empty()) {
                failed = true;
                FAIL_CHECK(label << ": " << problem);
            }
            leftover = std::move(got);
        };

        Options o = c.options;
        o.backend = Backend::Cpu;
        o.threads = 1;
        Mesh want;
        try {
            want = extract(view, o);
        } catch (const std::exception& e) {
            FAIL_CHECK("CPU engine, 1 thread, threw: " << e.what());
            ++failed_cases;
            continue;
        }
        CHECK(vmtest::structural_problem(want).empty());
        check("CPU engine", o, Backend::Cpu, c.threads, want, true, false, 0);

#ifdef VOXMESH_HAS_OPENCL
        if (opencl) {
            const RestoreHooks restore;
            detail::opencl_split_devices(c.split);  // first: it renumbers list_devices()
            detail::opencl_deal_first_chunks(c.deal);
            detail::opencl_pretend_discrete(c.discrete);
            detail::opencl_pretend_no_fp64(c.no_fp64);
            detail::opencl_staging_block_bytes(c.staging_bytes);
            detail::opencl_pretend_slow(c.slow[0], c.slow[1], c.slow[2], c.slow[3]);
            const std::vector<DeviceInfo> devices = list_devices();
            const int count = static_cast<int>(devices.size());
            const bool has_cpu_device = std::any_of(devices.begin(), devices.end(),
                                                    [](const DeviceInfo& info) { return info.type == DeviceType::Cpu; });
            if (c.pick == Pick::First) o.devices = {0};
            else if (c.pick == Pick::Last) o.devices = {count - 1};
            else if (c.pick == Pick::CpuType && has_cpu_device) o.device_type = DeviceType::Cpu;
            else  // all, also for CpuType on a machine whose devices are all GPUs
                for (int d = 0; d < count; ++d) o.devices.push_back(d);
            // The bound of test_opencl.cpp (1e-5 of the extent), taken of the largest
            // coordinate: a far origin's floats have larger ulps.
            double largest = 0;
            for (int a = 0; a < 3; ++a)
                largest = std::max(largest, std::abs(c.origin[a]) + double(c.dims[a] - 1) * c.spacing[a]);
            const bool converted = c.no_fp64 && view.type == ScalarType::F64;
            check("OpenCL", o, Backend::OpenCL, c.threads, want, false, converted, 1e-5 * largest);
            check("Hybrid", o, Backend::Hybrid, c.threads, want, false, converted, 1e-5 * largest);
        }
#endif
        const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        if (took > slowest_s) {
            slowest_s = took;
            slowest = description;
        }
        if (failed) ++failed_cases;
    }
#ifdef VOXMESH_HAS_OPENCL
    // Most drawn faults meet a call they fail (not all: a Hybrid run may leave the device nothing).
    if (faults.loaded() && opencl) {
        WARN("the fault layer failed a call in " << runs_faulted << " of " << 2 * iterations << " OpenCL and Hybrid runs");
        CHECK(runs_faulted >= iterations / 2);
    }
#endif
    // Not asserted (speed is measured in bench/): a case that stalls shows here.
    if (slowest_s > 3) WARN("the slowest case took " << slowest_s << " s:\n" << slowest);
}
