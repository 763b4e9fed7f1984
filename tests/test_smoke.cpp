#include <catch2/catch.hpp>
#include <voxmesh/voxmesh.hpp>
#include <cmath>
#include <vector>

TEST_CASE("sphere smoke", "[core]") {
    const size_t n = 32;
    std::vector<float> v(n * n * n);
    for (size_t z = 0; z < n; ++z) for (size_t y = 0; y < n; ++y) for (size_t x = 0; x < n; ++x)
        v[x + n * (y + n * z)] = 10.f - std::sqrt(float((x-15.5)*(x-15.5)+(y-15.5)*(y-15.5)+(z-15.5)*(z-15.5)));
    voxmesh::VolumeView view{v.data(), voxmesh::ScalarType::F32, {n, n, n}};
    voxmesh::Options o; o.backend = voxmesh::Backend::Cpu;
    for (unsigned t : {1u, 2u, 3u}) {
        o.threads = t;
        auto m = voxmesh::extract(view, o);
        auto topo = voxmesh::analyze_topology(m);
        CHECK(topo.closed());
        CHECK(topo.euler == 2);
        CHECK(m.triangle_count() > 100);
    }
}
