// The row packers against a one-sample-at-a-time definition of the inside bits, for every
// sample type, row lengths around the 64-sample word, thresholds at the type's ends, and
// NaN/infinity detection. The AVX2 packer is checked where the processor has it.
#include "core/row_packer.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

using voxmesh::detail::Word;

namespace {

template <class T>
std::vector<Word> expected_bits(const std::vector<T>& row, T threshold) {
    std::vector<Word> bits((row.size() + 63) / 64, 0);
    for (std::size_t i = 0; i < row.size(); ++i)
        if (row[i] >= threshold) bits[i / 64] |= Word{1} << (i % 64);
    return bits;
}

template <class T>
T random_sample(std::mt19937& rng, T threshold) {
    if constexpr (std::is_floating_point_v<T>) {
        // Mostly near the threshold, sometimes exactly on it or at the type's extremes.
        switch (rng() % 8) {
            case 0: return threshold;
            case 1: return std::numeric_limits<T>::max();
            case 2: return std::numeric_limits<T>::lowest();
            case 3: return -T(0);
            default: return threshold + static_cast<T>(std::uniform_real_distribution<double>(-2, 2)(rng));
        }
    } else {
        std::uniform_int_distribution<long long> any(std::numeric_limits<T>::lowest(), std::numeric_limits<T>::max());
        if (rng() % 4 == 0) return threshold;
        // One step either side of the threshold, wrapping at the type's ends (in long long:
        // no overflow in the arithmetic itself).
        if (rng() % 4 == 0) return static_cast<T>(static_cast<long long>(threshold) + (rng() % 2 ? 1 : -1));
        return static_cast<T>(any(rng));
    }
}

template <class T>
void check_packers(std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<voxmesh::detail::RowPacker<T>> packers{&voxmesh::detail::pack_row_portable<T>};
    if (auto avx2 = voxmesh::detail::avx2_row_packer<T>()) packers.push_back(avx2);
    std::vector<T> thresholds{std::numeric_limits<T>::lowest(), std::numeric_limits<T>::max(), T(0), T(1)};
    if constexpr (std::is_floating_point_v<T>) thresholds.push_back(static_cast<T>(0.37));
    for (std::size_t nx : {1, 2, 63, 64, 65, 127, 128, 200, 257}) {
        for (T threshold : thresholds) {
            std::vector<T> row(nx);
            for (T& v : row) v = random_sample(rng, threshold);
            const auto want = expected_bits(row, threshold);
            for (auto pack : packers) {
                std::vector<Word> got(want.size(), ~Word{0});
                CAPTURE(nx, double(threshold));
                CHECK_FALSE(pack(row.data(), nx, threshold, got.data()));
                CHECK(got == want);
            }
            if constexpr (std::is_floating_point_v<T>) {
                // One non-finite sample anywhere in the row is reported, by every packer.
                for (T bad : {std::numeric_limits<T>::quiet_NaN(), std::numeric_limits<T>::infinity(),
                              -std::numeric_limits<T>::infinity()}) {
                    std::vector<T> broken = row;
                    broken[rng() % nx] = bad;
                    for (auto pack : packers) {
                        std::vector<Word> got(want.size());
                        CHECK(pack(broken.data(), nx, threshold, got.data()));
                    }
                }
            }
        }
    }
}

}  // namespace

TEST_CASE("row packers give the one-at-a-time inside bits for every type", "[core][packer]") {
    INFO("AVX2 packer present: " << (voxmesh::detail::avx2_row_packer<float>() != nullptr));
    check_packers<std::uint8_t>(1);
    check_packers<std::int8_t>(2);
    check_packers<std::uint16_t>(3);
    check_packers<std::int16_t>(4);
    check_packers<std::uint32_t>(5);
    check_packers<std::int32_t>(6);
    check_packers<float>(7);
    check_packers<double>(8);
}
