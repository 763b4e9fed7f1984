// A Mesh's structure: the arrays' consistency, and edges shared by triangles.
#include "components.hpp"
#include "mesh_arrays.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace voxmesh {

namespace detail {

void check_mesh_arrays(const Mesh& mesh, const std::string& who) {
    if (mesh.positions.size() % 3 || mesh.indices.size() % 3) throw Error(who + "mesh arrays are not multiples of 3");
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
        throw Error(who + "mesh has normals for a different number of vertices than positions");
    const std::size_t n = mesh.vertex_count();
    for (const std::uint32_t i : mesh.indices)
        if (i >= n)
            throw Error(who + "mesh index " + std::to_string(i) + " is out of range (" + std::to_string(n) + " vertices)");
}

void check_finite_vertices(const std::vector<float>& values, const std::string& who, const char* what) {
    for (std::size_t i = 0; i < values.size(); ++i)
        if (!std::isfinite(values[i]))
            throw Error(who + "vertex " + std::to_string(i / 3) + " has a non-finite " + what);
}

}  // namespace detail

MeshTopology analyze_topology(const Mesh& mesh) {
    detail::check_mesh_arrays(mesh, "analyze_topology: ");
    std::vector<std::uint64_t> edges;
    edges.reserve(mesh.indices.size());
    std::vector<bool> used(mesh.vertex_count(), false);
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        for (int k = 0; k < 3; ++k) {
            const std::uint64_t a = mesh.indices[3 * t + k], b = mesh.indices[3 * t + (k + 1) % 3];
            edges.push_back(std::min(a, b) << 32 | std::max(a, b));
            used[a] = true;
        }
    }
    std::sort(edges.begin(), edges.end());
    MeshTopology topo;
    long long unique_edges = 0;
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        const std::size_t uses = j - i;
        ++unique_edges;
        if (uses == 1) ++topo.boundary_edges;
        else if (uses > 2) ++topo.nonmanifold_edges;
        i = j;
    }
    const long long vertices = std::count(used.begin(), used.end(), true);
    topo.euler = vertices - unique_edges + static_cast<long long>(mesh.triangle_count());
    topo.components = detail::mesh_pieces(mesh).triangles.size();
    return topo;
}

}  // namespace voxmesh
