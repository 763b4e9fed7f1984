#include "case_tables.hpp"

#include <array>

namespace voxmesh::detail {

const std::uint8_t kCornerOffset[8][3] = {
    {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

// Edges 0..11 join corners 0-1 1-2 3-2 0-3 4-5 5-6 7-6 4-7 0-4 1-5 2-6 3-7; the owner is
// the lower corner of each pair.
const CellEdge kCellEdge[12] = {
    {0, 0, 0, 0}, {1, 0, 0, 1}, {0, 1, 0, 0}, {0, 0, 0, 1}, {0, 0, 1, 0}, {1, 0, 1, 1},
    {0, 1, 1, 0}, {0, 0, 1, 1}, {0, 0, 0, 2}, {1, 0, 0, 2}, {1, 1, 0, 2}, {0, 1, 0, 2}};

const CaseEntry kCaseTable[256] = {
#include "case_table_data.inc"
};

namespace {
// Column code bit b is row (y + (b & 1), z + (b >> 1)); place the 8 corners from the pair.
std::array<std::uint8_t, 256> make_column_pair_to_case() {
    std::array<std::uint8_t, 256> table{};
    for (int pair = 0; pair < 256; ++pair) {
        int code = 0;
        for (int c = 0; c < 8; ++c) {
            const int column = kCornerOffset[c][0] ? pair >> 4 : pair & 15;
            if (column >> (kCornerOffset[c][1] + 2 * kCornerOffset[c][2]) & 1) code |= 1 << c;
        }
        table[pair] = static_cast<std::uint8_t>(code);
    }
    return table;
}

std::array<std::uint8_t, 256> make_row_pairs_to_case() {
    std::array<std::uint8_t, 256> table{};
    for (int pairs = 0; pairs < 256; ++pairs) {
        int code = 0;
        for (int c = 0; c < 8; ++c) {
            const int row = kCornerOffset[c][1] + 2 * kCornerOffset[c][2];
            if (pairs >> (2 * row + kCornerOffset[c][0]) & 1) code |= 1 << c;
        }
        table[pairs] = static_cast<std::uint8_t>(code);
    }
    return table;
}
}  // namespace

const std::array<std::uint8_t, 256> kColumnPairToCase = make_column_pair_to_case();
const std::array<std::uint8_t, 256> kRowPairsToCase = make_row_pairs_to_case();

}  // namespace voxmesh::detail
