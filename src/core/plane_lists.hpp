// What vertex_edges and triangle_cells share: a volume's z-planes packed to inside bits two at
// a time, and lists gathered plane by plane on worker threads and joined in slab order, which
// keeps them in the canonical mesh's order.
#pragma once

#include "array_sizing.hpp"
#include "bit_rows.hpp"
#include "cpu_engine.hpp"  // throw_non_finite, first_non_finite_plane, validate_volume
#include "out_of_memory.hpp"
#include "parallel.hpp"
#include "scalar_dispatch.hpp"
#include "threshold.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <span>
#include <string>
#include <vector>

namespace voxmesh::detail {

// Plane z's rows packed to `bits` (ny rows of words_per_row(nx) words); a NaN or infinite
// sample throws, naming z.
template <class T>
void pack_plane(const VolumeView& volume, const RowPacker<T>& pack, T threshold, std::size_t z, Word* bits) {
    const std::size_t nx = volume.dims[0], ny = volume.dims[1], words = words_per_row(nx);
    const T* data = static_cast<const T*>(volume.data) + nx * ny * z;
    bool bad = false;
    for (std::size_t y = 0; y < ny; ++y) bad |= pack(data + nx * y, nx, threshold, bits + y * words);
    if (bad) throw_non_finite(z);
}

// A slab's list, written in chunks: no copy as it grows, and only the pages written are
// touched. A vector per slab copied itself into fresh pages at each doubling, which took most
// of a dense surface's time (a gyroid f32 256³, 2 threads, through Python: 2.6 M edges 13 ms
// and 5.1 M cells 21 ms, in chunks 7-8 and 16 ms). Reading the volume twice, to count and then
// write in place, gave 9 and 17 ms, but sparse surfaces took 1.6x as long (sphere f32 256³).
class ChunkedList {
public:
    static constexpr std::size_t kChunk = std::size_t{1} << 15;  // entries: 256 KiB

    void push(std::uint64_t value) {
        if (used_ == kChunk) grow();
        chunks_.back()[used_++] = value;
    }
    std::size_t size() const { return chunks_.empty() ? 0 : (chunks_.size() - 1) * kChunk + used_; }
    // Copies the list to `out`; returns the end of the copy.
    std::uint64_t* copy_to(std::uint64_t* out) const {
        for (std::size_t c = 0; c < chunks_.size(); ++c)
            out = std::copy_n(chunks_[c].get(), c + 1 < chunks_.size() ? kChunk : used_, out);
        return out;
    }

private:
    void grow() {
        chunks_.push_back(std::make_unique_for_overwrite<std::uint64_t[]>(kChunk));
        used_ = 0;
    }

    std::vector<std::unique_ptr<std::uint64_t[]>> chunks_;
    std::size_t used_ = kChunk;  // the first push makes a chunk
};

// The list that visit(z, here, above, list) pushes for planes z of [0, planes), in plane order:
// `here` is plane z packed to inside bits (ny rows of words_per_row(nx) words), `above` plane
// z + 1, or null past the volume's last plane. Slab by slab on worker threads, each packing its
// planes once into two planes' room; then room(total) says where the list goes (a span of at
// least `total`, else it is not written), and each slab's part is copied to its place on a
// worker thread (the caller's memory is often fresh pages, which then fault in on every core).
// Returns the list's size; where no sample can cross iso it is empty (after the NaN check the
// packing does not make then).
template <class T, class Visit, class Room>
std::size_t list_by_slabs(const VolumeView& volume, double iso, std::size_t planes, unsigned threads,
                          const Visit& visit, const Room& room) {
    const Threshold<T> threshold = make_threshold<T>(iso);
    if (threshold.uniform != Uniform::Mixed) {
        if (const std::size_t z = first_non_finite_plane(volume); z < volume.dims[2]) throw_non_finite(z);
        return 0;
    }
    const RowPacker<T> pack = row_packer<T>();
    const std::size_t plane_words = words_per_row(volume.dims[0]) * volume.dims[1];
    // Two planes' bits per worker: dims no memory can hold (2 x 2^61 x 2 u8 fits size_t) asked
    // a vector for more than max_size(), and its std::length_error escaped as no Error.
    if (plane_words > std::vector<Word>().max_size() / 2) throw std::bad_alloc();
    // Several slabs per thread, so that a thread done early takes another.
    const unsigned slabs = slab_count(threads, planes, 4);
    std::vector<ChunkedList> found(slabs);
    {
        std::vector<std::vector<Word>> scratch(std::min(slabs, threads));
        run_slabs(slabs, threads, [&](unsigned slab, unsigned worker) {
            if (scratch[worker].empty()) scratch[worker].resize(2 * plane_words);
            Word* here = scratch[worker].data();
            Word* above = here + plane_words;
            const Share share = share_of(planes, slab, slabs);
            pack_plane(volume, pack, threshold.value, share.begin, here);
            for (std::size_t z = share.begin; z < share.end; ++z) {
                const bool has_above = z + 1 < volume.dims[2];
                if (has_above) pack_plane(volume, pack, threshold.value, z + 1, above);
                visit(z, here, has_above ? above : nullptr, found[slab]);
                std::swap(here, above);
            }
        });
    }
    std::vector<std::size_t> start(slabs + 1, 0);
    for (unsigned slab = 0; slab < slabs; ++slab) start[slab + 1] = start[slab] + found[slab].size();
    const std::size_t total = start[slabs];
    const std::span<std::uint64_t> out = room(total);
    if (total > 0 && out.size() >= total)
        run_slabs(slabs, threads, [&](unsigned slab, unsigned) { found[slab].copy_to(out.data() + start[slab]); });
    return total;
}

// A list query from the top: the volume checked, its sample type chosen, list_by_slabs over
// its z-planes less `fewer_planes` (1 for cell planes), and running out of memory an Error
// saying it was `listing`.
template <class Visit, class Room>
std::size_t list_query(const VolumeView& volume, double iso, std::size_t fewer_planes, unsigned threads,
                       const char* listing, const Visit& visit, const Room& room) {
    validate_volume(volume);
    const unsigned resolved = resolve_threads(threads);
    return out_of_memory_as_error([&] { return std::string("out of memory listing ") + listing; }, [&] {
        return dispatch_scalar(volume.type, [&](auto tag) {
            return list_by_slabs<decltype(tag)>(volume, iso, volume.dims[2] - fewer_planes, resolved, visit, room);
        });
    });
}

// list_by_slabs' room for a list in `list`, sized to it on up to `threads` threads
// (array_sizing.hpp).
inline auto room_in(std::vector<std::uint64_t>& list, unsigned threads) {
    return [&list, threads](std::size_t total) {
        ArraySizing sizing;
        sizing.add(list, total);
        sizing.run(threads);
        return std::span<std::uint64_t>(list);
    };
}

}  // namespace voxmesh::detail
