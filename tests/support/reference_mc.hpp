// A deliberately naive reference marching cubes, the oracle of the core tests.
//
// One cell at a time: classify its 8 corners (inside is value >= iso), look the case up in
// voxmesh's case table (the table is the definition of the triangles) and emit a triangle
// soup keyed by grid-edge id (owning sample linear index * 3 + axis). Welding afterwards by
// sorting the distinct edge ids gives the canonical vertex order directly; the soup is
// already in canonical triangle order (cell linear index, then table order). Positions and
// normals are computed here, in double, from the definitions in DESIGN.md. Corner and edge
// numbering is this file's own (the classic convention); a test checks that the engine's
// table agrees with it.
#pragma once

#include "support/mesh_checks.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vmtest {

// Corner c of a cell at offset kRefCorner[c]; edge e joins corners kRefEdge[e][0..1].
extern const int kRefCorner[8][3];
extern const int kRefEdge[12][2];

struct RefOptions {
    double iso = 0;
    bool inside_below = false;  // winding and normals reversed; classification unchanged
    std::array<double, 3> spacing{1, 1, 1};
    std::array<double, 3> origin{0, 0, 0};
};

struct RefMesh {
    std::vector<std::uint64_t> edge_ids;  // per vertex, ascending: sample * 3 + axis
    std::vector<double> positions;        // xyz per vertex
    std::vector<double> normals;          // xyz per vertex; (0,0,0) where the gradient vanishes
    std::vector<std::uint32_t> indices;   // canonical triangle order
    std::vector<std::array<std::uint64_t, 3>> soup;  // the same triangles as edge-id triples
    std::vector<std::uint64_t> cells;                 // per triangle, its cell: x + (nx-1) * (y + (ny-1) * z)

    std::size_t vertex_count() const { return edge_ids.size(); }
    std::size_t triangle_count() const { return soup.size(); }
};

// values: x-fastest doubles, dims >= 2 on every axis.
RefMesh reference_mc(const std::vector<double>& values, const Dims& dims, const RefOptions& options);

// The case index of a cell (bit c set where corner c is inside), with this file's corners.
unsigned reference_case(const std::vector<double>& values, const Dims& dims, std::size_t x, std::size_t y,
                        std::size_t z, double iso);

// How an engine mesh compares with the oracle's.
struct Comparison {
    bool same_counts = false;        // vertex and triangle counts
    bool same_triangle_set = false;  // oriented triangles, vertices matched by position (order-free)
    bool same_indices = false;       // the index buffers are identical (canonical order)
    double max_position_error = 0;   // in canonical order, relative to 1 + |coordinate|
    double max_normal_error = 0;     // in canonical order, where the oracle's gradient is non-zero
    std::string first_problem;       // a readable description of the first difference, or ""
};
Comparison compare_with_reference(const voxmesh::Mesh& mesh, const RefMesh& ref);

}  // namespace vmtest
