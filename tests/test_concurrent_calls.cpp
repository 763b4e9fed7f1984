// extract() called from several user threads at once, every backend mixed: the engines share
// the process-wide thread pool and OpenCL devices, and each call must still give the
// canonical mesh (the 1-thread CPU engine's, bit for bit).
#include <catch2/catch.hpp>
#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
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
    std::array<std::size_t, 3> dims;
    double iso = 0;
    VolumeView view() const {
        VolumeView v;
        v.dims = dims;
        v.type = f32.empty() ? ScalarType::U8 : ScalarType::F32;
        v.data = f32.empty() ? static_cast<const void*>(u8.data()) : static_cast<const void*>(f32.data());
        v.spacing = {0.5, 1, 1.5};
        v.origin = {-3, 2, 7};
        return v;
    }
};

// Fields of [0,1]^3 coordinates, sampled on n0 x n1 x n2.
template <class F>
std::vector<float> field(std::array<std::size_t, 3> n, F f) {
    std::vector<float> v;
    for (std::size_t z = 0; z < n[2]; ++z)
        for (std::size_t y = 0; y < n[1]; ++y)
            for (std::size_t x = 0; x < n[0]; ++x)
                v.push_back(static_cast<float>(
                    f(double(x) / double(n[0] - 1), double(y) / double(n[1] - 1), double(z) / double(n[2] - 1))));
    return v;
}

std::vector<Case> cases() {
    std::vector<Case> out;
    const std::array<std::size_t, 3> a{41, 37, 45}, b{64, 24, 33};
    out.push_back({"sphere f32", field(a, [](double x, double y, double z) {
                       return 0.4 - std::sqrt((x - .5) * (x - .5) + (y - .45) * (y - .45) + (z - .55) * (z - .55));
                   }), {}, a, 0});
    out.push_back({"gyroid f32", field(b, [](double x, double y, double z) {
                       const double s = 12;
                       return std::sin(s * x) * std::cos(s * y) + std::sin(s * y) * std::cos(s * z) +
                              std::sin(s * z) * std::cos(s * x);
                   }), {}, b, 0.1});
    Case torus{"torus u8", {}, {}, a, 127.5};
    for (const float v : field(a, [](double x, double y, double z) {
             const double q = std::sqrt((x - .5) * (x - .5) + (y - .5) * (y - .5)) - 0.3;
             return 0.12 - std::sqrt(q * q + (z - .5) * (z - .5));
         }))
        torus.u8.push_back(static_cast<std::uint8_t>(std::lround(std::clamp(127.5 + 600 * v, 0.0, 255.0))));
    out.push_back(std::move(torus));
    return out;
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
    for (std::thread& c : callers) c.join();
    std::string report;
    for (unsigned t = 0; t < kCallers; ++t) report += "caller " + std::to_string(t) + ": " + reports[t] + "\n";
    INFO(report);
    CHECK(errors == 0);
    CHECK(mismatches == 0);
}
