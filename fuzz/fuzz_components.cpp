// libFuzzer target: analyze_topology against the tests' sorted-edge oracle, and
// keep_largest_components and MeshTopology::components against their breadth-first one, on
// meshes of any shape (repeated corners, unused vertices, pieces touching at a vertex). The
// input is a vertex count byte, a count-to-keep byte, then two bytes per index (modulo the
// vertex count); positions and normals are made from the ids.
#include "fuzz_common.hpp"
#include "support/mesh_checks.hpp"

#include <algorithm>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2) return 0;
    const std::size_t n = 1 + data[0] % 128u, keep = 1 + data[1] % 8u;
    const bool normals = data[0] & 128u;
    voxmesh::Mesh mesh;
    for (std::size_t v = 0; v < n; ++v)
        for (std::size_t c = 0; c < 3; ++c) {
            mesh.positions.push_back(static_cast<float>(3 * v + c));
            if (normals) mesh.normals.push_back(-static_cast<float>(3 * v + c));
        }
    for (std::size_t i = 2; i + 1 < size && mesh.indices.size() < 3 * 512; i += 2)
        mesh.indices.push_back(static_cast<std::uint32_t>((data[i] | data[i + 1] << 8) % n));
    mesh.indices.resize(mesh.indices.size() / 3 * 3);

    std::size_t pieces = 0;
    vmtest::oracle_pieces(mesh, pieces);
    const voxmesh::MeshTopology topology = voxmesh::analyze_topology(mesh);
    const vmtest::Topology edges = vmtest::topology(mesh);
    if (topology.components != pieces || topology.boundary_edges != edges.boundary_edges ||
        topology.nonmanifold_edges != edges.nonmanifold_edges || topology.euler != edges.euler)
        std::abort();
    const voxmesh::Mesh kept = voxmesh::keep_largest_components(mesh, keep);
    const voxmesh::Mesh expected = vmtest::oracle_keep_largest(mesh, keep);
    if (kept.indices != expected.indices || !vmtest::same_bits(kept.positions, expected.positions) ||
        !vmtest::same_bits(kept.normals, expected.normals))
        std::abort();
    if (voxmesh::analyze_topology(kept).components != std::min(keep, pieces)) std::abort();
    return 0;
}
