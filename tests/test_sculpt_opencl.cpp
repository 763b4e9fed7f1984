// Sculpting on an OpenCL device (PoCL in CI): after every update() each block mesh equals the
// CPU block mesher's (indices identical, positions and normals within a few ulps), and
// mesh() is extract's canonical mesh. Every [opencl] test returns with a visible WARN when no
// OpenCL device exists; the [fallback] one runs under ctest with no OpenCL platform.
#include <catch2/catch.hpp>

#include <voxmesh/sculpt.hpp>

#include "support/child_process.hpp"
#ifdef VOXMESH_HAS_OPENCL
#include "support/cl_fault.hpp"
#endif
#include "support/sculpt_fields.hpp"

#include "sculpt/device_blocks.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

namespace {

using voxmesh::Backend;
using voxmesh::BrushOp;
using voxmesh::Dab;
using voxmesh::Mesh;
using voxmesh::ScalarType;
using voxmesh::Sculpt;
using voxmesh::SculptOptions;
using Dims = std::array<std::size_t, 3>;

bool have_device() {
    if (!voxmesh::list_devices().empty()) return true;
    WARN("no OpenCL device found: this [opencl] test is SKIPPED");
    return false;
}

// Distance in representable floats between a and b (0 = same bits; +0 and -0 are 0 apart).
std::int64_t ulps(float a, float b) {
    const auto ordered = [](float f) {
        std::int32_t i;
        std::memcpy(&i, &f, 4);
        return i < 0 ? std::int64_t{INT32_MIN} - i : std::int64_t{i};
    };
    const std::int64_t d = ordered(a) - ordered(b);
    return d < 0 ? -d : d;
}

// Positions within `max_ulps`; normals (unit vectors, components near 0 have tiny ulps)
// within `max_ulps` float epsilons.
struct Tolerance {
    std::int64_t max_ulps = 4;
};
struct Worst {
    std::int64_t position_ulps = 0;
    double normal = 0;
};

void require_close(std::span<const float> a, std::span<const float> b, bool normals, const Tolerance& tol, Worst& worst) {
    REQUIRE(a.size() == b.size());
    const double normal_limit = double(tol.max_ulps) * 1.1920929e-7;
    std::size_t bad = a.size();  // the first component out of tolerance
    for (std::size_t i = 0; i < a.size(); ++i) {
        bool ok;
        if (normals) {
            const double d = std::abs(double(a[i]) - double(b[i]));
            worst.normal = std::max(worst.normal, d);
            ok = d <= normal_limit;
        } else {
            const std::int64_t u = ulps(a[i], b[i]);
            worst.position_ulps = std::max(worst.position_ulps, u);
            ok = u <= tol.max_ulps;
        }
        if (!ok && bad == a.size()) bad = i;
    }
    if (bad < a.size()) FAIL((normals ? "normal" : "position") << " component " << bad << ": " << a[bad] << " vs " << b[bad]);
}

// Every block of the OpenCL sculpt equals the CPU sculpt's block.
void require_same_blocks(const Sculpt& cpu, const Sculpt& cl, const Tolerance& tol, Worst& worst) {
    REQUIRE(cpu.block_count() == cl.block_count());
    for (std::size_t b = 0; b < cpu.block_count(); ++b) {
        const voxmesh::BlockMesh x = cpu.block(b), y = cl.block(b);
        INFO("block " << b);
        REQUIRE(x.indices.size() == y.indices.size());
        REQUIRE(std::equal(x.indices.begin(), x.indices.end(), y.indices.begin()));
        require_close(x.positions, y.positions, false, tol, worst);
        require_close(x.normals, y.normals, true, tol, worst);
    }
}

// mesh() of the OpenCL sculpt is extract's mesh: identical indices (so the same welded
// triangle set), vertices within the tolerance; closed where asked.
void require_mesh_equals_extract(Sculpt& s, bool closed, const Tolerance& tol, Worst& worst) {
    voxmesh::Options o;
    o.iso = s.options().iso;
    o.backend = Backend::Cpu;
    o.threads = 2;
    o.normals = s.options().normals;
    o.inside_below = s.options().inside_below;
    const Mesh want = voxmesh::extract(s.view(), o);
    const Mesh got = s.mesh();
    REQUIRE(got.indices == want.indices);
    require_close(got.positions, want.positions, false, tol, worst);
    require_close(got.normals, want.normals, true, tol, worst);
    if (closed) {
        const voxmesh::MeshTopology topo = voxmesh::analyze_topology(got);
        CHECK(topo.closed());
    }
}

using sculpt_test::balls;
using sculpt_test::kTypes;
using sculpt_test::random_op;
using sculpt_test::random_strength;
using sculpt_test::TypeSetup;

Sculpt make(const TypeSetup& ts, Dims d, std::size_t block, Backend backend) {
    SculptOptions o;
    o.iso = ts.iso;
    o.block_size = block;
    o.threads = 2;
    o.strength_scale = ts.scale;
    o.backend = backend;
    return Sculpt::from_function(d, ts.type, balls(d, ts.scale, ts.offset), o);
}

// A dab: random op and radius; centre anywhere, on a block corner, or beyond the border.
Dab random_dab(std::mt19937& rng, Dims d, std::size_t block, double scale, double offset) {
    std::uniform_real_distribution<double> u01(0, 1);
    Dab dab;
    dab.op = random_op(rng);
    dab.radius = 1 + u01(rng) * 6;
    const int where = static_cast<int>(u01(rng) * 3);
    for (int k = 0; k < 3; ++k) {
        const double n = double(d[k] - 1);
        if (where == 0) {
            dab.center[k] = u01(rng) * n;
        } else if (where == 1) {  // a block corner: up to 8 blocks change
            const std::size_t corners = (d[k] - 1) / block;
            dab.center[k] = double(block * static_cast<std::size_t>(u01(rng) * double(corners + 1)));
        } else {  // clipped at the border (or entirely outside)
            dab.center[k] = u01(rng) < 0.5 ? -u01(rng) * 3 : n + u01(rng) * 3;
        }
    }
    random_strength(dab, rng, scale, offset, 3.0);
    return dab;
}

// The same dabs on a CPU sculpt and an OpenCL sculpt; every update compared block by block.
void run_sequence(const TypeSetup& ts, Dims d, std::size_t block, std::uint32_t seed, int dabs, const Tolerance& tol,
                  Worst& worst) {
    Sculpt cpu = make(ts, d, block, Backend::Cpu);
    Sculpt cl = make(ts, d, block, Backend::OpenCL);
    REQUIRE(cl.backend() == Backend::OpenCL);
    REQUIRE(cpu.update().changed == cl.update().changed);
    require_same_blocks(cpu, cl, tol, worst);
    require_mesh_equals_extract(cl, true, tol, worst);
    std::mt19937 rng(seed);
    for (int i = 0; i < dabs; ++i) {
        const Dab dab = random_dab(rng, d, block, ts.scale, ts.offset);
        INFO("dab " << i << ": " << voxmesh::brush_op_name(dab.op) << " at " << dab.center[0] << ", " << dab.center[1]
                    << ", " << dab.center[2] << " r " << dab.radius);
        cpu.apply(dab);
        cl.apply(dab);
        const voxmesh::UpdateResult a = cpu.update(), b = cl.update();
        REQUIRE(a.changed == b.changed);
        REQUIRE(a.remeshed == b.remeshed);
        require_same_blocks(cpu, cl, tol, worst);
        if (i % 4 == 3) require_mesh_equals_extract(cl, false, tol, worst);
    }
    require_mesh_equals_extract(cl, false, tol, worst);
}

// The device mesher's test tuning while it lives, the defaults back however the test ends.
struct TuningScope {
    explicit TuningScope(const voxmesh::detail::sculpt::DeviceBlockTuning& tuning) {
        voxmesh::detail::sculpt::set_device_block_tuning(tuning);
    }
    ~TuningScope() { voxmesh::detail::sculpt::set_device_block_tuning({}); }
    TuningScope(const TuningScope&) = delete;
    TuningScope& operator=(const TuningScope&) = delete;
};

// run_sequence for every sample type under a device mesher tuning (seeds from `seed` on, six
// dabs each); returns the worst differences seen.
Worst run_every_type(const voxmesh::detail::sculpt::DeviceBlockTuning& tuning, Dims d, std::size_t block,
                     std::uint32_t seed, const Tolerance& tol) {
    const TuningScope tuning_scope(tuning);
    Worst worst;
    for (const TypeSetup& ts : kTypes) {
        INFO(voxmesh::scalar_name(ts.type));
        run_sequence(ts, d, block, seed++, 6, tol, worst);
    }
    return worst;
}

}  // namespace

TEST_CASE("sculpt OpenCL: random edit sequences give the CPU's block meshes and extract's mesh", "[sculpt][opencl]") {
    if (!have_device()) return;
    Worst worst;
    std::uint32_t seed = 7;
    for (const TypeSetup& ts : kTypes) {
        // Block sizes that do not divide the cells (28 x 22 x 25 cells).
        for (std::size_t block : {std::size_t{8}, std::size_t{5}}) {
            INFO(voxmesh::scalar_name(ts.type) << " block " << block << " seed " << seed);
            run_sequence(ts, {29, 23, 26}, block, seed++, 12, Tolerance{}, worst);
        }
    }
    // fp64 devices (PoCL) compute exactly the CPU's double formula.
    const auto devices = voxmesh::list_devices();
    if (devices.front().fp64) {
        CHECK(worst.position_ulps == 0);
        CHECK(worst.normal == 0);
    }
}

TEST_CASE("sculpt OpenCL: float vertex math (devices without fp64) stays within a few ulps", "[sculpt][opencl]") {
    if (!have_device()) return;
    voxmesh::detail::sculpt::DeviceBlockTuning tuning;
    tuning.no_fp64 = true;
    const Worst worst = run_every_type(tuning, {25, 27, 22}, 7, 101, Tolerance{4});
    INFO("worst position ulps " << worst.position_ulps << ", worst normal difference " << worst.normal);
    CHECK(worst.position_ulps <= 4);  // PoCL: 1 ulp, normals within 1 epsilon
}

// The row scans as a GPU runs them (work-groups of 256 items of 8 rows, where PoCL runs 1 of
// 1024): the first update meshes all 48 blocks in one batch of 2,900 rows, more than one GPU
// scan block of 2,048, so a block's offset is used.
TEST_CASE("sculpt OpenCL: row scans in GPU work-groups give the CPU's block meshes", "[sculpt][opencl]") {
    if (!have_device()) return;
    voxmesh::detail::sculpt::DeviceBlockTuning tuning;
    tuning.gpu_scans = true;
    run_every_type(tuning, {29, 23, 26}, 8, 301, Tolerance{});
}

TEST_CASE("sculpt OpenCL: spacing, origin, inside_below, normals off and many small batches", "[sculpt][opencl]") {
    if (!have_device()) return;
    voxmesh::detail::sculpt::DeviceBlockTuning tuning;
    tuning.batch_samples = 600;  // a few blocks per batch: every update runs several batches
    const TuningScope tuning_scope(tuning);
    Worst worst;
    const Dims d{24, 21, 19};
    for (bool inside_below : {false, true}) {
        for (bool normals : {true, false}) {
            INFO("inside_below " << inside_below << " normals " << normals);
            SculptOptions o;
            o.block_size = 6;
            o.inside_below = inside_below;
            o.normals = normals;
            o.iso = 0.25;
            const auto field = balls(d, 1, 0);
            std::vector<float> samples(d[0] * d[1] * d[2]);
            for (std::size_t i = 0; i < samples.size(); ++i)
                samples[i] = float(field(double(i % d[0]), double(i / d[0] % d[1]), double(i / (d[0] * d[1]))));
            voxmesh::VolumeView v;
            v.data = samples.data();
            v.dims = d;
            v.spacing = {0.5, 0.75, 1.25};
            v.origin = {-3, 2, 7.5};
            Sculpt cpu(v, o);
            o.backend = Backend::OpenCL;
            Sculpt cl(v, o);
            REQUIRE(cl.backend() == Backend::OpenCL);
            cpu.update();
            cl.update();
            require_same_blocks(cpu, cl, Tolerance{}, worst);
            for (Sculpt* s : {&cpu, &cl}) {
                s->add({5, 6, 7}, 4, 1.5);
                s->subtract({12, 12, 12}, 5, 2);  // a block corner
                s->set_region({20, -3, 15}, {30, 4, 30}, -1);  // clipped at three faces
                s->update();
            }
            require_same_blocks(cpu, cl, Tolerance{}, worst);
            require_mesh_equals_extract(cl, false, Tolerance{}, worst);
        }
    }
}

TEST_CASE("sculpt OpenCL: the device path is chosen, named and checked", "[sculpt][opencl]") {
    if (!have_device()) return;
    SculptOptions o;
    o.backend = Backend::OpenCL;
    Sculpt s = Sculpt::from_function({12, 12, 12}, ScalarType::F32, balls({12, 12, 12}, 1, 0), o);
    CHECK(s.backend() == Backend::OpenCL);
    CHECK(s.device_name() == voxmesh::list_devices().front().name);
    o.device = static_cast<int>(voxmesh::list_devices().size());
    CHECK_THROWS_WITH(Sculpt::from_function({12, 12, 12}, ScalarType::F32, balls({12, 12, 12}, 1, 0), o),
                      Catch::Contains("does not exist"));
    o.device = -1;
    o.backend = Backend::Hybrid;
    CHECK_THROWS_WITH(Sculpt::from_function({12, 12, 12}, ScalarType::F32, balls({12, 12, 12}, 1, 0), o),
                      Catch::Contains("hybrid"));
    // Auto on a machine whose only OpenCL devices are CPUs keeps the CPU's threads.
    bool gpu = false;
    for (const auto& d : voxmesh::list_devices()) gpu = gpu || d.type != voxmesh::DeviceType::Cpu;
    o.backend = Backend::Auto;
    Sculpt a = Sculpt::from_function({12, 12, 12}, ScalarType::F32, balls({12, 12, 12}, 1, 0), o);
    CHECK(a.backend() == (gpu ? Backend::OpenCL : Backend::Cpu));
}

// Run by ctest with OCL_ICD_VENDORS pointing at an empty directory (tests/opencl.cmake).
TEST_CASE("sculpt OpenCL: without an OpenCL platform update() meshes on the CPU, with a warning",
          "[sculpt][opencl][fallback]") {
    if (!voxmesh::list_devices().empty()) {
        WARN("an OpenCL device is present: the fallback test only runs with OCL_ICD_VENDORS=<empty dir> (ctest)");
        return;
    }
    std::vector<std::string> logged;
    SculptOptions o;
    o.backend = Backend::OpenCL;
    o.log = [&](const std::string& m) { logged.push_back(m); };
    const Dims d{20, 18, 22};
    Sculpt s = Sculpt::from_function(d, ScalarType::F32, balls(d, 1, 0), o);
    CHECK(s.backend() == Backend::Cpu);
    CHECK(s.device_name() == "cpu");
    REQUIRE(logged.size() == 1);
    CHECK_THAT(logged[0], Catch::Contains("OpenCL") && Catch::Contains("CPU"));
    s.add({10, 9, 11}, 4, 2);
    Worst worst;
    require_mesh_equals_extract(s, true, Tolerance{0}, worst);
}

// A Sculpt meshing on OpenCL, carried into a forked child: its device's objects belong to the
// parent's runtime, whose threads the child lacks (meshing, or even releasing them, waited for
// ever there). In the child it re-meshes on the CPU with a warning and is destroyed cleanly;
// the mesh is extract's, as ever.
TEST_CASE("sculpt: a Sculpt on OpenCL in a forked child re-meshes on the CPU", "[sculpt][opencl]") {
    if (!have_device()) return;
    if (!vmtest::threads_after_fork_or_warn()) return;
    std::vector<std::string> warnings;
    SculptOptions options;
    options.backend = Backend::OpenCL;
    options.threads = 2;
    options.log = [&](const std::string& m) { warnings.push_back(m); };
    auto sculpt = std::make_unique<Sculpt>(voxmesh::make_sculpt_sphere(48, options));
    sculpt->update();
    REQUIRE(sculpt->backend() == Backend::OpenCL);
    const std::string device = sculpt->device_name();
    const std::string child = vmtest::output_of_child(
        [&] {
            sculpt->add({24, 24, 24}, 6, 1);
            sculpt->update();
            if (sculpt->backend() != Backend::Cpu) return std::string("still on ") + sculpt->device_name();
            const Mesh mesh = sculpt->mesh();
            voxmesh::Options cpu;
            cpu.backend = Backend::Cpu;
            cpu.iso = sculpt->options().iso;
            if (mesh.indices != voxmesh::extract(sculpt->view(), cpu).indices) return std::string("another mesh");
            sculpt.reset();
            return warnings.size() == 1 ? warnings[0] : std::to_string(warnings.size()) + " warnings";
        },
        60);
    CHECK(child == device + " was opened before this process was forked and cannot be used in the child; sculpt "
                            "re-meshes on the CPU from now on");
    sculpt->add({24, 24, 24}, 6, 1);  // the parent's device still works
    sculpt->update();
    CHECK(sculpt->backend() == Backend::OpenCL);
    CHECK(warnings.empty());
}

#ifdef VOXMESH_HAS_OPENCL
// Run by ctest as voxmesh_opencl_faults, with the fault layer loaded (tests/opencl.cmake): an
// OpenCL error in update(), out of memory or not, drops the device with a warning naming it;
// that update() and the later ones re-mesh on the CPU and give what the device would have.
TEST_CASE("sculpt OpenCL: a device that fails in update() hands the sculpt to the CPU", "[.clfault]") {
    if (!vmtest::fault_layer_named()) return;  // run by name without the layer: skipped, with a warning
    const vmtest::FaultLayer layer = vmtest::fault_layer();
    REQUIRE(layer.loaded());
    REQUIRE(have_device());
    const vmtest::ClearFaults clear{layer};
    voxmesh::detail::sculpt::DeviceBlockTuning tuning;
    tuning.batch_samples = 600;  // several batches: the failing one comes after others were stored
    const TuningScope tuning_scope(tuning);
    Worst worst;
    const struct {
        const char* kernel;
        int error;
        const char* named;
    } faults[] = {{"block_vertices", CL_OUT_OF_RESOURCES, "CL_OUT_OF_RESOURCES"},
                  {"block_triangles", CL_INVALID_COMMAND_QUEUE, "CL_INVALID_COMMAND_QUEUE"},
                  {"block_classify", CL_MEM_OBJECT_ALLOCATION_FAILURE, "CL_MEM_OBJECT_ALLOCATION_FAILURE"}};
    const TypeSetup& ts = kTypes[1];  // u8
    const Dims d{29, 23, 26};
    for (const auto& fault : faults) {
        INFO(fault.kernel);
        Sculpt cpu = make(ts, d, 5, Backend::Cpu);
        SculptOptions o = cpu.options();
        o.backend = Backend::OpenCL;
        std::vector<std::string> warnings;
        o.log = [&](const std::string& w) { warnings.push_back(w); };
        Sculpt cl = Sculpt::from_function(d, ts.type, balls(d, ts.scale, ts.offset), o);
        REQUIRE(cl.backend() == Backend::OpenCL);
        cpu.update();
        cl.update();
        for (Sculpt* s : {&cpu, &cl}) s->add({9, 11, 13}, 6, 2);  // over several blocks
        const voxmesh::UpdateResult want = cpu.update();
        layer.set(fault.kernel, fault.error, 0, 2, 1);  // the third launch: batches before it were stored
        const voxmesh::UpdateResult got = cl.update();
        CHECK(layer.given() == 1);
        layer.clear();
        CHECK(got.changed == want.changed);
        CHECK(cl.backend() == Backend::Cpu);
        REQUIRE(warnings.size() == 1);
        CHECK_THAT(warnings[0], Catch::Contains(fault.named) && Catch::Contains("re-meshes on the CPU"));
        require_same_blocks(cpu, cl, Tolerance{}, worst);
        for (Sculpt* s : {&cpu, &cl}) s->subtract({14, 12, 12}, 5, 2);
        CHECK(cpu.update().changed == cl.update().changed);
        require_same_blocks(cpu, cl, Tolerance{}, worst);
        require_mesh_equals_extract(cl, false, Tolerance{}, worst);
    }
}
#endif  // VOXMESH_HAS_OPENCL
