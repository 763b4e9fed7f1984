// Writing a mesh or a volume to a stream the caller opened (the CLI's standard output), with
// the same checks and bytes as write_mesh and write_nrrd, which write through a temporary file.
// A failure may leave part of the output written: a stream cannot be taken back.
#pragma once

#include <voxmesh/io.hpp>
#include <voxmesh/voxmesh.hpp>

#include <cstdio>
#include <map>
#include <string>

namespace voxmesh::detail {

// `format`: ".stl", ".ply", ".obj" or ".glb"; `name` names the output in errors ("cannot write 'name': ...").
void write_mesh_to(std::FILE* file, const Mesh& mesh, const std::string& format, const std::string& name);
void write_nrrd_to(std::FILE* file, const VolumeView& volume, const std::map<std::string, std::string>& key_values,
                   const std::string& name);

}  // namespace voxmesh::detail
