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

// The cells of cell planes [z0, z1), one entry per triangle, appended to `list`.
// Planes z and z + 1 are packed to inside bits 64 samples a word, so a word of 64 cells none of
// which the surface crosses costs a few operations (CellWord: the engine's own corner masks).
template <class T>
void slab_cells(const VolumeView& volume, T threshold, std::size_t z0, std::size_t z1, Word* planes,
                detail::ChunkedList& list) {
    const std::size_t nx = volume.dims[0], ny = volume.dims[1];
    const std::size_t words = detail::words_per_row(nx), plane_words = words * ny;
    const detail::RowPacker<T> pack = detail::row_packer<T>();
    Word* cur = planes;
    Word* next = planes + plane_words;
    detail::pack_plane(volume, pack, threshold, z0, cur);
    for (std::size_t z = z0; z < z1; ++z) {
        detail::pack_plane(volume, pack, threshold, z + 1, next);  // z + 1 < nz: z is a cell plane
        for (std::size_t y = 0; y + 1 < ny; ++y) {
            const Word *a = cur + y * words, *b = a + words, *c = next + y * words, *d = c + words;
            const std::uint64_t base = (nx - 1) * (y + (ny - 1) * z);
            for (std::size_t q = 0; q < words; ++q) {
                const detail::CellWord cell(a, b, c, d, q, words);
                const Word cells = cell.nonuniform(q, nx);
                for (Word rest = cells; rest; rest &= rest - 1) {
                    const unsigned r = static_cast<unsigned>(std::countr_zero(rest));
                    for (unsigned t = cell.triangles(r); t > 0; --t) list.push(base + 64 * q + r);
                }
            }
        }
        std::swap(cur, next);
    }
}

// The triangles' count; their cells are written where room(count) says (list_by_slabs).
template <class Room>
std::size_t cells_of_triangles(const VolumeView& volume, double iso, unsigned threads, const Room& room) {
    const auto fill = [&](auto threshold, std::size_t z0, std::size_t z1, Word* planes, detail::ChunkedList& list) {
        slab_cells(volume, threshold, z0, z1, planes, list);
    };
    return detail::list_query(volume, iso, 1, threads, "the cells of the volume's triangles", fill, room);
}

}  // namespace

std::vector<std::uint64_t> triangle_cells(const VolumeView& volume, double iso, unsigned threads) {
    std::vector<std::uint64_t> cells;
    cells_of_triangles(volume, iso, threads, detail::room_in(cells));
    return cells;
}

std::size_t triangle_cells_into(const VolumeView& volume, double iso, std::span<std::uint64_t> cells, unsigned threads) {
    return cells_of_triangles(volume, iso, threads, [&](std::size_t) { return cells; });
}

}  // namespace voxmesh
