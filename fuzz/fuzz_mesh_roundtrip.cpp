// libFuzzer target: write_mesh in each format, then read_mesh of what it wrote. Whatever mesh
// the writer accepts, PLY and OBJ must give back its positions, normals and indices bit for
// bit, and STL (welded on reading, normals not stored) every triangle's corner positions in
// order (-0 read as +0, which compares equal). The input is a flags byte, a vertex count, then
// floats for the positions (and normals), then one byte per index (modulo the vertex count).
// write_mesh_to_memory must give the file's bytes, or refuse with write_mesh's message.
// GLB, which read_mesh does not read, is read back by the tests' glTF reader, which checks
// the file against glTF's rules on the way: the arrays bit for bit, and POSITION's min and max
// the data's own (once as given, where glTF's unit normals refuse most random normals, and
// once without normals).
#include "fuzz_common.hpp"
#include "support/glb_reader.hpp"
#include "support/mesh_checks.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <iterator>
#include <string>
#include <vector>

namespace {

voxmesh::Mesh read_back(const std::string& path) {
    try {
        return voxmesh::read_mesh(path);
    } catch (const voxmesh::Error&) {
        std::abort();  // the writer wrote what the reader refuses
    }
}

// Whatever .glb the writer gives for `mesh` (at `path` and in memory) reads back as `mesh`.
void check_glb(const voxmesh::Mesh& mesh, const std::string& path) {
    std::vector<unsigned char> in_memory;
    const auto memory_error = fuzz::error_of([&] { in_memory = voxmesh::write_mesh_to_memory(mesh, path); });
    const auto error = fuzz::error_of([&] { voxmesh::write_mesh(path, mesh); });
    if (error != memory_error) std::abort();
    if (error) return;  // a NaN or infinity, or a normal not of unit length
    std::ifstream file(path, std::ios::binary);
    const std::string written{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    if (written != std::string(in_memory.begin(), in_memory.end())) std::abort();
    vmtest::GlbContents back;
    try {
        back = vmtest::read_glb(written);
    } catch (const std::runtime_error&) {
        std::abort();  // the writer broke a rule of glTF
    }
    if (back.mode != 4 || !vmtest::same_bits(back.mesh.positions, mesh.positions) ||
        !vmtest::same_bits(back.mesh.normals, mesh.normals) || back.mesh.indices != mesh.indices)
        std::abort();
    for (std::size_t d = 0; d < 3; ++d) {
        float lo = mesh.positions[d], hi = mesh.positions[d];
        for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
            lo = std::min(lo, mesh.positions[3 * v + d]);
            hi = std::max(hi, mesh.positions[3 * v + d]);
        }
        // As a validator reads them: the text's double, compared with the data's floats.
        if (back.min[d] != static_cast<double>(lo) || back.max[d] != static_cast<double>(hi)) std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2) return 0;
    const bool normals = data[0] & 1;
    const std::size_t n = 1 + data[1] % 64u;
    const std::size_t floats = 3 * n * (normals ? 2 : 1);
    if (size < 2 + 4 * floats) return 0;
    voxmesh::Mesh mesh;
    mesh.positions.resize(3 * n);
    std::memcpy(mesh.positions.data(), data + 2, 12 * n);
    if (normals) {
        mesh.normals.resize(3 * n);
        std::memcpy(mesh.normals.data(), data + 2 + 12 * n, 12 * n);
    }
    const std::size_t rest = size - 2 - 4 * floats;
    for (std::size_t i = 0; i + 3 <= rest && i < 3 * 256; ++i)
        mesh.indices.push_back(static_cast<std::uint32_t>(data[2 + 4 * floats + i] % n));
    if (mesh.indices.empty()) return 0;  // empty meshes: test_io_mesh reads them back in each format

    for (const char* name : {"/roundtrip.ply", "/roundtrip.obj", "/roundtrip.stl"}) {
        const std::string path = fuzz::scratch_dir() + name;
        std::vector<unsigned char> in_memory;
        const auto memory_error = fuzz::error_of([&] { in_memory = voxmesh::write_mesh_to_memory(mesh, path); });
        const auto error = fuzz::error_of([&] { voxmesh::write_mesh(path, mesh); });
        if (error != memory_error) std::abort();
        if (error) return 0;  // refused with a message: a NaN or infinite coordinate or normal
        std::ifstream file(path, std::ios::binary);
        const std::string written{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
        if (written != std::string(in_memory.begin(), in_memory.end())) std::abort();
        const voxmesh::Mesh back = read_back(path);
        if (std::strstr(name, ".stl")) {
            if (!back.normals.empty() || vmtest::triangle_corners(back) != vmtest::triangle_corners(mesh)) std::abort();
        } else if (!vmtest::same_bits(back.positions, mesh.positions) || !vmtest::same_bits(back.normals, mesh.normals) ||
                   back.indices != mesh.indices) {
            std::abort();
        }
    }
    check_glb(mesh, fuzz::scratch_dir() + "/roundtrip.glb");
    voxmesh::Mesh without_normals = mesh;
    without_normals.normals.clear();
    check_glb(without_normals, fuzz::scratch_dir() + "/roundtrip.glb");
    return 0;
}
