// The mesh readers over an InputFile (a path opened, or bytes in memory), for read_mesh.cpp's
// public read_* functions, which add the out-of-memory Error naming the file.
#pragma once

#include "input_file.hpp"

#include <voxmesh/voxmesh.hpp>

namespace voxmesh::io {

Mesh read_stl_from(const InputFile& file);
Mesh read_ply_from(const InputFile& file);
Mesh read_obj_from(const InputFile& file);

}  // namespace voxmesh::io
