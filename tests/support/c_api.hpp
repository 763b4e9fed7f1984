// Helpers of the C API tests (test_c_api*.cpp): owning pointers for its objects, a C view of a
// C++ one, and byte-for-byte comparisons of what the C calls give with what the C++ calls give.
#pragma once

#include <catch2/catch.hpp>
#include <voxmesh/voxmesh.h>
#include <voxmesh/voxmesh.hpp>

#include <memory>

namespace capitest {

using MeshPtr = std::unique_ptr<voxmesh_mesh, decltype(&voxmesh_mesh_free)>;
using VolumePtr = std::unique_ptr<voxmesh_volume, decltype(&voxmesh_volume_free)>;
using SculptPtr = std::unique_ptr<voxmesh_sculpt, decltype(&voxmesh_sculpt_free)>;
using BytesPtr = std::unique_ptr<voxmesh_bytes, decltype(&voxmesh_bytes_free)>;

// The enums' order is checked in test_c_api.cpp, so the type converts by value.
voxmesh_volume_view c_view(const voxmesh::VolumeView& v);

// Vertex and triangle counts, then every byte of positions, normals and indices (a C array
// is NULL where the C++ one is empty).
void require_same(const voxmesh_mesh* c, const voxmesh::Mesh& cpp);
// Type, geometry and every sample byte.
void require_same(const voxmesh_volume_view& c, const voxmesh::Volume& cpp);

// The C API's mesh of `view` with `options`; REQUIREs success.
MeshPtr extract_c(const voxmesh_volume_view& view, const voxmesh_options& options);

}  // namespace capitest
