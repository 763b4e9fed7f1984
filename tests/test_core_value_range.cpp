// value_range against a deliberately simple oracle: one loop over every sample in double.
#include <catch2/catch.hpp>

#include "support/mesh_checks.hpp"

#include <voxmesh/voxmesh.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <vector>

using vmtest::Dims;

namespace {

// Whether a sample of type T can hold `value` exactly (range checked before converting).
template <class T>
bool holds(double value) {
    if (!(value >= static_cast<double>(std::numeric_limits<T>::lowest()) &&
          value <= static_cast<double>(std::numeric_limits<T>::max())))
        return false;
    return static_cast<double>(static_cast<T>(value)) == value;
}

template <class T>
voxmesh::ValueRange oracle_range(const std::vector<T>& data, const Dims& n, std::optional<double> equal_to) {
    voxmesh::ValueRange r;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i = 0; i < data.size(); ++i) {
        const double v = static_cast<double>(data[i]);
        if (!std::isfinite(v)) {
            if (r.nonfinite++ == 0) r.first_nonfinite = {i % n[0], i / n[0] % n[1], i / (n[0] * n[1])};
            continue;
        }
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        // Equal in the sample's own type: a value no sample can hold matches none.
        if (equal_to && holds<T>(*equal_to) && v == *equal_to) ++r.equal;
    }
    if (lo <= hi) {
        r.min = lo;
        r.max = hi;
    }
    return r;
}

void require_same(const voxmesh::ValueRange& got, const voxmesh::ValueRange& want) {
    CHECK(got.min == want.min);
    CHECK(got.max == want.max);
    CHECK(got.nonfinite == want.nonfinite);
    if (want.nonfinite) CHECK(got.first_nonfinite == want.first_nonfinite);
    CHECK(got.equal == want.equal);
}

template <class T>
void check_random_volumes(double lowest, double highest) {
    std::mt19937 random(11);
    std::uniform_real_distribution<double> value(lowest, highest);
    for (const Dims n : {Dims{7, 5, 9}, Dims{67, 3, 5}, Dims{1, 1, 1}, Dims{130, 2, 3}}) {
        std::vector<T> data(n[0] * n[1] * n[2]);
        for (auto& v : data) v = static_cast<T>(std::is_integral_v<T> ? std::round(value(random)) : value(random));
        data[data.size() / 2] = static_cast<T>(3);  // a value to count, at least once
        const auto view = vmtest::view_of(data, n);
        for (const std::optional<double> equal_to : {std::optional<double>{}, std::optional<double>{3.0},
                                                     std::optional<double>{3.25}, std::optional<double>{1e300}})
            for (const unsigned threads : {1u, 2u, 3u, 8u}) {
                INFO("dims " << n[0] << "x" << n[1] << "x" << n[2] << ", threads " << threads);
                require_same(voxmesh::value_range(view, equal_to, threads), oracle_range(data, n, equal_to));
            }
    }
}

}  // namespace

TEST_CASE("value_range gives the oracle's min, max and equal count for every type and thread count", "[value_range][core]") {
    check_random_volumes<std::uint8_t>(0, 9);
    check_random_volumes<std::int8_t>(-128, 127);
    check_random_volumes<std::uint16_t>(0, 65535);
    check_random_volumes<std::int16_t>(-5, 5);
    check_random_volumes<std::uint32_t>(0, 4e9);
    check_random_volumes<std::int32_t>(-2e9, 2e9);
    check_random_volumes<float>(-1e3, 1e3);
    check_random_volumes<double>(-1e-3, 1e-3);
}

TEST_CASE("value_range orders negative floats and zeros as floats do", "[value_range][core]") {
    // The integer keys of negative floats run backwards from their bits: -2 < -1 < -0.0 == 0 < 1.
    const Dims n{5, 1, 1};
    const std::vector<float> data{-1.0f, -0.0f, -2.0f, 0.0f, 1.0f};
    const auto r = voxmesh::value_range(vmtest::view_of(data, n), 0.0, 1);
    CHECK(r.min == -2.0);
    CHECK(r.max == 1.0);
    CHECK(r.equal == 2);  // -0.0 == 0.0
    const std::vector<double> lows{-1e300, -std::numeric_limits<double>::denorm_min(), -1e-300, -7.5, -1e300};
    const auto d = voxmesh::value_range(vmtest::view_of(lows, n), -1e300, 2);
    CHECK(d.min == -1e300);
    CHECK(d.max == -std::numeric_limits<double>::denorm_min());
    CHECK(d.equal == 2);
}

TEST_CASE("value_range counts NaN and infinite samples, names the first, and leaves them out of the range",
          "[value_range][core]") {
    const Dims n{33, 4, 6};
    std::vector<float> data(n[0] * n[1] * n[2]);
    for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<float>(i % 17) - 8.0f;
    data[5 + 33 * (2 + 4 * 3)] = std::numeric_limits<float>::quiet_NaN();
    data[1 + 33 * (0 + 4 * 4)] = std::numeric_limits<float>::infinity();
    data[7 + 33 * (3 + 4 * 5)] = -std::numeric_limits<float>::infinity();
    for (const unsigned threads : {1u, 2u, 5u}) {
        const auto r = voxmesh::value_range(vmtest::view_of(data, n), -8.0, threads);
        require_same(r, oracle_range(data, n, -8.0));
        CHECK(r.nonfinite == 3);
        CHECK(r.first_nonfinite == std::array<std::size_t, 3>{5, 2, 3});
        CHECK(r.min == -8.0);
        CHECK(r.max == 8.0);
    }
    std::vector<double> all_nan(8, std::numeric_limits<double>::quiet_NaN());
    const auto r = voxmesh::value_range(vmtest::view_of(all_nan, Dims{2, 2, 2}), 0.0, 2);
    CHECK(r.nonfinite == 8);
    CHECK(r.min == 0.0);
    CHECK(r.max == 0.0);
    CHECK(r.equal == 0);
}

TEST_CASE("value_range refuses a volume without data or misaligned, and sums up an empty one as nothing",
          "[value_range][core]") {
    voxmesh::VolumeView view;
    view.dims = {2, 2, 2};
    REQUIRE_THROWS_WITH(voxmesh::value_range(view), Catch::Contains("no data"));
    std::vector<float> data(9, 1.0f);
    view.data = reinterpret_cast<const char*>(data.data()) + 2;
    REQUIRE_THROWS_WITH(voxmesh::value_range(view), Catch::Contains("not a multiple of 4"));
    view.data = data.data();
    view.dims = {0, 3, 3};
    const auto r = voxmesh::value_range(view, 1.0);
    CHECK(r.min == 0.0);
    CHECK(r.max == 0.0);
    CHECK(r.equal == 0);
}

TEST_CASE("value_range reads a zero extreme as +0.0, with or without a NaN in its plane", "[value_range][core]") {
    const Dims n{3, 1, 1};
    const std::vector<float> plain{-0.0f, -1.0f, -0.0f};
    const std::vector<float> with_nan{-0.0f, std::numeric_limits<float>::quiet_NaN(), -1.0f};
    for (const auto* data : {&plain, &with_nan}) {
        const auto r = voxmesh::value_range(vmtest::view_of(*data, n), std::nullopt, 1);
        CHECK(r.min == -1.0);
        CHECK(r.max == 0.0);
        CHECK_FALSE(std::signbit(r.max));
    }
}
