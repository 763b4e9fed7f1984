// libFuzzer target: write_mesh in each format, then read_mesh of what it wrote. Whatever mesh
// the writer accepts, PLY and OBJ must give back its positions, normals and indices bit for
// bit, and STL (welded on reading, normals not stored) every triangle's corner positions in
// order (-0 read as +0). The input is a flags byte, a vertex count, then floats for the
// positions (and normals), then one byte per index (taken modulo the vertex count).
#include "fuzz_common.hpp"

#include <array>
#include <cstring>
#include <vector>

namespace {

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

// Each triangle's nine corner coordinates, -0 as +0 (the STL reader welds the two).
std::vector<std::array<float, 9>> corners(const voxmesh::Mesh& m) {
    std::vector<std::array<float, 9>> out(m.triangle_count());
    for (std::size_t t = 0; t < m.triangle_count(); ++t)
        for (std::size_t k = 0; k < 3; ++k)
            for (std::size_t c = 0; c < 3; ++c) out[t][3 * k + c] = m.positions[3 * m.indices[3 * t + k] + c] + 0.0f;
    return out;
}

voxmesh::Mesh read_back(const std::string& path) {
    try {
        return voxmesh::read_mesh(path);
    } catch (const voxmesh::Error&) {
        std::abort();  // the writer wrote what the reader refuses
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
    if (mesh.indices.empty()) return 0;  // a file with no triangles is refused by STL and OBJ

    for (const char* name : {"/roundtrip.ply", "/roundtrip.obj", "/roundtrip.stl"}) {
        const std::string path = fuzz::scratch_dir() + name;
        try {
            voxmesh::write_mesh(path, mesh);
        } catch (const voxmesh::Error&) {
            return 0;  // refused with a message: a NaN or infinite coordinate or normal
        }
        const voxmesh::Mesh back = read_back(path);
        if (std::strstr(name, ".stl")) {
            if (!back.normals.empty() || corners(back) != corners(mesh)) std::abort();
        } else if (!same_bits(back.positions, mesh.positions) || !same_bits(back.normals, mesh.normals) ||
                   back.indices != mesh.indices) {
            std::abort();
        }
    }
    return 0;
}
