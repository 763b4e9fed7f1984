// extract() called from several user threads at once, every backend mixed: the engines share
// the process-wide thread pool and OpenCL devices, and each call must still give the
// canonical mesh (the 1-thread CPU engine's, bit for bit).
#include <catch2/catch.hpp>
#include <voxmesh/voxmesh.hpp>

#include "support/mesh_checks.hpp"

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

using namespace voxmesh;

namespace {

struct Case {
    std::string name;
    std::vector<float> f32;
    std::vector<std::uint8_t> u8;
    vmtest::Dims dims;
    double iso = 0;
    VolumeView view() const {
        const std::array<double, 3> spacing{0.5, 1, 1.5}, origin{-3, 2, 7};
        return f32.empty() ? vmtest::view_of(u8, dims, spacing, origin) : vmtest::view_of(f32, dims, spacing, origin);
    }
};

std::vector<Case> cases() {
    const vmtest::Dims a{41, 37, 45}, b{64, 24, 33};
    const vmtest::FieldFn torus = vmtest::torus({20, 18, 22}, 12, 5);
    return {
        {"sphere f32", vmtest::sample_field<float>(a, vmtest::sphere({20, 16.5, 24}, 16)), {}, a, 0},
        {"wavy f32", vmtest::sample_field<float>(b, vmtest::wavy(0.5)), {}, b, 0.1},
        {"torus u8", {},
         vmtest::sample_field<std::uint8_t>(a, [&](double x, double y, double z) { return 127.5 + 20 * torus(x, y, z); }),
         a, 127.5},
    };
}

bool same(const Mesh& a, const Mesh& b) {
    return a.indices == b.indices && a.positions == b.positions && a.normals == b.normals;
}

}  // namespace

TEST_CASE("extract from several threads at once, every backend, gives the canonical mesh", "[concurrency]") {
    const std::vector<Case> volumes = cases();
    std::vector<Mesh> canonical;
    for (const Case& c : volumes) {
        Options o;
        o.iso = c.iso;
        o.backend = Backend::Cpu;
        o.threads = 1;
        canonical.push_back(extract(c.view(), o));
        REQUIRE(canonical.back().triangle_count() > 0);
    }
    const bool opencl = !list_devices().empty();
    if (!opencl) WARN("no OpenCL device found: only the CPU engine runs concurrently here");

    // Each caller walks the (volume, backend, threads) combinations from its own starting point,
    // so that different engines overlap; extract_into reuses the caller's mesh.
    const std::vector<Backend> backends =
        opencl ? std::vector<Backend>{Backend::Cpu, Backend::OpenCL, Backend::Hybrid, Backend::Auto}
               : std::vector<Backend>{Backend::Cpu, Backend::Auto};
    constexpr unsigned kCallers = 4, kCallsEach = 24;
    std::atomic<unsigned> mismatches{0}, errors{0};
    std::vector<std::string> reports(kCallers);
    std::vector<std::thread> callers;
    for (unsigned t = 0; t < kCallers; ++t)
        callers.emplace_back([&, t] {
            Mesh reused;
            for (unsigned i = 0; i < kCallsEach; ++i) {
                const unsigned step = t * 5 + i;
                const std::size_t v = step % volumes.size();
                Options o;
                o.iso = volumes[v].iso;
                o.backend = backends[step % backends.size()];
                o.threads = 1 + step % 3;
                o.normals = true;
                try {
                    Stats stats;
                    Mesh got;
                    if (i % 2) {
                        extract_into(volumes[v].view(), o, reused, stats);
                        got = reused;
                    } else {
                        got = extract(volumes[v].view(), o, stats);
                    }
                    if (!same(got, canonical[v])) {
                        ++mismatches;
                        reports[t] += volumes[v].name + " backend " + backend_name(o.backend) + " threads " +
                                      std::to_string(o.threads) + "; ";
                    }
                } catch (const std::exception& e) {
                    ++errors;
                    reports[t] += std::string("error: ") + e.what() + "; ";
                }
            }
        });
    // Meanwhile another thread keeps freeing what the engines keep between calls: a device or
    // scratch block in use stays with its call, and the next call makes what it needs again.
    std::atomic<bool> done{false};
    unsigned releases = 0;
    std::thread releaser([&] {
        while (!done) {
            release_scratch_memory();
            ++releases;
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
    });
    for (std::thread& c : callers) c.join();
    done = true;
    releaser.join();
    CHECK(releases > 0);
    std::string report;
    for (unsigned t = 0; t < kCallers; ++t) report += "caller " + std::to_string(t) + ": " + reports[t] + "\n";
    INFO(report);
    CHECK(errors == 0);
    CHECK(mismatches == 0);
}
