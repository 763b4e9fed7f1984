// The public mesh readers: a path or bytes in memory, and the reader the name's extension picks.
#include "core/out_of_memory.hpp"
#include "input_file.hpp"
#include "mesh_readers.hpp"

#include <voxmesh/io.hpp>

#include <filesystem>

namespace voxmesh {

namespace {

using Reader = Mesh (*)(const io::InputFile&);

Reader reader_for(const std::string& name) {
    if (io::ends_with_nocase(name, ".stl")) return io::read_stl_from;
    if (io::ends_with_nocase(name, ".ply")) return io::read_ply_from;
    if (io::ends_with_nocase(name, ".obj")) return io::read_obj_from;
    io::fail(name, "unknown mesh format '" + std::filesystem::path(name).extension().string() +
                       "' (read: .stl, .ply or .obj)");
}

// reader(the file at `path`), out of memory anywhere in it an Error naming the file.
Mesh read_file(const std::string& path, Reader reader) {
    return io::out_of_memory_reading(path, "mesh", [&] {
        const io::InputFile file(path);
        return reader(file);
    });
}

}  // namespace

Mesh read_stl(const std::string& path) { return read_file(path, io::read_stl_from); }
Mesh read_ply(const std::string& path) { return read_file(path, io::read_ply_from); }
Mesh read_obj(const std::string& path) { return read_file(path, io::read_obj_from); }
Mesh read_mesh(const std::string& path) { return read_file(path, reader_for(path)); }

Mesh read_mesh_from_memory(const void* data, std::size_t size, const std::string& name) {
    const Reader reader = reader_for(name);
    return io::out_of_memory_reading(name, "mesh", [&] {
        const io::InputFile file(name, data, size);
        return reader(file);
    });
}

}  // namespace voxmesh
