// A mesh's connected pieces: triangles that share a vertex belong to one piece (as in VTK's
// vtkPolyDataConnectivityFilter). A CT's iso-surface is one large piece among many specks of
// noise; keep_largest_components keeps the large ones.
#include "components.hpp"
#include "array_sizing.hpp"
#include "huge_pages.hpp"
#include "mesh_arrays.hpp"
#include "out_of_memory.hpp"
#include "parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

namespace voxmesh {

namespace detail {

namespace {

// Sides per worker below which one more worker is not worth its wake-up.
constexpr std::size_t kSidesPerWorker = std::size_t{1} << 20;

// Union-find over vertex ids, shared by worker threads: a root is only ever linked under a
// lower vertex (by compare-and-swap, retried when another thread linked it first), so
// parent <= vertex always, no cycle can form, and a piece's root is its lowest vertex
// whatever order the triangles are united in. Path halving on the way up.
class VertexSets {
public:
    VertexSets(std::size_t vertices, unsigned workers)
        : parent_block_(allocate_zeroed(vertices * sizeof(std::uint32_t))),
          parent_(static_cast<std::uint32_t*>(parent_block_.get())) {
        run_workers(workers, [&](unsigned w) {
            const Share mine = share_of(vertices, w, workers);
            for (std::size_t v = mine.begin; v < mine.end; ++v) parent_[v] = static_cast<std::uint32_t>(v);
        });
    }
    std::uint32_t find(std::uint32_t v) {
        for (;;) {
            std::uint32_t p = at(v).load(std::memory_order_relaxed);
            if (p == v) return v;
            const std::uint32_t grand = at(p).load(std::memory_order_relaxed);
            if (grand != p) at(v).compare_exchange_weak(p, grand, std::memory_order_relaxed);  // a lost race is harmless
            v = grand;
        }
    }
    void unite(std::uint32_t a, std::uint32_t b) {
        for (;;) {
            a = find(a);
            b = find(b);
            if (a == b) return;
            if (a > b) std::swap(a, b);
            std::uint32_t expected = b;
            if (at(b).compare_exchange_strong(expected, a, std::memory_order_relaxed)) return;
        }
    }

private:
    std::atomic_ref<std::uint32_t> at(std::uint32_t v) { return std::atomic_ref<std::uint32_t>(parent_[v]); }
    std::shared_ptr<void> parent_block_;  // fresh pages in huge pages, faulted in by the workers below
    std::uint32_t* parent_;
};

// The pieces as vertex sets: each triangle's corners united, the triangles split among
// `workers` threads.
VertexSets united_corners(const Mesh& mesh, unsigned workers) {
    VertexSets sets(mesh.vertex_count(), workers);
    const std::size_t triangles = mesh.triangle_count();
    const std::uint32_t* const corners = mesh.indices.data();
    run_workers(workers, [&](unsigned w) {
        const Share mine = share_of(triangles, w, workers);
        for (std::size_t t = mine.begin; t < mine.end; ++t) {
            sets.unite(corners[3 * t], corners[3 * t + 1]);
            sets.unite(corners[3 * t], corners[3 * t + 2]);
        }
    });
    return sets;
}

}  // namespace

unsigned workers_for_sides(std::size_t sides) {
    return static_cast<unsigned>(std::clamp<std::size_t>(sides / kSidesPerWorker, 1, resolve_threads(0)));
}

std::size_t count_mesh_pieces(const Mesh& mesh, const std::vector<std::uint8_t>& used, unsigned workers) {
    VertexSets sets = united_corners(mesh, workers);
    std::vector<std::size_t> roots(workers, 0);  // one root, its lowest vertex, a piece
    const std::size_t vertices = used.size();
    run_workers(workers, [&](unsigned w) {
        const Share mine = share_of(vertices, w, workers);
        for (std::size_t v = mine.begin; v < mine.end; ++v)
            roots[w] += used[v] && sets.find(static_cast<std::uint32_t>(v)) == v;  // used: named by a 32-bit index
    });
    return std::accumulate(roots.begin(), roots.end(), std::size_t{0});
}

MeshPieces mesh_pieces(const Mesh& mesh, unsigned workers) {
    VertexSets sets = united_corners(mesh, std::max(workers, 1u));
    const std::size_t triangles = mesh.triangle_count();
    // Pieces numbered in the order of their first triangle.
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> piece_of_root;
    reserve_huge(piece_of_root, mesh.vertex_count());  // huge pages: 4 KiB ones faulted one by one here
    piece_of_root.assign(mesh.vertex_count(), kNone);
    MeshPieces pieces;
    reserve_huge(pieces.of_triangle, triangles);
    pieces.of_triangle.resize(triangles);
    for (std::size_t t = 0; t < triangles; ++t) {
        std::uint32_t& piece = piece_of_root[sets.find(mesh.indices[3 * t])];
        if (piece == kNone) {
            piece = static_cast<std::uint32_t>(pieces.triangles.size());
            pieces.triangles.push_back(0);
        }
        pieces.of_triangle[t] = piece;
        ++pieces.triangles[piece];
    }
    return pieces;
}

}  // namespace detail

namespace {

Mesh largest_pieces(const Mesh& mesh, std::size_t count) {
    const detail::MeshPieces pieces = detail::mesh_pieces(mesh, detail::workers_for_sides(mesh.indices.size()));

    // The `count` pieces with the most triangles; of equal ones, those met first.
    std::vector<std::uint32_t> order(pieces.triangles.size());
    std::iota(order.begin(), order.end(), std::uint32_t{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return pieces.triangles[a] > pieces.triangles[b]; });
    std::vector<bool> kept_piece(pieces.triangles.size(), false);
    for (std::size_t i = 0; i < std::min(count, order.size()); ++i) kept_piece[order[i]] = true;

    // The kept triangles in their order, their vertices in theirs: a piece of a canonical mesh
    // stays in canonical order.
    constexpr std::uint32_t kDropped = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> new_index;
    detail::reserve_huge(new_index, mesh.vertex_count());
    new_index.assign(mesh.vertex_count(), kDropped);
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
        if (kept_piece[pieces.of_triangle[t]])
            for (std::size_t k = 0; k < 3; ++k) new_index[mesh.indices[3 * t + k]] = 0;
    std::uint32_t vertices = 0;
    for (std::uint32_t& i : new_index)
        if (i != kDropped) i = vertices++;
    std::size_t triangles = 0;
    for (std::size_t piece = 0; piece < pieces.triangles.size(); ++piece)
        if (kept_piece[piece]) triangles += pieces.triangles[piece];

    Mesh out;
    detail::ArraySizing sizing;  // a new mesh's pages sized as extract's are (array_sizing.hpp)
    sizing.add(out.positions, 3 * std::size_t{vertices});
    if (!mesh.normals.empty()) sizing.add(out.normals, 3 * std::size_t{vertices});
    sizing.add(out.indices, 3 * triangles);
    sizing.run(0);
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
        if (new_index[v] == kDropped) continue;
        const std::size_t to = 3 * std::size_t{new_index[v]};
        for (std::size_t c = 0; c < 3; ++c) {
            out.positions[to + c] = mesh.positions[3 * v + c];
            if (!mesh.normals.empty()) out.normals[to + c] = mesh.normals[3 * v + c];
        }
    }
    std::size_t written = 0;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
        if (kept_piece[pieces.of_triangle[t]])
            for (std::size_t k = 0; k < 3; ++k) out.indices[written++] = new_index[mesh.indices[3 * t + k]];
    return out;
}

}  // namespace

Mesh keep_largest_components(const Mesh& mesh, std::size_t count) {
    detail::check_mesh_arrays(mesh, "keep_largest_components: ");
    if (count == 0) throw Error("keep_largest_components: count must be at least 1");
    return detail::out_of_memory_as_error([&] { return "keep_largest_components: " + detail::out_of_memory_for(mesh); },
                                          [&] { return largest_pieces(mesh, count); });
}

}  // namespace voxmesh
