// triangle_cells: the cell each triangle of the canonical mesh lies in, from the samples alone.
// The canonical mesh writes a cell's triangles together, cells in index order, as many as the
// case table gives its case; so a pass over the cells' cases lists them without meshing.
#include "bit_rows.hpp"
#include "plane_lists.hpp"

#include <voxmesh/voxmesh.hpp>

#include <bit>
#include <cstdint>
#include <vector>

namespace voxmesh {

namespace {

using detail::Word;

// The cells of cell plane z, one entry per triangle, appended to `list`, from the inside bits
// of planes z and z + 1: the engine's corner masks (CellWord), 64 cells a word, so a word of
// cells none of which the surface crosses costs a few operations.
void plane_cells(const VolumeView& volume, std::size_t z, const Word* here, const Word* above,
                 detail::ChunkedList& list) {
    const std::size_t nx = volume.dims[0], ny = volume.dims[1];
    const std::size_t words = detail::words_per_row(nx);
    for (std::size_t y = 0; y + 1 < ny; ++y) {
        const Word *a = here + y * words, *b = a + words, *c = above + y * words, *d = c + words;
        const std::uint64_t base = (nx - 1) * (y + (ny - 1) * z);
        for (std::size_t q = 0; q < words; ++q) {
            const detail::CellWord cell(a, b, c, d, q, words);
            for (Word cells = cell.nonuniform(q, nx); cells; cells &= cells - 1) {
                const unsigned r = static_cast<unsigned>(std::countr_zero(cells));
                for (unsigned t = cell.triangles(r); t > 0; --t) list.push(base + 64 * q + r);
            }
        }
    }
}

// The triangles' count; their cells are written where room(count) says (list_by_slabs). Cell
// planes are z = 0 .. nz - 2, so plane z + 1 is always there.
template <class Room>
std::size_t cells_of_triangles(const VolumeView& volume, double iso, unsigned threads, const Room& room) {
    const auto visit = [&](std::size_t z, const Word* here, const Word* above, detail::ChunkedList& list) {
        plane_cells(volume, z, here, above, list);
    };
    return detail::list_query(volume, iso, 1, threads, "the cells of the volume's triangles", visit, room);
}

}  // namespace

std::vector<std::uint64_t> triangle_cells(const VolumeView& volume, double iso, unsigned threads) {
    std::vector<std::uint64_t> cells;
    cells_of_triangles(volume, iso, threads, detail::room_in(cells, threads));
    return cells;
}

std::size_t triangle_cells_into(const VolumeView& volume, double iso, std::span<std::uint64_t> cells, unsigned threads) {
    return cells_of_triangles(volume, iso, threads, [&](std::size_t) { return cells; });
}

}  // namespace voxmesh
