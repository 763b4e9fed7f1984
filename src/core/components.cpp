// A mesh's connected pieces: triangles that share a vertex belong to one piece (as in VTK's
// vtkPolyDataConnectivityFilter). A CT's iso-surface is one large piece among many specks of
// noise; keep_largest_components keeps the large ones.
#include "components.hpp"
#include "mesh_arrays.hpp"
#include "out_of_memory.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

namespace voxmesh {

namespace detail {

namespace {

// Union-find over vertex ids with path halving; the smaller root wins a union, so a piece's
// root is its lowest vertex whatever order the triangles come in.
class VertexSets {
public:
    explicit VertexSets(std::size_t vertices) : parent_(vertices) {
        std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
    }
    std::uint32_t find(std::uint32_t v) {
        while (parent_[v] != v) {
            parent_[v] = parent_[parent_[v]];
            v = parent_[v];
        }
        return v;
    }
    void unite(std::uint32_t a, std::uint32_t b) {
        a = find(a);
        b = find(b);
        if (a < b) parent_[b] = a;
        else if (b < a) parent_[a] = b;
    }

private:
    std::vector<std::uint32_t> parent_;
};

// The pieces as vertex sets: a triangle's corners united.
VertexSets united_corners(const Mesh& mesh) {
    VertexSets sets(mesh.vertex_count());
    const std::size_t triangles = mesh.triangle_count();
    for (std::size_t t = 0; t < triangles; ++t) {
        sets.unite(mesh.indices[3 * t], mesh.indices[3 * t + 1]);
        sets.unite(mesh.indices[3 * t], mesh.indices[3 * t + 2]);
    }
    return sets;
}

}  // namespace

std::size_t count_mesh_pieces(const Mesh& mesh, const std::vector<bool>& used) {
    VertexSets sets = united_corners(mesh);
    std::size_t pieces = 0;  // one root, its lowest vertex, a piece
    for (std::size_t v = 0; v < used.size(); ++v)
        pieces += used[v] && sets.find(static_cast<std::uint32_t>(v)) == v;  // used: named by a 32-bit index
    return pieces;
}

MeshPieces mesh_pieces(const Mesh& mesh) {
    VertexSets sets = united_corners(mesh);
    const std::size_t triangles = mesh.triangle_count();
    // Pieces numbered in the order of their first triangle.
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> piece_of_root(mesh.vertex_count(), kNone);
    MeshPieces pieces;
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
    const detail::MeshPieces pieces = detail::mesh_pieces(mesh);

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
    std::vector<std::uint32_t> new_index(mesh.vertex_count(), kDropped);
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
    out.positions.resize(3 * std::size_t{vertices});
    if (!mesh.normals.empty()) out.normals.resize(3 * std::size_t{vertices});
    out.indices.resize(3 * triangles);
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
    return detail::out_of_memory_as_error("keep_largest_components: " + detail::out_of_memory_for(mesh),
                                          [&] { return largest_pieces(mesh, count); });
}

}  // namespace voxmesh
