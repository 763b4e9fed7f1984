#include "row_packer.hpp"

#include "env_word.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>

#ifdef VOXMESH_X86_DISPATCH
#include <immintrin.h>
#endif

namespace voxmesh::detail {

namespace {

// |v| <= max is false exactly for NaN and infinities.
template <class T>
bool is_finite_sample(T v) {
    if constexpr (std::is_floating_point_v<T>)
        return std::fabs(v) <= std::numeric_limits<T>::max();
    else
        return true;
}

// Bits of the last, partial word (n < 64 samples), one sample at a time.
template <class T>
Word pack_tail(const T* values, std::size_t n, T threshold, bool& bad) {
    Word w = 0;
    for (std::size_t i = 0; i < n; ++i) {
        w |= Word{values[i] >= threshold} << i;
        bad |= !is_finite_sample(values[i]);
    }
    return w;
}

// VOXMESH_ISA (any case): "portable" forces the portable code; "popcnt" allows POPCNT but no
// AVX2, as an older x86-64 processor runs (classify's POPCNT copy beside the portable packers
// and generator, a mix no AVX2 machine runs otherwise); unset, empty or "native" leaves the
// choice to the processor. Another value (a typo) is named once on stderr rather than silently
// timing the AVX2 code as if it were the portable one.
enum class IsaLimit { None, Popcnt, Portable };

IsaLimit isa_limit() {
    static const IsaLimit limit = [] {
        const std::optional<std::string> value = env_word("VOXMESH_ISA");
        if (!value) return IsaLimit::None;
        if (*value == "portable") return IsaLimit::Portable;
        if (*value == "popcnt") return IsaLimit::Popcnt;
        if (*value != "native")
            std::fprintf(stderr, "voxmesh: warning: VOXMESH_ISA='%s' is not 'portable', 'popcnt' or 'native'; ignored\n",
                         std::getenv("VOXMESH_ISA"));
        return IsaLimit::None;
    }();
    return limit;
}

}  // namespace

template <class T>
bool pack_row_portable(const T* values, std::size_t nx, T threshold, Word* out) {
    const std::size_t full = nx / 64;
    unsigned bad = 0;
    for (std::size_t q = 0; q < full; ++q) {
        // Compare into bytes (vectorises for every type), then gather each 8 bytes into 8
        // bits with one multiply: bytes of 0/1 at bit 8k land at bit 56+k of the product.
        std::uint8_t bytes[64];
        const T* v = values + 64 * q;
        for (unsigned i = 0; i < 64; ++i) {
            bytes[i] = v[i] >= threshold;
            bad |= !is_finite_sample(v[i]);
        }
        Word w = 0;
        for (unsigned g = 0; g < 8; ++g) {
            std::uint64_t eight;
            std::memcpy(&eight, bytes + 8 * g, 8);
            w |= ((eight * 0x0102040810204080ull) >> 56) << (8 * g);
        }
        out[q] = w;
    }
    bool tail_bad = false;
    if (nx % 64) out[full] = pack_tail(values + 64 * full, nx % 64, threshold, tail_bad);
    return bad != 0 || tail_bad;
}

#ifdef VOXMESH_X86_DISPATCH
namespace {

#define VOXMESH_AVX2 __attribute__((target("avx2")))

// 64 samples -> 64 inside bits. Integers: inside = !(threshold > v), unsigned types compared
// as signed after flipping the sign bit. Floats: ordered >=, so NaN is outside; `bad` gathers
// the lanes that are not finite.
template <class T>
VOXMESH_AVX2 inline Word pack64_avx2(const T* p, T threshold, unsigned& bad) {
    Word w = 0;
    if constexpr (std::is_same_v<T, float>) {
        // Four compares (32 lanes of 0 / -1) narrow to 32 bytes with two packs; the packs work
        // within 128-bit halves, so a permute restores sample order before one movemask.
        const __m256 t = _mm256_set1_ps(threshold);
        const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
        __m256 nonfinite = _mm256_setzero_ps();  // v - v: +0 when finite, NaN otherwise; or-ed
        for (unsigned h = 0; h < 2; ++h) {
            __m256i inside[4];
            for (unsigned g = 0; g < 4; ++g) {
                const __m256 v = _mm256_loadu_ps(p + 32 * h + 8 * g);
                inside[g] = _mm256_castps_si256(_mm256_cmp_ps(v, t, _CMP_GE_OQ));
                nonfinite = _mm256_or_ps(nonfinite, _mm256_sub_ps(v, v));
            }
            const __m256i bytes = _mm256_packs_epi16(_mm256_packs_epi32(inside[0], inside[1]),
                                                     _mm256_packs_epi32(inside[2], inside[3]));
            w |= Word(std::uint32_t(_mm256_movemask_epi8(_mm256_permutevar8x32_epi32(bytes, order)))) << (32 * h);
        }
        bad |= unsigned(!_mm256_testz_si256(_mm256_castps_si256(nonfinite), _mm256_castps_si256(nonfinite)));
    } else if constexpr (std::is_same_v<T, double>) {
        const __m256d t = _mm256_set1_pd(threshold), max = _mm256_set1_pd(std::numeric_limits<double>::max());
        const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffll));
        __m256d nonfinite = _mm256_setzero_pd();
        for (unsigned g = 0; g < 16; ++g) {
            const __m256d v = _mm256_loadu_pd(p + 4 * g);
            w |= Word(unsigned(_mm256_movemask_pd(_mm256_cmp_pd(v, t, _CMP_GE_OQ)))) << (4 * g);
            nonfinite = _mm256_or_pd(nonfinite, _mm256_cmp_pd(_mm256_and_pd(v, abs_mask), max, _CMP_NLE_UQ));
        }
        bad |= unsigned(_mm256_movemask_pd(nonfinite));
    } else if constexpr (sizeof(T) == 1) {
        const char flip = std::is_signed_v<T> ? 0 : static_cast<char>(0x80);
        const __m256i bias = _mm256_set1_epi8(flip);
        const __m256i t = _mm256_set1_epi8(static_cast<char>(static_cast<char>(threshold) ^ flip));
        Word below = 0;
        for (unsigned g = 0; g < 2; ++g) {
            const __m256i v = _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 32 * g)), bias);
            below |= Word(std::uint32_t(_mm256_movemask_epi8(_mm256_cmpgt_epi8(t, v)))) << (32 * g);
        }
        w = ~below;
    } else if constexpr (sizeof(T) == 2) {
        const short flip = std::is_signed_v<T> ? 0 : static_cast<short>(0x8000);
        const __m256i bias = _mm256_set1_epi16(flip);
        const __m256i t = _mm256_set1_epi16(static_cast<short>(static_cast<short>(threshold) ^ flip));
        Word below = 0;
        for (unsigned g = 0; g < 2; ++g) {
            const auto* at = reinterpret_cast<const __m256i*>(p + 32 * g);
            const __m256i a = _mm256_cmpgt_epi16(t, _mm256_xor_si256(_mm256_loadu_si256(at), bias));
            const __m256i b = _mm256_cmpgt_epi16(t, _mm256_xor_si256(_mm256_loadu_si256(at + 1), bias));
            // packs interleaves 128-bit lanes (a.lo b.lo a.hi b.hi); the permute restores order.
            const __m256i ab = _mm256_permute4x64_epi64(_mm256_packs_epi16(a, b), 0xD8);
            below |= Word(std::uint32_t(_mm256_movemask_epi8(ab))) << (32 * g);
        }
        w = ~below;
    } else {
        static_assert(sizeof(T) == 4 && std::is_integral_v<T>);
        const int flip = std::is_signed_v<T> ? 0 : static_cast<int>(0x80000000u);
        const __m256i bias = _mm256_set1_epi32(flip);
        const __m256i t = _mm256_set1_epi32(static_cast<int>(static_cast<int>(threshold) ^ flip));
        Word below = 0;
        for (unsigned g = 0; g < 8; ++g) {
            const __m256i v = _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 8 * g)), bias);
            below |= Word(unsigned(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(t, v))))) << (8 * g);
        }
        w = ~below;
    }
    return w;
}

template <class T>
VOXMESH_AVX2 bool pack_row_avx2(const T* values, std::size_t nx, T threshold, Word* out) {
    const std::size_t full = nx / 64;
    unsigned bad = 0;
    for (std::size_t q = 0; q < full; ++q) out[q] = pack64_avx2(values + 64 * q, threshold, bad);
    bool tail_bad = false;
    if (nx % 64) out[full] = pack_tail(values + 64 * full, nx % 64, threshold, tail_bad);
    return bad != 0 || tail_bad;
}

}  // namespace
#endif

template <class T>
RowPacker<T> avx2_row_packer() {
#ifdef VOXMESH_X86_DISPATCH
    if (__builtin_cpu_supports("avx2")) return &pack_row_avx2<T>;
#endif
    return nullptr;
}

template <class T>
RowPacker<T> row_packer() {
    const RowPacker<T> fast = use_avx2() ? avx2_row_packer<T>() : nullptr;
    return fast ? fast : &pack_row_portable<T>;
}

bool use_avx2() {
#ifdef VOXMESH_X86_DISPATCH
    static const bool use = isa_limit() == IsaLimit::None && __builtin_cpu_supports("avx2");
    return use;
#else
    return false;
#endif
}

bool cpu_has_popcnt() {
#ifdef VOXMESH_X86_DISPATCH
    static const bool has = isa_limit() != IsaLimit::Portable && __builtin_cpu_supports("popcnt");
    return has;
#else
    return false;
#endif
}

bool cpu_has_avx2_bmi2() {
#ifdef VOXMESH_X86_DISPATCH
    static const bool has = cpu_has_popcnt() && use_avx2() && __builtin_cpu_supports("bmi") &&
                            __builtin_cpu_supports("bmi2");
    return has;
#else
    return false;
#endif
}

#define VOXMESH_INSTANTIATE(T)                                                       \
    template bool pack_row_portable<T>(const T*, std::size_t, T, Word*);            \
    template RowPacker<T> avx2_row_packer<T>();                                      \
    template RowPacker<T> row_packer<T>();
VOXMESH_INSTANTIATE(std::uint8_t)
VOXMESH_INSTANTIATE(std::int8_t)
VOXMESH_INSTANTIATE(std::uint16_t)
VOXMESH_INSTANTIATE(std::int16_t)
VOXMESH_INSTANTIATE(std::uint32_t)
VOXMESH_INSTANTIATE(std::int32_t)
VOXMESH_INSTANTIATE(float)
VOXMESH_INSTANTIATE(double)
#undef VOXMESH_INSTANTIATE

}  // namespace voxmesh::detail
