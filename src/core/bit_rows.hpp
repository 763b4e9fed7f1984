// Rows of inside bits packed 64 samples to a word, and the word-parallel masks the CPU
// engine derives from them: which owned edges cross, which cells are not uniform. Bit r
// of word q stands for sample x = 64q + r; bits past the row's end are always 0.
#pragma once

#include <bit>
#include <cmath>
#include <limits>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace voxmesh::detail {

using Word = std::uint64_t;
constexpr Word kNoBits = 0, kAllBits = ~Word{0};

inline std::size_t words_per_row(std::size_t nx) { return (nx + 63) / 64; }

// Mask of the bits of word q that stand for x < limit.
inline Word bits_below(std::size_t q, std::size_t limit) {
    const std::size_t begin = 64 * q;
    if (limit >= begin + 64) return kAllBits;
    if (limit <= begin) return kNoBits;
    return (Word{1} << (limit - begin)) - 1;
}

// Bit r of the result is bit r+1 of the row: the row's neighbour in +x.
inline Word next_x(const Word* row, std::size_t q, std::size_t words) {
    return row[q] >> 1 | (q + 1 < words ? row[q + 1] << 63 : 0);
}

// Inside bits of one row: compare into bytes (vectorises for every type), then gather each
// 8 bytes into 8 bits with one multiply. `bytes` is scratch of 64 * words. Returns true
// when the row holds a NaN or an infinity.
template <class T>
bool pack_row_bits(const T* values, std::size_t nx, T threshold, std::uint8_t* bytes, Word* out) {
    const std::size_t words = words_per_row(nx);
    bool nan = false;
    if constexpr (std::is_floating_point_v<T>) {
        // |v| <= max is false exactly for NaN and infinities, and vectorises.
        constexpr T kMax = std::numeric_limits<T>::max();
        unsigned bad = 0;
        for (std::size_t i = 0; i < nx; ++i) {
            bytes[i] = values[i] >= threshold;
            bad |= !(std::fabs(values[i]) <= kMax);
        }
        nan = bad != 0;
    } else {
        for (std::size_t i = 0; i < nx; ++i) bytes[i] = values[i] >= threshold;
    }
    std::memset(bytes + nx, 0, 64 * words - nx);
    for (std::size_t q = 0; q < words; ++q) {
        Word w = 0;
        for (unsigned g = 0; g < 8; ++g) {
            std::uint64_t eight;
            std::memcpy(&eight, bytes + 64 * q + 8 * g, 8);
            // Bytes of 0/1 at bit 8k land, without carries, at bit 56+k of the product.
            w |= ((eight * 0x0102040810204080ull) >> 56) << (8 * g);
        }
        out[q] = w;
    }
    return nan;
}

// Crossed owned edges of a row (sample x owns x->x+1, y->y+1, z->z+1) as three masks.
// next_y / next_z are the neighbouring rows, or null at the volume's border.
struct EdgeMasks {
    Word x, y, z;
    Word any() const { return x | y | z; }
};

inline EdgeMasks edge_masks(const Word* row, const Word* next_y, const Word* next_z, std::size_t q,
                            std::size_t words, std::size_t nx) {
    return {(row[q] ^ next_x(row, q, words)) & bits_below(q, nx - 1), next_y ? row[q] ^ next_y[q] : 0,
            next_z ? row[q] ^ next_z[q] : 0};
}

inline unsigned popcount(Word w) { return static_cast<unsigned>(std::popcount(w)); }

// Cells x of the cell row spanned by rows a=(y,z), b=(y+1,z), c=(y,z+1), d=(y+1,z+1):
// bit set where the cell's 8 corners are not all equal.
inline Word nonuniform_cells(const Word* a, const Word* b, const Word* c, const Word* d, std::size_t q,
                             std::size_t words, std::size_t nx) {
    const Word a0 = a[q];
    const Word diff = (a0 ^ next_x(a, q, words)) | (a0 ^ b[q]) | (a0 ^ next_x(b, q, words)) | (a0 ^ c[q]) |
                      (a0 ^ next_x(c, q, words)) | (a0 ^ d[q]) | (a0 ^ next_x(d, q, words));
    return diff & bits_below(q, nx - 1);
}

// Case index of cell 64q + r (bit k set where corner k is inside).
inline unsigned cell_case(const Word* a, const Word* b, const Word* c, const Word* d, std::size_t q, unsigned r,
                          std::size_t words) {
    auto bit = [&](const Word* row, bool plus_x) {
        return static_cast<unsigned>((plus_x ? next_x(row, q, words) : row[q]) >> r & 1);
    };
    return bit(a, false) | bit(a, true) << 1 | bit(b, true) << 2 | bit(b, false) << 3 | bit(c, false) << 4 |
           bit(c, true) << 5 | bit(d, true) << 6 | bit(d, false) << 7;
}

}  // namespace voxmesh::detail
