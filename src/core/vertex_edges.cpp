// vertex_edges and edge_cell_ranges: which edge each vertex of the canonical mesh lies on, and
// a per-edge statistic of the cells around it (scikit-image's `values`). A pass of its own over
// the volume, not the engines': the canonical order fixes the answer, so it needs no mesh.
#include "array_sizing.hpp"
#include "bit_rows.hpp"
#include "cpu_engine.hpp"
#include "edge_vertex.hpp"  // prefetch
#include "out_of_memory.hpp"
#include "parallel.hpp"
#include "plane_lists.hpp"
#include "scalar_dispatch.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

namespace voxmesh {

namespace {

using detail::run_slabs;

// The crossed edges owned by samples of plane z, in canonical order, appended to `list`, from
// the plane's inside bits and those of plane z + 1 (null past the last plane): the engine's edge
// masks, 64 samples a word, so a word without crossings costs a few operations.
void plane_edges(const VolumeView& volume, std::size_t z, const detail::Word* here, const detail::Word* above,
                 detail::ChunkedList& list) {
    using detail::Word;
    const std::size_t nx = volume.dims[0], ny = volume.dims[1];
    const std::size_t words = detail::words_per_row(nx);
    for (std::size_t y = 0; y < ny; ++y) {
        const Word* row = here + y * words;
        // A missing neighbour row is the row itself: nothing crosses toward it.
        const Word* up = y + 1 < ny ? row + words : row;
        const Word* next_z = above ? above + y * words : row;
        const std::uint64_t base = 3 * (nx * (y + ny * z));
        for (std::size_t q = 0; q < words; ++q) {
            const detail::EdgeMasks m = detail::edge_masks(row, up, next_z, q, words, nx);
            for (Word any = m.any(); any; any &= any - 1) {
                const unsigned r = static_cast<unsigned>(std::countr_zero(any));
                const std::uint64_t edge = base + 3 * (64 * q + r);
                if (m.x >> r & 1) list.push(edge);
                if (m.y >> r & 1) list.push(edge + 1);
                if (m.z >> r & 1) list.push(edge + 2);
            }
        }
    }
}

// The crossed edges' count; they are written where room(count) says (list_by_slabs).
template <class Room>
std::size_t crossed_edges(const VolumeView& volume, double iso, unsigned threads, const Room& room) {
    const auto visit = [&](std::size_t z, const detail::Word* here, const detail::Word* above, detail::ChunkedList& list) {
        plane_edges(volume, z, here, above, list);
    };
    return detail::list_query(volume, iso, 0, threads, "the volume's crossed edges", visit, room);
}

// The Error for edges[index], an edge the volume does not hold: its lower end not a sample, or
// its upper end past the volume.
[[noreturn]] void throw_bad_edge(const std::array<std::size_t, 3>& dims, std::size_t index, std::uint64_t edge) {
    const std::uint64_t sample = edge / 3;
    const unsigned axis = static_cast<unsigned>(edge % 3);
    const std::uint64_t count = static_cast<std::uint64_t>(dims[0]) * dims[1] * dims[2];
    const std::string which = "edge_cell_ranges: edges[" + std::to_string(index) + "] = " + std::to_string(edge);
    if (sample >= count)
        throw Error(which + " starts at sample " + std::to_string(sample) + ", past the volume's " +
                    std::to_string(count) + " samples");
    const std::uint64_t at[3] = {sample % dims[0], sample / dims[0] % dims[1], sample / (dims[0] * dims[1])};
    throw Error(which + " runs along " + std::string(1, "xyz"[axis]) + " from " + std::string(1, "xyz"[axis]) + " = " +
                std::to_string(at[axis]) + ", the volume's last sample on that axis: no edge leaves it");
}

// A range as float: double ranges of f64 samples can lie beyond float's, where converting is
// undefined; they become infinity, as IEEE rounding would make them.
float range_as_float(double range) {
    return range <= static_cast<double>(std::numeric_limits<float>::max()) ? static_cast<float>(range)
                                                                           : std::numeric_limits<float>::infinity();
}

template <class T>
void cell_ranges(const VolumeView& volume, const std::uint64_t* edges, std::size_t first, std::size_t count, double offset,
                 const std::uint8_t* cell_mask, float* out) {
    const std::size_t nx = volume.dims[0], ny = volume.dims[1];
    const std::size_t stride[3] = {1, nx, nx * ny};
    const std::size_t cells[3] = {nx - 1, ny - 1, volume.dims[2] - 1};
    const T* data = static_cast<const T*>(volume.data);
    // The row of the last edge: edges in canonical order come a few to a row, so most find their
    // y and z here instead of in three divisions.
    std::size_t row_start = 0, row_y = 0, row_z = 0;
    const std::size_t last = nx * ny * volume.dims[2] - 1;
    constexpr std::size_t kAhead = 32;
    for (std::size_t e = 0; e < count; ++e) {
        // The lines a later edge reads, asked for now: the edges of a surface reach a new
        // stretch of rows every few edges, and those rows are rarely cached.
        if (e + kAhead < count) {
            const std::size_t ahead = static_cast<std::size_t>(edges[e + kAhead] / 3);
            for (const std::size_t dz : {std::size_t{0}, stride[2], 2 * stride[2]})
                for (const std::size_t dy : {std::size_t{0}, nx, 2 * nx})
                    detail::prefetch(data + std::min(last, std::max(ahead + dz + dy, stride[2] + nx) - stride[2] - nx));
        }
        if (edges[e] / 3 > last) throw_bad_edge(volume.dims, first + e, edges[e]);
        const std::size_t sample = static_cast<std::size_t>(edges[e] / 3);
        const unsigned axis = static_cast<unsigned>(edges[e] % 3), p = (axis + 1) % 3, q = (axis + 2) % 3;
        if (sample - row_start >= nx) {  // unsigned: also when the sample is before the row
            row_y = sample / nx % ny;
            row_z = sample / (nx * ny);
            row_start = nx * (row_y + ny * row_z);
        }
        const std::size_t at[3] = {sample - row_start, row_y, row_z};
        if (at[axis] >= cells[axis]) throw_bad_edge(volume.dims, first + e, edges[e]);
        // The 3 x 3 sample pairs along the edge around it, as max and min of each pair; a cell
        // around the edge is a 2 x 2 block of them (i, j = -1 or 0 its offset across p and q).
        T high[3][3]{}, low[3][3]{};
        for (int i = -1; i <= 1; ++i)
            for (int j = -1; j <= 1; ++j) {
                const bool held = !((i < 0 && at[p] == 0) || (i > 0 && at[p] + 1 > cells[p]) ||
                                    (j < 0 && at[q] == 0) || (j > 0 && at[q] + 1 > cells[q]));
                if (!held) continue;
                const std::size_t s = sample + i * static_cast<std::ptrdiff_t>(stride[p]) +
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
                const float range = range_as_float((static_cast<double>(top) - offset) - (static_cast<double>(bottom) - offset));
                best = std::max(best, range);
            }
        out[e] = best;
    }
}

}  // namespace

std::vector<std::uint64_t> vertex_edges(const VolumeView& volume, double iso, unsigned threads) {
    std::vector<std::uint64_t> edges;
    crossed_edges(volume, iso, threads, detail::room_in(edges, threads));
    return edges;
}

std::size_t vertex_edges_into(const VolumeView& volume, double iso, std::span<std::uint64_t> edges, unsigned threads) {
    return crossed_edges(volume, iso, threads, [&](std::size_t) { return edges; });
}

void edge_cell_ranges_into(const VolumeView& volume, std::span<const std::uint64_t> edges, std::span<float> ranges,
                           double offset, const std::uint8_t* cell_mask, unsigned threads) {
    detail::validate_volume(volume);
    if (!std::isfinite(offset)) throw Error("edge_cell_ranges: offset must be finite");
    if (ranges.size() != edges.size())
        throw Error("edge_cell_ranges: room for " + std::to_string(ranges.size()) + " ranges, for " +
                    std::to_string(edges.size()) + " edges");
    const unsigned resolved = detail::resolve_threads(threads);
    // Pieces of 64 Ki edges: a few per thread on a large mesh, one on a small one. An edge the
    // volume does not hold throws from its piece; run_slabs passes on the lowest piece's, so the
    // first such edge is named on any thread count.
    const std::size_t piece = std::size_t{1} << 16;
    // Rounded up without adding first: a count near SIZE_MAX wrapped to 0 pieces, and the call
    // returned having done nothing.
    const std::size_t pieces = edges.size() / piece + (edges.size() % piece != 0);
    if (pieces > std::numeric_limits<unsigned>::max()) throw Error("edge_cell_ranges: too many edges");
    run_slabs(static_cast<unsigned>(pieces), resolved, [&](unsigned w, unsigned) {
        const std::size_t begin = std::size_t{w} * piece, end = std::min(edges.size(), begin + piece);
        detail::dispatch_scalar(volume.type, [&](auto tag) {
            cell_ranges<decltype(tag)>(volume, edges.data() + begin, begin, end - begin, offset, cell_mask, ranges.data() + begin);
        });
    });
}

std::vector<float> edge_cell_ranges(const VolumeView& volume, std::span<const std::uint64_t> edges, double offset,
                                    const std::uint8_t* cell_mask, unsigned threads) {
    std::vector<float> ranges;
    detail::out_of_memory_as_error(
        [&] { return "out of memory for the ranges of " + std::to_string(edges.size()) + " edges"; }, [&] {
            detail::ArraySizing sizing;
            sizing.add(ranges, edges.size());
            sizing.run(threads);
        });
    edge_cell_ranges_into(volume, edges, ranges, offset, cell_mask, threads);
    return ranges;
}

}  // namespace voxmesh
