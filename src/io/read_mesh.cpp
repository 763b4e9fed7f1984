// read_mesh: the mesh reader named by the file's extension.
#include "input_file.hpp"

#include <voxmesh/io.hpp>

#include <filesystem>

namespace voxmesh {

Mesh read_mesh(const std::string& path) {
    if (io::ends_with_nocase(path, ".stl")) return read_stl(path);
    if (io::ends_with_nocase(path, ".ply")) return read_ply(path);
    if (io::ends_with_nocase(path, ".obj")) return read_obj(path);
    io::fail(path, "unknown mesh format '" + std::filesystem::path(path).extension().string() +
                       "' (read: .stl, .ply or .obj)");
}

}  // namespace voxmesh
