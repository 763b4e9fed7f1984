// glTF 2.0 in its binary container (.glb): one buffer holding the positions, the normals and
// the indices as they are in the Mesh, described by a JSON chunk (one scene, one node, one
// mesh of one triangle primitive), for web viewers, three.js, Blender and the like.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace voxmesh::detail {

// The JSON chunk's text, padded with spaces to a multiple of 4 bytes as the container asks.
// Built once per write: it needs a pass over the positions for their bounds.
std::string glb_json(const Mesh& mesh);

// The file's size for a mesh of these counts whose JSON chunk takes `json_bytes` (no binary
// chunk for a mesh without vertices); throws Error naming `name` where that passes the
// container's 32-bit length.
std::uint64_t checked_glb_bytes(std::uint64_t vertices, bool normals, std::uint64_t triangles, std::uint64_t json_bytes,
                                const std::string& name);

// Throws Error naming `name` where a normal is not of unit length, which glTF requires (within
// the 0.00674 its validator allows; the engines' normals are within about 1e-7).
void check_glb_normals(const Mesh& mesh, const std::string& name);

// The file: header, `json` (glb_json(mesh)), then the binary chunk.
void write_glb(std::FILE* f, const Mesh& mesh, const std::string& json);

}  // namespace voxmesh::detail
