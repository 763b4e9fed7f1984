// The one check of a Mesh's arrays that every function taking a user's Mesh makes first.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <string>
#include <vector>

namespace voxmesh::detail {

// Throws Error (its message starting with `who`, e.g. "voxelize: ") when positions or indices
// are not whole triples, normals are present for a different number of vertices, or an index
// names no vertex.
void check_mesh_arrays(const Mesh& mesh, const std::string& who = "");

// Throws Error(who + "vertex N has a non-finite " + what) for the first xyz triple of `values`
// (positions or normals) holding a NaN or an infinity.
void check_finite_vertices(const std::vector<float>& values, const std::string& who, const char* what);

}  // namespace voxmesh::detail
