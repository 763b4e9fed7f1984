// A Mesh's structure: the arrays' consistency, and edges shared by triangles.
#include "components.hpp"
#include "mesh_arrays.hpp"
#include "out_of_memory.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
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

namespace {

MeshTopology topology_of(const Mesh& mesh) {
    const std::size_t vertices = mesh.vertex_count();
    // Each triangle side filed under its lower vertex, holding the higher one (a counting
    // sort: linear, where sorting 3 keys a triangle took longer than extract itself on large
    // meshes). A vertex's list is a handful long; sorted, a run of one higher vertex is one
    // edge and its length the triangles on it.
    std::vector<std::size_t> list_end(vertices + 1, 0);
    std::vector<bool> used(vertices, false);
    const auto sides = [&](auto&& visit) {
        for (std::size_t i = 0; i < mesh.indices.size(); i += 3)
            for (std::size_t k = 0; k < 3; ++k) {
                const std::uint32_t a = mesh.indices[i + k], b = mesh.indices[i + (k + 1) % 3];
                visit(std::min(a, b), std::max(a, b));
            }
    };
    sides([&](std::uint32_t lo, std::uint32_t) { ++list_end[lo + 1]; });
    for (std::size_t v = 0; v < vertices; ++v) list_end[v + 1] += list_end[v];  // list_end[v]: where v's list starts
    // Every entry is written below: no zero-fill first (120 MB for 10 M triangles).
    const auto higher = std::make_unique_for_overwrite<std::uint32_t[]>(mesh.indices.size());
    sides([&](std::uint32_t lo, std::uint32_t hi) {
        higher[list_end[lo]++] = hi;  // list_end[v] ends at the start of v + 1's list
        used[lo] = used[hi] = true;
    });

    MeshTopology topo;
    long long edges = 0, used_vertices = 0;
    for (std::size_t v = 0; v < vertices; ++v) {
        used_vertices += used[v];
        std::uint32_t* const first = higher.get() + (v == 0 ? 0 : list_end[v - 1]);
        std::uint32_t* const last = higher.get() + list_end[v];
        std::sort(first, last);
        for (auto i = first; i != last;) {
            const auto j = std::find_if(i, last, [&](std::uint32_t h) { return h != *i; });
            const auto uses = j - i;
            ++edges;
            if (uses == 1) ++topo.boundary_edges;
            else if (uses > 2) ++topo.nonmanifold_edges;
            i = j;
        }
    }
    topo.euler = used_vertices - edges + static_cast<long long>(mesh.triangle_count());
    topo.components = detail::count_mesh_pieces(mesh, used);
    return topo;
}

}  // namespace

MeshTopology analyze_topology(const Mesh& mesh) {
    detail::check_mesh_arrays(mesh, "analyze_topology: ");
    return detail::out_of_memory_as_error("analyze_topology: " + detail::out_of_memory_for(mesh),
                                          [&] { return topology_of(mesh); });
}

}  // namespace voxmesh
