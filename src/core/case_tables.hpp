// The one source of the marching-cubes case tables, shared by the CPU engine and the
// OpenCL kernels (which receive these arrays from the host).
#pragma once

#include <array>
#include <cstdint>

namespace voxmesh::detail {

// Corner c of a cell sits at kCornerOffset[c] (dx, dy, dz); bit c of a case index is set
// where that corner is inside (value >= iso).
extern const std::uint8_t kCornerOffset[8][3];

// Edge e joins two corners and is owned by the sample at (dx, dy, dz) from the cell's
// origin, along `axis` (0 = x, 1 = y, 2 = z).
struct CellEdge {
    std::uint8_t dx, dy, dz, axis;
};
extern const CellEdge kCellEdge[12];

// Per case: the number of triangles and their edges, wound counter-clockwise seen from
// outside (for value >= iso inside); unused entries are -1. Derived from VTK's table by
// tools/gen_case_table.py, so the triangles are exactly VTK's.
struct CaseEntry {
    std::uint8_t count;
    std::int8_t edges[15];
};
extern const CaseEntry kCaseTable[256];

// Case index from two 4-bit column codes at x and x+1, where a column code holds the
// inside bits of rows (y, z), (y+1, z), (y, z+1), (y+1, z+1) in bits 0..3.
extern const std::array<std::uint8_t, 256> kColumnPairToCase;

// Case index from the inside bits at x and x+1 (bits 0 and 1 of a 2-bit pair) of rows
// (y, z), (y+1, z), (y, z+1), (y+1, z+1), their pairs at bits 0, 2, 4, 6 of the index.
extern const std::array<std::uint8_t, 256> kRowPairsToCase;
// kCaseTable[kRowPairsToCase[pairs]].count: classify counts a cell's triangles in one lookup.
extern const std::array<std::uint8_t, 256> kRowPairsToTriangles;

}  // namespace voxmesh::detail
