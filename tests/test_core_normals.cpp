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
