// Batched normal normalisation (four lanes at a time where the processor has AVX2) against
// the one-at-a-time definition, bit for bit: ordinary vectors, lengths whose square
// overflows or underflows, zero, NaN and infinite components (the flat-gradient fallback),
// and batch lengths around the batch size and the lane count.
#include "core/edge_vertex.hpp"
#include "core/normal_batch.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <utility>
#include <vector>

using voxmesh::detail::NormalBatch;
using voxmesh::detail::normalise_normal;

namespace {

double random_component(std::mt19937_64& rng) {
    std::uniform_int_distribution<int> kind(0, 19);
    std::uniform_real_distribution<double> unit(-1, 1);
    std::uniform_int_distribution<int> exponent(-200, 200);
    switch (kind(rng)) {
        case 0: return 0.0;
        case 1: return -0.0;
        case 2: return std::numeric_limits<double>::quiet_NaN();
        case 3: return std::numeric_limits<double>::infinity();
        case 4: return std::ldexp(unit(rng), exponent(rng) * 5);  // squares that overflow or underflow
        default: return unit(rng) * 100;
    }
}

}  // namespace

TEST_CASE("batched normals are normalised exactly as one at a time", "[core]") {
    std::mt19937_64 rng(7);
    std::uniform_int_distribution<unsigned> axis(0, 2), positive(0, 1);
    for (std::size_t count : {0u, 1u, 3u, 4u, 5u, 127u, 128u, 129u, 300u}) {
        INFO("count " << count);
        std::vector<double> n(3 * count);
        std::vector<unsigned> flat(count);
        for (double& c : n) c = random_component(rng);
        for (unsigned& f : flat) f = axis(rng) | (positive(rng) ? voxmesh::detail::kFlatPositive : 0u);
        std::vector<float> want(3 * count + 3, 42.f), got(3 * count + 3, 42.f);  // one guard vertex
        for (std::size_t v = 0; v < count; ++v) normalise_normal(&n[3 * v], flat[v], &want[3 * v]);
        NormalBatch batch;
        batch.start(got.data());
        for (std::size_t v = 0; v < count; ++v) batch.push(&n[3 * v], flat[v]);
        batch.flush();
        REQUIRE(std::memcmp(got.data(), want.data(), got.size() * sizeof(float)) == 0);
        for (std::size_t v = 0; v < count; ++v) {
            const double len = std::hypot(got[3 * v], got[3 * v + 1], got[3 * v + 2]);
            CHECK(std::fabs(len - 1) < 1e-6);
        }
    }
}

// Samples written to between classify and generate (a data race, for which the API promises a
// mix of old and new samples) can hand generate an edge that no longer crosses iso: both ends
// on iso (t = 0 / 0), equal off iso (t = +-inf), or crossing the other way (t outside [0, 1]).
// Its vertex stays finite and on its edge.
TEST_CASE("a vertex on an edge whose samples changed since classify stays finite and on its edge", "[core]") {
    const std::uint16_t iso = 1000;
    for (const auto& [a, b] : std::vector<std::pair<std::uint16_t, std::uint16_t>>{
             {1000, 1000}, {999, 999}, {1001, 1001}, {990, 980}, {990, 995}, {1010, 1020}, {0, 65535}}) {
        INFO(a << " -> " << b);
        // Sample (1, 1, 1) holds a, its +x, +y and +z neighbours b, the rest a.
        const std::size_t n = 4;
        std::vector<std::uint16_t> samples(n * n * n, a);
        samples[2 + n * 1 + n * n * 1] = b;
        samples[1 + n * 2 + n * n * 1] = b;
        samples[1 + n * 1 + n * n * 2] = b;
        voxmesh::VolumeView v;
        v.data = samples.data();
        v.type = voxmesh::ScalarType::U16;
        v.dims = {n, n, n};
        v.spacing = {0.5, 2, 3};
        v.origin = {-1, 10, 100};
        const voxmesh::detail::EdgeVertex<std::uint16_t> vertex(v, iso, false);
        float position[9], normal[9];
        vertex.sample(1, 1, 1, 7u, position, normal);
        for (unsigned axis = 0; axis < 3; ++axis) {
            INFO("axis " << axis);
            for (unsigned d = 0; d < 3; ++d) {
                const float c = position[3 * axis + d];
                REQUIRE(std::isfinite(c));
                REQUIRE(std::isfinite(normal[3 * axis + d]));
                const double first = v.origin[d] + 1 * v.spacing[d], last = v.origin[d] + (d == axis ? 2 : 1) * v.spacing[d];
                CHECK(c >= first);
                CHECK(c <= last);
            }
        }
    }
}
