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
// Case index of every 8-bit index that holds corner c's inside bit at bit index_bit(dx, dy, dz)
// of the corner's offset.
template <class IndexBit>
std::array<std::uint8_t, 256> cases_by_index(IndexBit index_bit) {
    std::array<std::uint8_t, 256> table{};
    for (int index = 0; index < 256; ++index) {
        int code = 0;
        for (int c = 0; c < 8; ++c)
            if (index >> index_bit(kCornerOffset[c][0], kCornerOffset[c][1], kCornerOffset[c][2]) & 1) code |= 1 << c;
        table[index] = static_cast<std::uint8_t>(code);
    }
    return table;
}
}  // namespace

// Column code at x + dx in bits 4 dx..4 dx + 3, its bit dy + 2 dz for row (y + dy, z + dz).
const std::array<std::uint8_t, 256> kColumnPairToCase =
    cases_by_index([](int dx, int dy, int dz) { return 4 * dx + dy + 2 * dz; });
// Row (y + dy, z + dz)'s pair in bits 2 (dy + 2 dz)..+1, its bit dx for x + dx.
const std::array<std::uint8_t, 256> kRowPairsToCase =
    cases_by_index([](int dx, int dy, int dz) { return 2 * (dy + 2 * dz) + dx; });

// Defined after kRowPairsToCase: initialised in that order.
const std::array<std::uint8_t, 256> kRowPairsToTriangles = [] {
    std::array<std::uint8_t, 256> table{};
    for (std::size_t pairs = 0; pairs < 256; ++pairs) table[pairs] = kCaseTable[kRowPairsToCase[pairs]].count;
    return table;
}();

}  // namespace voxmesh::detail
