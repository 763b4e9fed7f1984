// vertex_edges and edge_cell_ranges: which edge each vertex of the canonical mesh lies on, and
// a per-edge statistic of the cells around it (scikit-image's `values`). A pass of its own over
// the volume, not the engines': the canonical order fixes the answer, so it needs no mesh.
#include "cpu_engine.hpp"
#include "out_of_memory.hpp"
#include "parallel.hpp"
#include "scalar_dispatch.hpp"
#include "threshold.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

namespace voxmesh {

namespace {

using detail::run_slabs;

// Inside bytes (0 or 1) of plane z, plus whether it holds a NaN or infinite sample.
template <class T>
bool inside_plane(const T* samples, std::size_t count, T threshold, std::uint8_t* inside) {
    bool bad = false;
    for (std::size_t i = 0; i < count; ++i) {
        const T v = samples[i];
        inside[i] = static_cast<std::uint8_t>(v >= threshold);
        if constexpr (std::is_floating_point_v<T>) bad |= !(std::fabs(v) <= std::numeric_limits<T>::max());
    }
    return bad;
}

std::uint64_t load8(const std::uint8_t* p) {
    std::uint64_t w;
    std::memcpy(&w, p, sizeof w);
    return w;
}

// The crossed edges owned by samples of planes [z0, z1), in canonical order, appended to `out`.
// `planes` holds room for two planes of inside bytes plus 8 bytes of slack for word loads.
template <class T>
void slab_edges(const VolumeView& volume, T threshold, std::size_t z0, std::size_t z1, std::vector<std::uint8_t>& planes,
                std::vector<std::uint64_t>& out) {
    const std::size_t nx = volume.dims[0], ny = volume.dims[1], nz = volume.dims[2];
    const std::size_t plane = nx * ny;
    const T* data = static_cast<const T*>(volume.data);
    std::uint8_t* cur = planes.data();
    std::uint8_t* next = planes.data() + plane + 8;
    if (inside_plane(data + z0 * plane, plane, threshold, cur)) detail::throw_non_finite(z0);
    for (std::size_t z = z0; z < z1; ++z) {
        const bool has_next = z + 1 < nz;
        if (has_next && inside_plane(data + (z + 1) * plane, plane, threshold, next)) detail::throw_non_finite(z + 1);
        for (std::size_t y = 0; y < ny; ++y) {
            const std::uint8_t* row = cur + y * nx;
            // A missing neighbour row is the row itself: no crossing toward it.
            const std::uint8_t* up = y + 1 < ny ? row + nx : row;
            const std::uint8_t* above = has_next ? next + y * nx : row;
            const std::uint64_t base = 3 * (nx * (y + ny * z));
            // Eight samples a step: flags per byte, bit a for an edge along axis a. Bytes are 0 or 1,
            // so the shifted xors never carry into a neighbouring byte. The last sample has no
            // x-edge: it is done on its own below.
            std::size_t x = 0;
            for (; x + 8 < nx; x += 8) {
                const std::uint64_t a = load8(row + x);
                const std::uint64_t flags = (a ^ load8(row + x + 1)) | (a ^ load8(up + x)) << 1 | (a ^ load8(above + x)) << 2;
                if (flags == 0) continue;
                for (unsigned b = 0; b < 8; ++b) {
                    const unsigned f = static_cast<unsigned>(flags >> (8 * b)) & 7u;
                    for (unsigned axis = 0; axis < 3; ++axis)
                        if (f >> axis & 1u) out.push_back(base + 3 * (x + b) + axis);
                }
            }
            for (; x < nx; ++x) {
                const unsigned f = (x + 1 < nx ? row[x] ^ row[x + 1] : 0u) | (row[x] ^ up[x]) << 1 | (row[x] ^ above[x]) << 2;
                for (unsigned axis = 0; axis < 3; ++axis)
                    if (f >> axis & 1u) out.push_back(base + 3 * x + axis);
            }
        }
        std::swap(cur, next);
    }
}

// Slabs of z-planes: several per thread, so that a thread done early takes another.
unsigned slab_count(unsigned threads, std::size_t planes) {
    return static_cast<unsigned>(std::min<std::size_t>(planes, std::size_t{4} * threads));
}

template <class T>
std::vector<std::uint64_t> crossed_edges(const VolumeView& volume, double iso, unsigned threads) {
    const detail::Threshold<T> threshold = detail::make_threshold<T>(iso);
    if (threshold.uniform != detail::Uniform::Mixed) {
        if (const std::size_t z = detail::first_non_finite_plane(volume); z < volume.dims[2]) detail::throw_non_finite(z);
        return {};
    }
    const std::size_t nz = volume.dims[2], plane = volume.dims[0] * volume.dims[1];
    const unsigned slabs = slab_count(threads, nz);
    std::vector<std::vector<std::uint64_t>> found(slabs);
    std::vector<std::vector<std::uint8_t>> scratch(std::min(slabs, threads));
    run_slabs(slabs, threads, [&](unsigned slab, unsigned worker) {
        if (scratch[worker].empty()) scratch[worker].resize(2 * (plane + 8));
        const detail::Share share = detail::share_of(nz, slab, slabs);
        slab_edges<T>(volume, threshold.value, share.begin, share.end, scratch[worker], found[slab]);
    });
    std::size_t total = 0;
    for (const auto& f : found) total += f.size();
    std::vector<std::uint64_t> edges;
    edges.reserve(total);
    for (auto& f : found) {
        edges.insert(edges.end(), f.begin(), f.end());
        std::vector<std::uint64_t>().swap(f);
    }
    return edges;
}

// Throws Error unless `edge` names an edge of the volume: its lower end a sample, its upper end
// one step along its axis inside the volume too.
void check_edge(const std::array<std::size_t, 3>& dims, std::uint64_t edge) {
    const std::uint64_t sample = edge / 3;
    const unsigned axis = static_cast<unsigned>(edge % 3);
    const std::uint64_t count = static_cast<std::uint64_t>(dims[0]) * dims[1] * dims[2];
    if (sample >= count)
        throw Error("edge " + std::to_string(edge) + " starts at sample " + std::to_string(sample) +
                    ", past the volume's " + std::to_string(count) + " samples");
    const std::uint64_t at[3] = {sample % dims[0], sample / dims[0] % dims[1], sample / (dims[0] * dims[1])};
    if (at[axis] + 1 >= dims[axis])
        throw Error("edge " + std::to_string(edge) + " runs along " + std::string(1, "xyz"[axis]) + " from " +
                    std::string(1, "xyz"[axis]) + " = " + std::to_string(at[axis]) +
                    ", the volume's last sample on that axis: no edge leaves it");
}

template <class T>
void cell_ranges(const VolumeView& volume, const std::uint64_t* edges, std::size_t count, double offset,
                 const std::uint8_t* cell_mask, float* out) {
    const std::size_t nx = volume.dims[0], ny = volume.dims[1];
    const std::size_t stride[3] = {1, nx, nx * ny};
    const std::size_t cells[3] = {nx - 1, ny - 1, volume.dims[2] - 1};
    const T* data = static_cast<const T*>(volume.data);
    for (std::size_t e = 0; e < count; ++e) {
        const std::uint64_t sample = edges[e] / 3;
        const unsigned axis = static_cast<unsigned>(edges[e] % 3), p = (axis + 1) % 3, q = (axis + 2) % 3;
        const std::size_t at[3] = {static_cast<std::size_t>(sample % nx), static_cast<std::size_t>(sample / nx % ny),
                                   static_cast<std::size_t>(sample / (nx * ny))};
        // The 3 x 3 sample pairs along the edge around it, as max and min of each pair; a cell
        // around the edge is a 2 x 2 block of them (i, j = -1 or 0 its offset across p and q).
        T high[3][3]{}, low[3][3]{};
        for (int i = -1; i <= 1; ++i)
            for (int j = -1; j <= 1; ++j) {
                const bool held = !((i < 0 && at[p] == 0) || (i > 0 && at[p] + 1 > cells[p]) ||
                                    (j < 0 && at[q] == 0) || (j > 0 && at[q] + 1 > cells[q]));
                if (!held) continue;
                const std::size_t s = static_cast<std::size_t>(sample) + i * static_cast<std::ptrdiff_t>(stride[p]) +
                                      j * static_cast<std::ptrdiff_t>(stride[q]);
                const T a = data[s], b = data[s + stride[axis]];
                high[i + 1][j + 1] = std::max(a, b);
                low[i + 1][j + 1] = std::min(a, b);
            }
        float best = 0;
        for (int i = -1; i <= 0; ++i)
            for (int j = -1; j <= 0; ++j) {
                if ((i < 0 && at[p] == 0) || (i == 0 && at[p] >= cells[p]) || (j < 0 && at[q] == 0) ||
                    (j == 0 && at[q] >= cells[q]))
                    continue;  // the cell is outside the volume
                if (cell_mask) {
                    std::size_t c[3] = {at[0], at[1], at[2]};
                    c[p] += i;
                    c[q] += j;
                    if (!cell_mask[c[0] + cells[0] * (c[1] + cells[1] * c[2])]) continue;
                }
                const T top = std::max({high[i + 1][j + 1], high[i + 2][j + 1], high[i + 1][j + 2], high[i + 2][j + 2]});
                const T bottom = std::min({low[i + 1][j + 1], low[i + 2][j + 1], low[i + 1][j + 2], low[i + 2][j + 2]});
                const float range = static_cast<float>((static_cast<double>(top) - offset) - (static_cast<double>(bottom) - offset));
                best = std::max(best, range);
            }
        out[e] = best;
    }
}

}  // namespace

std::vector<std::uint64_t> vertex_edges(const VolumeView& volume, double iso, unsigned threads) {
    detail::validate_volume(volume);
    const unsigned resolved = detail::resolve_threads(threads);
    return detail::out_of_memory_as_error([] { return std::string("out of memory listing the volume's crossed edges"); },
                                          [&] {
                                              return detail::dispatch_scalar(volume.type, [&](auto tag) {
                                                  return crossed_edges<decltype(tag)>(volume, iso, resolved);
                                              });
                                          });
}

std::vector<float> edge_cell_ranges(const VolumeView& volume, std::span<const std::uint64_t> edges, double offset,
                                    const std::uint8_t* cell_mask, unsigned threads) {
    detail::validate_volume(volume);
    if (!std::isfinite(offset)) throw Error("edge_cell_ranges: offset must be finite");
    for (const std::uint64_t edge : edges) check_edge(volume.dims, edge);
    const unsigned resolved = detail::resolve_threads(threads);
    return detail::out_of_memory_as_error(
        [&] { return "out of memory for the ranges of " + std::to_string(edges.size()) + " edges"; }, [&] {
            std::vector<float> ranges(edges.size());
            // Pieces of 64 Ki edges: a few per thread on a large mesh, one on a small one.
            const std::size_t piece = std::size_t{1} << 16;
            const std::size_t pieces = (edges.size() + piece - 1) / piece;
            run_slabs(static_cast<unsigned>(std::min<std::size_t>(pieces, std::numeric_limits<unsigned>::max())),
                      resolved, [&](unsigned w, unsigned) {
                          const std::size_t begin = w * piece, end = std::min(edges.size(), begin + piece);
                          detail::dispatch_scalar(volume.type, [&](auto tag) {
                              cell_ranges<decltype(tag)>(volume, edges.data() + begin, end - begin, offset, cell_mask,
                                                         ranges.data() + begin);
                          });
                      });
            return ranges;
        });
}

}  // namespace voxmesh
