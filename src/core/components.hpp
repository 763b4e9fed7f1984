// Which connected piece each triangle of a mesh is in (triangles sharing a vertex are in one),
// for analyze_topology's count and keep_largest_components.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace voxmesh::detail {

struct MeshPieces {
    std::vector<std::uint32_t> of_triangle;  // per triangle, its piece: 0, 1, ... in order of first triangle
    std::vector<std::size_t> triangles;      // per piece, how many triangles it has
};
// The mesh's arrays must have passed check_mesh_arrays. `workers` threads unite the corners;
// the result does not depend on how many.
MeshPieces mesh_pieces(const Mesh& mesh, unsigned workers);
// How many pieces, where used[v] != 0 says that a triangle names vertex v: the count alone,
// without mesh_pieces' per-triangle array (4 bytes a triangle, written and then unread), on
// `workers` threads.
std::size_t count_mesh_pieces(const Mesh& mesh, const std::vector<std::uint8_t>& used, unsigned workers);

// Threads for a pass over a mesh of `sides` triangle sides: one per 2^20 sides, at most
// resolve_threads(0).
unsigned workers_for_sides(std::size_t sides);

// analyze_topology's work on `workers` threads (it picks the count from the mesh's size); the
// same result on any count. Arrays checked by the caller.
MeshTopology topology_with_workers(const Mesh& mesh, unsigned workers);

}  // namespace voxmesh::detail
