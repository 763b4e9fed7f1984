// Rows of inside bits packed 64 samples to a word, and the word-parallel masks the CPU
// engine derives from them: which owned edges cross, which cells are not uniform. Bit r
// of word q stands for sample x = 64q + r; bits past the row's end are always 0.
#pragma once

#include "case_tables.hpp"
#include "row_packer.hpp"  // Word

#include <bit>
#include <cstddef>
#include <cstdint>

// The per-word helpers below run in the engine's innermost loops; the compiler's inlining
// heuristics sometimes leave them as calls, which costs more than their bodies.
#if defined(__GNUC__) || defined(__clang__)
#define VOXMESH_HOT_INLINE [[gnu::always_inline]] inline
#else
#define VOXMESH_HOT_INLINE inline
#endif

namespace voxmesh::detail {

constexpr Word kNoBits = 0, kAllBits = ~Word{0};

inline std::size_t words_per_row(std::size_t nx) { return (nx + 63) / 64; }

// Mask of the bits of word q that stand for x < limit.
VOXMESH_HOT_INLINE Word bits_below(std::size_t q, std::size_t limit) {
    const std::size_t begin = 64 * q;
    if (limit >= begin + 64) return kAllBits;
    if (limit <= begin) return kNoBits;
    return (Word{1} << (limit - begin)) - 1;
}

// Bit r of the result is bit r+1 of the row: the row's neighbour in +x.
VOXMESH_HOT_INLINE Word next_x(const Word* row, std::size_t q, std::size_t words) {
    return row[q] >> 1 | (q + 1 < words ? row[q + 1] << 63 : 0);
}

// Crossed owned edges of a row (sample x owns x->x+1, y->y+1, z->z+1) as three masks.
// next_y / next_z are the neighbouring rows; at the volume's border pass the row itself
// (nothing crosses). Only the row's last word needs the next-word and row-end tests.
struct EdgeMasks {
    Word x, y, z;
    Word any() const { return x | y | z; }
};

VOXMESH_HOT_INLINE EdgeMasks edge_masks(const Word* row, const Word* next_y, const Word* next_z, std::size_t q,
                                        std::size_t words, std::size_t nx) {
    const Word here = row[q];
    const Word x = q + 1 < words ? here ^ (here >> 1 | row[q + 1] << 63) : (here ^ here >> 1) & bits_below(q, nx - 1);
    return {x, here ^ next_y[q], here ^ next_z[q]};
}

// A set of a row's words as one mask: bit q for word q < 63, bit 63 for all words from 63 on
// (rows of more than 4032 samples share it).
inline Word word_bit(std::size_t q) { return Word{1} << (q < 63 ? q : 63); }

inline unsigned popcount(Word w) { return static_cast<unsigned>(std::popcount(w)); }

// The eight corner masks of the 64 cells in word q of the cell row spanned by rows
// a=(y,z), b=(y+1,z), c=(y,z+1), d=(y+1,z+1), in case-bit order: bit k of a cell's case is
// bit r of corner[k]. Loaded once per word, then read per cell.
struct CellWord {
    Word corner[8];

    VOXMESH_HOT_INLINE CellWord(const Word* a, const Word* b, const Word* c, const Word* d, std::size_t q, std::size_t words)
        : corner{a[q], next_x(a, q, words), next_x(b, q, words), b[q],
                 c[q], next_x(c, q, words), next_x(d, q, words), d[q]} {}

    // Bit set where the cell's 8 corners are not all equal (cells x < nx - 1 only).
    VOXMESH_HOT_INLINE Word nonuniform(std::size_t q, std::size_t nx) const {
        Word diff = 0;
        for (unsigned k = 1; k < 8; ++k) diff |= corner[0] ^ corner[k];
        return diff & bits_below(q, nx - 1);
    }

    // Case index of cell 64q + r (bit k set where corner k is inside). Below bit 63 a cell's
    // x and x+1 bits are neighbours in the rows' own words: four 2-bit pairs and a lookup.
    VOXMESH_HOT_INLINE unsigned cell_case(unsigned r) const {
        if (r < 63) return kRowPairsToCase[row_pairs(r)];
        unsigned c = 0;
        for (unsigned k = 0; k < 8; ++k) c |= static_cast<unsigned>(corner[k] >> r & 1) << k;
        return c;
    }

    // The number of triangles of cell 64q + r.
    VOXMESH_HOT_INLINE unsigned triangles(unsigned r) const {
        return r < 63 ? kRowPairsToTriangles[row_pairs(r)] : kCaseTable[cell_case(r)].count;
    }

    // The triangles of the cells set in `cells` (non-uniform ones), without a loop over them.
    // Every non-uniform case of the table has V - 2F - 4R triangles: V inside corners, F faces
    // with four inside corners, R = 1 for the four "rings" (the two outside corners at the
    // ends of a body diagonal). Why: a polygon through n edge vertices is n - 2 triangles, so
    // T = E - 2P (E crossed edges, P polygons); E = 3V - 2I (I edges with both corners
    // inside); the table makes one polygon per group of inside corners joined by edges, which
    // is V - I + F, except in a ring, whose six inside corners form a cycle with no face and
    // get two polygons (V - I + F + 2). The case-table test checks all 254 cases.
    VOXMESH_HOT_INLINE unsigned triangle_sum(Word cells) const {
        const Word* c = corner;
        int v = 0;
        for (unsigned k = 0; k < 8; ++k) v += std::popcount(c[k] & cells);
        const Word x01 = c[0] & c[1], x32 = c[3] & c[2], x45 = c[4] & c[5], x76 = c[7] & c[6];
        const Word y03 = c[0] & c[3], y12 = c[1] & c[2], y47 = c[4] & c[7], y56 = c[5] & c[6];
        const int f = std::popcount(x01 & x32 & cells) + std::popcount(x45 & x76 & cells) +
                      std::popcount(x01 & x45 & cells) + std::popcount(x32 & x76 & cells) +
                      std::popcount(y03 & y47 & cells) + std::popcount(y12 & y56 & cells);
        const Word rings = (~c[0] & ~c[6] & y12 & y47 & c[3] & c[5]) | (~c[1] & ~c[7] & y03 & y56 & c[2] & c[4]) |
                           (~c[2] & ~c[4] & y03 & y56 & c[1] & c[7]) | (~c[3] & ~c[5] & y12 & y47 & c[0] & c[6]);
        return static_cast<unsigned>(v - 2 * f - 4 * std::popcount(rings & cells));
    }

    // A word with more than this many non-uniform cells has its triangles counted in one go
    // (triangle_sum, about 100 instructions), fewer cell by cell. In-process A/B, 2 threads:
    // classify -3 to -11 % on gyroid u8 256³, u8 512³ and f32 512³, sphere ±0; summing every
    // word cost sphere u8 512³ +7 to +10 % classify (its words hold one to four such cells).
    static constexpr unsigned kCellsToSum = 4;

    // The triangles of the cells set in `cells` (non-uniform ones), whichever way is cheaper.
    VOXMESH_HOT_INLINE unsigned triangle_count(Word cells) const {
        if (std::popcount(cells) > static_cast<int>(kCellsToSum)) return triangle_sum(cells);
        unsigned count = 0;
        for (Word rest = cells; rest; rest &= rest - 1) count += triangles(static_cast<unsigned>(std::countr_zero(rest)));
        return count;
    }

private:
    // Rows a, b, c, d's bits r and r + 1 (r < 63), two bits each.
    VOXMESH_HOT_INLINE unsigned row_pairs(unsigned r) const {
        return static_cast<unsigned>((corner[0] >> r & 3) | (corner[3] >> r & 3) << 2 | (corner[4] >> r & 3) << 4 |
                                     (corner[7] >> r & 3) << 6);
    }
};

}  // namespace voxmesh::detail
