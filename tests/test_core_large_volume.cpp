// A volume of more than 2^32 samples: every index past 32 bits must stay 64-bit.
//
// The samples live in an anonymous private mapping. Pages never written read as the kernel's
// shared zero page, so the 4.4 G-sample volume costs only the pages the two spheres touch:
// the test is cheap in memory, and the engines still read every sample.
#include <catch2/catch.hpp>

#include "support/mesh_checks.hpp"
#include "support/reference_mc.hpp"
#include "support/sanitizers.hpp"

#include <voxmesh/voxmesh.hpp>

#include <sys/mman.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

using vmtest::Dims;

namespace {

// nx * ny = 4e6 does not divide 2^32, so sample 2^32 falls inside a row: (1296, 1483, 1073).
constexpr Dims kDims{2000, 2000, 1110};
constexpr std::size_t kSample2to32[3] = {1296, 1483, 1073};

struct Ball {
    double x, y, z, r;
};
// One ball around sample 2^32, one wholly beyond it; disjoint, so Euler characteristic 4.
constexpr Ball kBalls[] = {{1296.3, 1483.4, 1073.2, 20}, {1330.6, 1470.2, 1090.7, 12}};
// The samples around both balls, with a margin of 3 samples past each surface.
constexpr std::size_t kBoxMin[3] = {1272, 1455, 1050}, kBoxMax[3] = {1346, 1507, 1106};  // exclusive

template <typename T>
T ball_sample(double x, double y, double z) {
    double v = 0;  // 0 far from both balls, rising to 255 inside
    for (const Ball& b : kBalls) {
        const double d = std::sqrt((x - b.x) * (x - b.x) + (y - b.y) * (y - b.y) + (z - b.z) * (z - b.z));
        v = std::max(v, std::clamp(128 + 20 * (b.r - d), 0.0, 255.0));
    }
    return static_cast<T>(std::is_integral_v<T> ? std::floor(v) : v);
}

// An anonymous mapping read as zeros until written; unmapped on destruction.
class ZeroMapping {
public:
    explicit ZeroMapping(std::size_t bytes) : bytes_(bytes) {
        void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
        if (p == MAP_FAILED) return;
        data_ = p;
        // Huge zero pages where the kernel has them: reading the volume then faults in a few
        // thousand pages instead of a million.
        madvise(p, bytes, MADV_HUGEPAGE);
    }
    ~ZeroMapping() {
        if (data_) munmap(data_, bytes_);
    }
    ZeroMapping(const ZeroMapping&) = delete;
    ZeroMapping& operator=(const ZeroMapping&) = delete;
    void* data() const { return data_; }

private:
    void* data_ = nullptr;
    std::size_t bytes_;
};

std::size_t linear(std::size_t x, std::size_t y, std::size_t z) { return x + kDims[0] * (y + kDims[1] * z); }

template <typename T>
void check_large_volume(voxmesh::ScalarType type) {
    const std::size_t count = kDims[0] * kDims[1] * kDims[2];
    REQUIRE(count > (std::size_t{1} << 32));
    REQUIRE(linear(kSample2to32[0], kSample2to32[1], kSample2to32[2]) == (std::size_t{1} << 32));

    if (vmtest::kThreadSanitizer) {
        // ThreadSanitizer shadows every byte read: tens of GB of shadow for these volumes.
        WARN("skipped under ThreadSanitizer");
        return;
    }
    ZeroMapping mapping(count * sizeof(T));
    if (!mapping.data()) {
        WARN("skipped: no address space for a " << count * sizeof(T) << "-byte mapping");
        return;
    }
    T* samples = static_cast<T*>(mapping.data());

    // The same samples, written into the big volume and into a small box of their own.
    const Dims box{kBoxMax[0] - kBoxMin[0], kBoxMax[1] - kBoxMin[1], kBoxMax[2] - kBoxMin[2]};
    std::vector<T> boxed(box[0] * box[1] * box[2]);
    for (std::size_t z = 0; z < box[2]; ++z)
        for (std::size_t y = 0; y < box[1]; ++y)
            for (std::size_t x = 0; x < box[0]; ++x) {
                const std::size_t gx = kBoxMin[0] + x, gy = kBoxMin[1] + y, gz = kBoxMin[2] + z;
                const T v = ball_sample<T>(double(gx), double(gy), double(gz));
                boxed[x + box[0] * (y + box[1] * z)] = v;
                samples[linear(gx, gy, gz)] = v;
            }

    // Vertex order (owning sample, then axis) and triangle order (cell) keep their relative
    // order in a sub-box, so the big volume's mesh is the box's, moved by the box's corner.
    const double iso = 127.5;
    vmtest::RefOptions ro;
    ro.iso = iso;
    ro.origin = {double(kBoxMin[0]), double(kBoxMin[1]), double(kBoxMin[2])};
    const vmtest::RefMesh ref = vmtest::reference_mc(vmtest::to_doubles(boxed), box, ro);
    REQUIRE(ref.triangle_count() > 0);

    const voxmesh::VolumeView view{samples, type, kDims};
    struct Run {
        voxmesh::Backend backend;
        unsigned threads;
    };
    std::vector<Run> runs{{voxmesh::Backend::Cpu, 1}, {voxmesh::Backend::Cpu, 2}, {voxmesh::Backend::Cpu, 7}};
    if (voxmesh::opencl_available()) {
        runs.push_back({voxmesh::Backend::OpenCL, 2});
        runs.push_back({voxmesh::Backend::Hybrid, 2});
    }
    for (const Run& run : runs) {
        voxmesh::Options options;
        options.iso = iso;
        options.backend = run.backend;
        options.threads = run.threads;
        INFO(voxmesh::scalar_name(type) << ", " << voxmesh::backend_name(run.backend) << ", " << run.threads << " threads");
        const voxmesh::Mesh mesh = voxmesh::extract(view, options);
        const vmtest::Comparison cmp = vmtest::compare_with_reference(mesh, ref);
        INFO(cmp.first_problem);
        CHECK(cmp.same_indices);
        CHECK(cmp.max_position_error <= 1e-6);
        CHECK(cmp.max_normal_error <= 1e-5);
        const voxmesh::MeshTopology topology = voxmesh::analyze_topology(mesh);
        CHECK(topology.closed());
        CHECK(topology.euler == 4);
    }
}

}  // namespace

TEST_CASE("a volume past 2^32 samples meshes like the box around its surfaces", "[core][large]") {
    SECTION("u8") { check_large_volume<std::uint8_t>(voxmesh::ScalarType::U8); }
    SECTION("f32") { check_large_volume<float>(voxmesh::ScalarType::F32); }
}
