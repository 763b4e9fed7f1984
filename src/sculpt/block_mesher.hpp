// Marching cubes over one block of cells, producing a self-contained mesh: the crossed
// edges inside the block's closed box of samples, in canonical order (local sample linear
// index, then axis, which is the global order restricted to the box), and the triangles of
// the block's cells in cell order, then table order. Positions and normals come from
// EdgeVertex<T> on the whole volume, so they are bit-identical to extract()'s.
#pragma once

#include "core/case_tables.hpp"
#include "core/edge_vertex.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace voxmesh::detail::sculpt {

// The cells [c0, c0 + samples - 1) of a block on each axis; it reads samples [c0, c0 + samples).
struct BlockBox {
    std::array<std::size_t, 3> c0{0, 0, 0};
    std::array<std::size_t, 3> samples{0, 0, 0};  // cells + 1 per axis, >= 2
};

// A row of local samples is uniform (all outside / all inside) or mixed.
constexpr std::uint8_t kRowOutside = 0, kRowInside = 1, kRowMixed = 2;
constexpr std::uint8_t kCodeCount[8] = {0, 1, 1, 2, 1, 2, 2, 3};

// Per-worker scratch, sized once for the largest block and reused by every block.
struct Scratch {
    std::vector<std::uint8_t> bits;       // inside bit per local sample
    std::vector<std::uint8_t> code;       // crossed edges (bit = axis) per local sample
    std::vector<std::uint32_t> vid;       // local id of the sample's first vertex
    std::vector<std::uint8_t> row_state;  // per local row (y, z): kRowOutside/Inside/Mixed
    std::vector<std::uint8_t> row_active; // per local row: has crossed edges
    std::vector<std::uint32_t> tris;      // triangle output, copied into the block
    std::size_t capacity_bytes() const {
        return bits.capacity() + code.capacity() + 4 * vid.capacity() + row_state.capacity() +
               row_active.capacity() + 4 * tris.capacity();
    }
    void reserve_for(std::size_t block_size) {
        const std::size_t s = block_size + 1, n = s * s * s;
        if (bits.size() < n) {
            bits.resize(n);
            code.resize(n);
            vid.resize(n);
            row_state.resize(s * s);
            row_active.resize(s * s);
        }
    }
};

inline unsigned edge_offset(unsigned code, unsigned axis) {
    return axis == 0 ? 0u : axis == 1 ? (code & 1u) : (code & 1u) + (code >> 1 & 1u);
}

template <class T>
class BlockMesher {
public:
    BlockMesher(const VolumeView& volume, T threshold, double iso, bool inside_below, bool normals)
        : data_(static_cast<const T*>(volume.data)),
          nx_(volume.dims[0]),
          ny_(volume.dims[1]),
          threshold_(threshold),
          flip_(inside_below),
          normals_(normals),
          vertex_(volume, iso, inside_below) {}

    // Fills bits, row states, codes and local vertex ids for the box; returns the number of
    // vertices (0: the box has no crossed edge, nothing else is valid then).
    std::uint32_t classify(const BlockBox& box, Scratch& s) const {
        const std::size_t lx = box.samples[0], ly = box.samples[1], lz = box.samples[2];
        const std::size_t plane = lx * ly;
        std::uint8_t* bits = s.bits.data();
        std::uint8_t* state = s.row_state.data();
        unsigned all_or = 0, all_and = 1;
        for (std::size_t z = 0; z < lz; ++z) {
            for (std::size_t y = 0; y < ly; ++y) {
                const T* src = data_ + ((box.c0[2] + z) * ny_ + box.c0[1] + y) * nx_ + box.c0[0];
                std::uint8_t* b = bits + z * plane + y * lx;
                unsigned row_or = 0, row_and = 1;
                for (std::size_t x = 0; x < lx; ++x) {
                    const unsigned bit = src[x] >= threshold_;
                    b[x] = static_cast<std::uint8_t>(bit);
                    row_or |= bit;
                    row_and &= bit;
                }
                state[z * ly + y] = row_or != row_and ? kRowMixed : static_cast<std::uint8_t>(row_or);
                all_or |= row_or;
                all_and &= row_and;
            }
        }
        if (all_or == all_and) return 0;  // the whole box is one side of the surface

        std::uint32_t next = 0;
        for (std::size_t z = 0; z < lz; ++z) {
            for (std::size_t y = 0; y < ly; ++y) {
                const std::size_t r = z * ly + y;
                const std::uint8_t st = state[r];
                const bool has_y = y + 1 < ly, has_z = z + 1 < lz;
                const std::uint8_t sy = has_y ? state[r + 1] : st, sz = has_z ? state[r + ly] : st;
                if (st != kRowMixed && st == sy && st == sz) {
                    s.row_active[r] = 0;
                    continue;
                }
                s.row_active[r] = 1;
                const std::uint8_t* b = bits + z * plane + y * lx;
                const std::uint8_t* by = has_y ? b + lx : b;
                const std::uint8_t* bz = has_z ? b + plane : b;
                std::uint8_t* code = s.code.data() + z * plane + y * lx;
                std::uint32_t* vid = s.vid.data() + z * plane + y * lx;
                for (std::size_t x = 0; x < lx; ++x) {
                    const unsigned cx = x + 1 < lx ? b[x] ^ b[x + 1] : 0u;
                    const unsigned c = cx | (b[x] ^ by[x]) << 1 | (b[x] ^ bz[x]) << 2;
                    code[x] = static_cast<std::uint8_t>(c);
                    vid[x] = next;
                    next += kCodeCount[c];
                }
            }
        }
        return next;
    }

    // Calls f(local sample index, x, y, z (local), code) for each sample with a crossed owned
    // edge (bit a of code: the edge along axis a), in local order.
    template <class F>
    void for_each_crossed_sample(const BlockBox& box, const Scratch& s, F&& f) const {
        const std::size_t lx = box.samples[0], ly = box.samples[1], lz = box.samples[2];
        for (std::size_t z = 0; z < lz; ++z)
            for (std::size_t y = 0; y < ly; ++y) {
                if (!s.row_active[z * ly + y]) continue;
                const std::size_t row = (z * ly + y) * lx;
                for (std::size_t x = 0; x < lx; ++x)
                    if (const unsigned c = s.code[row + x]) f(row + x, x, y, z, c);
            }
    }

    // Calls f(local sample index, x, y, z (local), axis) for each vertex in local order.
    template <class F>
    void for_each_vertex(const BlockBox& box, const Scratch& s, F&& f) const {
        for_each_crossed_sample(box, s, [&](std::size_t at, std::size_t x, std::size_t y, std::size_t z, unsigned c) {
            for (unsigned axis = 0; axis < 3; ++axis)
                if (c >> axis & 1u) f(at, x, y, z, axis);
        });
    }

    // Writes positions/normals of the `vertices` vertices (after classify) into the arrays.
    void write_vertices(const BlockBox& box, const Scratch& s, float* positions, float* normals) const {
        std::size_t v = 0;
        for_each_crossed_sample(box, s, [&](std::size_t, std::size_t x, std::size_t y, std::size_t z, unsigned c) {
            vertex_.sample(box.c0[0] + x, box.c0[1] + y, box.c0[2] + z, c, positions + 3 * v,
                           normals_ ? normals + 3 * v : nullptr);
            v += static_cast<std::size_t>(std::popcount(c));
        });
    }

    // Appends the block's triangles (local vertex ids) to s.tris, cell order then table order.
    // If row_counts is not null, it receives the triangle count of each cell row (y, z).
    void triangles(const BlockBox& box, Scratch& s, std::uint32_t* row_counts) const {
        const std::size_t lx = box.samples[0], ly = box.samples[1], lz = box.samples[2];
        const std::size_t plane = lx * ly;
        const std::uint8_t* state = s.row_state.data();
        for (std::size_t z = 0; z + 1 < lz; ++z) {
            for (std::size_t y = 0; y + 1 < ly; ++y) {
                const std::size_t r = z * ly + y;
                const std::uint8_t sa = state[r];
                const std::size_t before = s.tris.size();
                if (sa == kRowMixed || sa != state[r + 1] || sa != state[r + ly] || sa != state[r + ly + 1]) {
                    const std::uint8_t* a = s.bits.data() + z * plane + y * lx;
                    const std::uint8_t *b = a + lx, *c = a + plane, *d = c + lx;
                    unsigned col = a[0] | b[0] << 1 | c[0] << 2 | d[0] << 3;
                    for (std::size_t x = 0; x + 1 < lx; ++x) {
                        const unsigned col1 = a[x + 1] | b[x + 1] << 1 | c[x + 1] << 2 | d[x + 1] << 3;
                        const unsigned pair = col | col1 << 4;
                        col = col1;
                        if (pair == 0 || pair == 0xFF) continue;
                        const CaseEntry& entry = kCaseTable[kColumnPairToCase[pair]];
                        for (unsigned t = 0; t < entry.count; ++t) {
                            std::uint32_t v[3];
                            for (unsigned e = 0; e < 3; ++e) {
                                const CellEdge& edge = kCellEdge[entry.edges[3 * t + e]];
                                const std::size_t at = (z + edge.dz) * plane + (y + edge.dy) * lx + x + edge.dx;
                                v[e] = s.vid[at] + edge_offset(s.code[at], edge.axis);
                            }
                            s.tris.push_back(v[0]);
                            s.tris.push_back(flip_ ? v[2] : v[1]);
                            s.tris.push_back(flip_ ? v[1] : v[2]);
                        }
                    }
                }
                if (row_counts) row_counts[r - z] = static_cast<std::uint32_t>((s.tris.size() - before) / 3);
            }
        }
    }

private:
    const T* data_;
    std::size_t nx_, ny_;
    T threshold_;
    bool flip_, normals_;
    EdgeVertex<T> vertex_;
};

}  // namespace voxmesh::detail::sculpt
