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
// The mesh's arrays must have passed check_mesh_arrays.
MeshPieces mesh_pieces(const Mesh& mesh);
// How many pieces, where used[v] says whether a triangle names vertex v: the count alone,
// without mesh_pieces' per-triangle array (4 bytes a triangle, written and then unread).
std::size_t count_mesh_pieces(const Mesh& mesh, const std::vector<bool>& used);

}  // namespace voxmesh::detail
