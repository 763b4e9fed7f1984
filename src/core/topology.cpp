// A Mesh's structure: the arrays' consistency, and edges shared by triangles.
#include "components.hpp"
#include "huge_pages.hpp"
#include "mesh_arrays.hpp"
#include "out_of_memory.hpp"
#include "parallel.hpp"

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

namespace detail {

// Each triangle side is filed under its lower vertex, holding the higher one (a counting
// sort: linear, where sorting 3 keys a triangle took longer than extract itself on large
// meshes). A vertex's list is a handful long; sorted, a run of one higher vertex is one edge
// and its length the triangles on it.
// In parallel, worker w owns a share of the vertex ids (share_of): it reads every side and
// files those whose lower vertex it owns, so that each list is written by one worker, in
// the order of the triangles, as on one thread; the counts do not depend on the workers.
MeshTopology topology_with_workers(const Mesh& mesh, unsigned workers) {
    const std::size_t vertices = mesh.vertex_count(), side_count = mesh.indices.size();
    const std::uint32_t* const corners = mesh.indices.data();
    workers = std::max(workers, 1u);
    // Visits (lower, higher) of the sides whose lower vertex worker w owns, and the corners it
    // owns (each once per triangle naming it).
    const auto owned = [&](unsigned w, auto&& side, auto&& corner) {
        const detail::Share mine = detail::share_of(vertices, w, workers);
        const std::size_t begin = mine.begin, span = mine.end - mine.begin;
        for (std::size_t i = 0; i < side_count; i += 3) {
            const std::uint32_t c[3] = {corners[i], corners[i + 1], corners[i + 2]};
            // A triangle with a repeated corner (a, a, b) has one edge, {a, b}, though two of
            // its sides name it; a side from a corner to itself is no edge.
            const bool degenerate = c[0] == c[1] || c[1] == c[2] || c[0] == c[2];
            bool filed = false;
            for (std::size_t k = 0; k < 3; ++k) {
                const std::uint32_t a = c[k], b = c[(k + 1) % 3], lo = std::min(a, b);
                if (a - begin < span) corner(a);
                if (a == b || (degenerate && filed)) continue;
                filed = true;
                if (lo - begin < span) side(lo, std::max(a, b));
            }
        }
    };

    // Fresh from the kernel, zeroed and in huge pages (huge_pages.hpp): the passes below fault
    // them in on every worker, where a vector's fill and 4 KiB pages faulted on one thread.
    const auto list_end_block = allocate_zeroed((vertices + 1) * sizeof(std::size_t));
    std::size_t* const list_end = static_cast<std::size_t*>(list_end_block.get());
    std::vector<std::uint8_t> used(vertices, 0);  // bytes: workers mark their own vertices only
    detail::run_workers(workers, [&](unsigned w) {
        owned(w, [&](std::uint32_t lo, std::uint32_t) { ++list_end[std::size_t{lo} + 1]; }, [](std::uint32_t) {});
    });
    for (std::size_t v = 0; v < vertices; ++v) list_end[v + 1] += list_end[v];  // list_end[v]: where v's list starts
    // Every entry up to list_end[vertices] is written below (120 MB for 10 M triangles; fewer
    // when triangles repeat a corner).
    const auto higher_block = allocate_zeroed(side_count * sizeof(std::uint32_t));
    std::uint32_t* const higher = static_cast<std::uint32_t*>(higher_block.get());
    detail::run_workers(workers, [&](unsigned w) {
        owned(
            w,
            [&](std::uint32_t lo, std::uint32_t hi) { higher[list_end[lo]++] = hi; },  // list_end[v]: v's list's end
            [&](std::uint32_t v) { used[v] = 1; });
    });

    struct Counts {
        long long edges = 0, used_vertices = 0;
        std::size_t boundary = 0, nonmanifold = 0;
    };
    std::vector<Counts> counts(workers);
    detail::run_workers(workers, [&](unsigned w) {
        Counts& n = counts[w];
        const detail::Share mine = detail::share_of(vertices, w, workers);
        for (std::size_t v = mine.begin; v < mine.end; ++v) {
            n.used_vertices += used[v];
            std::uint32_t* const first = higher + (v == 0 ? 0 : list_end[v - 1]);
            std::uint32_t* const last = higher + list_end[v];
            std::sort(first, last);
            for (auto i = first; i != last;) {
                const auto j = std::find_if(i, last, [&](std::uint32_t h) { return h != *i; });
                const auto uses = j - i;
                ++n.edges;
                if (uses == 1) ++n.boundary;
                else if (uses > 2) ++n.nonmanifold;
                i = j;
            }
        }
    });
    MeshTopology topo;
    long long edges = 0, used_vertices = 0;
    for (const Counts& n : counts) {
        edges += n.edges;
        used_vertices += n.used_vertices;
        topo.boundary_edges += n.boundary;
        topo.nonmanifold_edges += n.nonmanifold;
    }
    topo.euler = used_vertices - edges + static_cast<long long>(mesh.triangle_count());
    topo.components = detail::count_mesh_pieces(mesh, used, workers);
    return topo;
}

}  // namespace detail

MeshTopology analyze_topology(const Mesh& mesh) {
    detail::check_mesh_arrays(mesh, "analyze_topology: ");
    return detail::out_of_memory_as_error(
        [&] { return "analyze_topology: " + detail::out_of_memory_for(mesh); },
        [&] { return detail::topology_with_workers(mesh, detail::workers_for_sides(mesh.indices.size())); });
}

}  // namespace voxmesh
