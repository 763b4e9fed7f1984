#include "cpu_engine.hpp"

#include "array_sizing.hpp"
#include "bit_rows.hpp"
#include "case_tables.hpp"
#include "edge_vertex.hpp"
#include "float_extent.hpp"
#include "huge_pages.hpp"
#include "normal_batch.hpp"
#include "parallel.hpp"
#include "scalar_dispatch.hpp"
#include "threshold.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <type_traits>

namespace voxmesh::detail {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The first z-plane in `range` with a NaN or infinite sample; range.end when there is none.
template <class T>
std::size_t first_non_finite(const VolumeView& volume, ZRange range) {
    if constexpr (std::is_floating_point_v<T>) {
        const std::size_t plane = volume.dims[0] * volume.dims[1];
        const T* data = static_cast<const T*>(volume.data);
        for (std::size_t z = range.begin; z < range.end; ++z) {
            unsigned bad = 0;
            for (std::size_t i = 0; i < plane; ++i) bad |= !(std::fabs(data[z * plane + i]) <= std::numeric_limits<T>::max());
            if (bad) return z;
        }
    }
    return range.end;
}

// The classify pass finds non-finite samples; when iso is beyond the type's range it does not
// run, so scan for them here.
template <class T>
void check_finite(const VolumeView& volume, ZRange range) {
    if (const std::size_t z = first_non_finite<T>(volume, range); z < range.end) throw_non_finite(z);
}

// A plane of packed inside bits: ny rows of words_per_row(nx) words. A row is where its bits
// already are (classify's store, or one shared all-inside / all-outside row), or packed here.
struct BitPlane {
    std::vector<const Word*> rows;
    std::vector<Word> packed;  // ny rows' room, used for the rows packed from the volume
    const Word* row(std::size_t j) const { return rows[j]; }
};

template <class T>
class PlaneBits {
public:
    PlaneBits(const VolumeView& volume, T threshold)
        : data_(static_cast<const T*>(volume.data)),
          nx_(volume.dims[0]),
          ny_(volume.dims[1]),
          stride_(words_per_row(volume.dims[0])),
          threshold_(threshold),
          pack_(row_packer<T>()),
          uniform_{std::vector<Word>(stride_, kNoBits), std::vector<Word>(stride_)} {
        for (std::size_t q = 0; q < stride_; ++q) uniform_[1][q] = bits_below(q, nx_);
        rows_ = ny_ * volume.dims[2];
        ahead_rows_ = std::max<std::size_t>(1, kPackAheadBytes / (nx_ * sizeof(T)));
    }

    std::size_t stride() const { return stride_; }
    void resize(BitPlane& plane) const {
        plane.rows.assign(ny_, nullptr);
        plane.packed.assign(ny_ * stride_, 0);
    }

    // Plane z; with `rows` (classify results), rows without crossings are uniform and point
    // at a shared uniform row, and rows with crossings point into `stored` (classify's bits)
    // when there is one. Everything else is packed from the volume. Returns true when a
    // packed sample is NaN.
    bool fill(BitPlane& plane, std::size_t z, const RowInfo* rows, const Word* stored) const {
        bool nan = false;
        for (std::size_t j = 0; j < ny_; ++j) {
            if (rows && rows[j].empty()) {
                plane.rows[j] = uniform_[rows[j].uniform_bit()].data();
            } else if (rows && stored) {
                plane.rows[j] = stored + rows[j].bits_at;
            } else {
                prefetch_ahead(z, j);
                nan |= pack(plane, z, j);
            }
        }
        return nan;
    }

    // Asks for the lines of the volume's row kPackAheadBytes after row j of plane z, which
    // a pack a few rows from now reads. The hardware prefetcher alone left the packs' loads
    // waiting on memory (in-process A/B, 2 threads, sphere u8 512³: in classify, classify
    // 5.2 → 4.3 ms, total -5 %, 16 and 32 KiB ahead no better; in generate's re-pack of 8-bit
    // rows, generate -6 to -8 %; gyroid ±0 both).
    void prefetch_ahead(std::size_t z, std::size_t j) const {
        const std::size_t row = z * ny_ + j + ahead_rows_;
        if (row >= rows_) return;
        const char* line = reinterpret_cast<const char*>(data_ + row * nx_);
        for (std::size_t b = 0; b < nx_ * sizeof(T); b += 64) prefetch(line + b);
    }

    // Packs row j of plane z from the volume; true when a sample is NaN.
    bool pack(BitPlane& plane, std::size_t z, std::size_t j) const {
        Word* out = plane.packed.data() + j * stride_;
        plane.rows[j] = out;
        return pack_(data_ + (z * ny_ + j) * nx_, nx_, threshold_, out);
    }

private:
    static constexpr std::size_t kPackAheadBytes = 8192;

    const T* data_;
    std::size_t nx_, ny_, stride_;
    std::size_t rows_ = 0, ahead_rows_ = 0;
    T threshold_;
    RowPacker<T> pack_;
    std::vector<Word> uniform_[2];  // a row of all-outside and of all-inside samples
};

// ---------------------------------------------------------------- classify

// Counts the crossed edges a row owns and where the first and last lie; returns the set of
// words with a crossing (word_bit).
[[gnu::always_inline]] inline Word classify_row_body(const Word* row, const Word* next_y, const Word* next_z,
                                                    std::size_t words, std::size_t nx, RowInfo& info) {
    std::uint32_t count = 0;
    std::size_t first = kEmptyRow, last = row[0] & 1;  // an empty row keeps its inside bit in `last`
    Word busy = 0;
    for (std::size_t q = 0; q < words; ++q) {
        const EdgeMasks m = edge_masks(row, next_y, next_z, q, words, nx);
        const Word any = m.any();
        if (!any) continue;  // most words: nothing crosses
        count += static_cast<std::uint32_t>(__builtin_popcountll(m.x) + __builtin_popcountll(m.y) +
                                            __builtin_popcountll(m.z));
        if (first == kEmptyRow) first = 64 * q + static_cast<std::size_t>(std::countr_zero(any));
        last = 64 * q + 63 - static_cast<std::size_t>(std::countl_zero(any));
        busy |= word_bit(q);
    }
    info.vertices = count;
    info.first = static_cast<std::uint32_t>(first);
    info.last = static_cast<std::uint32_t>(last);
    info.triangles = 0;  // counted after the next row, where its cell row has any
    return busy;
}

// Words [begin, end) of a row: where the surface is (the span of x that rows of the same
// cell row cross), like Flying Edges' trimmed rows; outside it every word is uniform.
struct WordSpan {
    std::size_t begin = 0, end = 0;
};

inline WordSpan row_words(const RowInfo& row) { return {row.first / 64, std::size_t{row.last} / 64 + 1}; }

// A non-uniform cell x has a crossed edge owned by sample x or x+1 of rows a = (y, z) or
// b = (y+1, z): its edges in rows (y, z+1) and (y+1, z+1) cross only where a z-edge or an
// edge of a or b does. So a cell row whose rows a and b have no crossing has no triangles,
// its non-uniform cells lie in [first - 1, last] of a and b's crossings, and in words that
// hold a crossing of a or b or are followed by one.
inline bool cell_row_active(const RowInfo& a, const RowInfo& b) { return !a.empty() || !b.empty(); }

inline WordSpan cell_row_words(const RowInfo& a, const RowInfo& b) {
    const std::size_t first = std::min(a.first, b.first);
    const std::size_t last = std::max(a.empty() ? 0 : a.last, b.empty() ? 0 : b.last);
    return {(first > 0 ? first - 1 : 0) / 64, last / 64 + 1};
}

// Counts the triangles of cell row j (rows j and j + 1 of planes `here` and `up`) into
// info[j].triangles.
[[gnu::always_inline]] inline void count_cell_row_body(const BitPlane& here, const BitPlane& up, RowInfo* info,
                                                      const Word* busy, std::size_t j, std::size_t words,
                                                      std::size_t nx) {
    if (!cell_row_active(info[j], info[j + 1])) return;
    const Word *ra = here.row(j), *rb = here.row(j + 1), *rc = up.row(j), *rd = up.row(j + 1);
    std::uint32_t count = 0;
    const WordSpan span = cell_row_words(info[j], info[j + 1]);
    const Word crossed = busy[j] | busy[j + 1];
    const Word nonuniform_words = crossed | crossed >> 1;
    for (std::size_t q = span.begin; q < span.end; ++q) {
        if (!(nonuniform_words & word_bit(q))) continue;
        const CellWord cell(ra, rb, rc, rd, q, words);
        count += cell.triangle_count(cell.nonuniform(q, nx));
    }
    info[j].triangles = count;
}

template <class T>
[[gnu::always_inline]] inline void classify_planes_body(const CpuChunkPlan& plan, const VolumeView& volume,
                                                       T threshold, std::size_t a, std::size_t b, RowInfo* rows,
                                                       PlaneCounts* plane_counts) {
    const std::size_t nx = volume.dims[0], ny = volume.dims[1], nz = volume.dims[2];
    PlaneBits<T> bits(volume, threshold);
    const std::size_t words = bits.stride();
    BitPlane here, up;
    bits.resize(here);
    bits.resize(up);
    if (bits.fill(here, a, nullptr, nullptr)) throw_non_finite(a);
    std::vector<Word> busy(ny);  // per row of plane k, its words with a crossing
    for (std::size_t k = a; k < b; ++k) {
        const bool has_up = k + 1 < nz;
        const bool count_cells = has_up && k < plan.range.end;
        const BitPlane& next_z = has_up ? up : here;
        RowInfo* info = rows + (k - plan.range.begin) * ny;
        bool nan = false;
        // Row by row: pack row j of plane k + 1, classify row j of plane k, count cell row
        // j - 1. The volume streams in while the bits are worked on, where packing the whole
        // plane first left the memory idle during the counting.
        for (std::size_t j = 0; j < ny; ++j) {
            if (has_up) {
                bits.prefetch_ahead(k + 1, j);
                nan |= bits.pack(up, k + 1, j);
            }
            busy[j] = classify_row_body(here.row(j), here.row(j + 1 < ny ? j + 1 : j), next_z.row(j), words, nx, info[j]);
            if (count_cells && j > 0) count_cell_row_body(here, up, info, busy.data(), j - 1, words, nx);
        }
        if (nan) throw_non_finite(k + 1);
        if (plan.keeps_bits()) {
            Word* store = plan.kept_bits(k - plan.range.begin);
            std::uint32_t at = 0;
            for (std::size_t j = 0; j < ny; ++j)
                if (!info[j].empty()) {
                    info[j].bits_at = at;
                    std::memcpy(store + at, here.row(j), words * sizeof(Word));
                    at += static_cast<std::uint32_t>(words);
                }
        }
        // The plane's sums while its rows are in cache. Cost: a plane's bits plus its vertices
        // and triangles, and a pass over the words of each row with crossings.
        PlaneCounts& sums = plane_counts[k - plan.range.begin];
        sums.cost = static_cast<double>(nx * ny) / 16;
        for (std::size_t j = 0; j < ny; ++j) {
            sums.vertices += info[j].vertices;
            sums.triangles += info[j].triangles;
            sums.cost += 24.0 * info[j].vertices + 4.0 * info[j].triangles + (info[j].empty() ? 0 : nx / 4.0);
            if (!info[j].empty()) {
                const WordSpan row = row_words(info[j]);
                sums.widest_words = std::max(sums.widest_words, row.end - row.begin);
            }
            if (j + 1 < ny && cell_row_active(info[j], info[j + 1])) {
                const WordSpan cells = cell_row_words(info[j], info[j + 1]);
                sums.widest_words = std::max(sums.widest_words, cells.end - cells.begin);
            }
        }
        std::swap(here, up);
    }
}

// Compiled twice, here with POPCNT and inline in classify_planes without: the edge and
// triangle counts are popcounts, which without POPCNT are library calls that cost more than
// the rest of the pass.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
template <class T>
__attribute__((target("popcnt"))) void classify_planes_popcnt(const CpuChunkPlan& plan, const VolumeView& volume,
                                                              T threshold, std::size_t a, std::size_t b, RowInfo* rows,
                                                              PlaneCounts* plane_counts) {
    classify_planes_body<T>(plan, volume, threshold, a, b, rows, plane_counts);
}
#endif

template <class T>
void classify_planes(const CpuChunkPlan& plan, const VolumeView& volume, T threshold, std::size_t a, std::size_t b,
                     RowInfo* rows, PlaneCounts* plane_counts) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (cpu_has_popcnt()) return classify_planes_popcnt<T>(plan, volume, threshold, a, b, rows, plane_counts);
#endif
    classify_planes_body<T>(plan, volume, threshold, a, b, rows, plane_counts);
}

// Slab i's share of a pass's work shrinks geometrically, the last slab's an eighth of the
// first's, so the slabs taken last, whose ends the other threads wait for, are small, and
// the slab count (each slab's fixed cost) stays. With equal slabs a thread waited 1.4-6.6 %
// of a pass for the other at its end (2 threads). In-process A/B, 2 threads, extract_into,
// total: gyroid f32 512³ 0.92-0.99 over five runs, sphere f32 256³ 0.93-0.98 over five, ct
// i16 256³ 0.970, sphere u8 256³ 0.989, sphere f32 512³ 0.990, sphere u8 512³ 0.995-1.000,
// gyroid u8 256³ and 512³ 0.999; a last share of 1/4 or 1/16 measured like 1/8.
constexpr double kLastSlabShare = 1.0 / 8;

// Contiguous split of [0, n) into `parts` ranges whose sums of cost shrink as above.
std::vector<std::size_t> shrinking_split(const std::vector<double>& cost, unsigned parts) {
    double total = 0;
    for (double c : cost) total += c;
    const double ratio = parts > 1 ? std::pow(kLastSlabShare, 1.0 / (parts - 1)) : 1.0;
    double shares = 0;  // sum of ratio^i, i < parts
    for (unsigned p = 0; p < parts; ++p) shares += std::pow(ratio, p);
    std::vector<std::size_t> cuts{0};
    double acc = 0, done = 0;
    std::size_t i = 0;
    for (unsigned p = 1; p < parts; ++p) {
        done += std::pow(ratio, p - 1);
        const double target = total * done / shares;
        while (i < cost.size() && acc + cost[i] / 2 < target) acc += cost[i++];
        cuts.push_back(std::max(i, cuts.back()));
    }
    cuts.push_back(cost.size());
    return cuts;
}

// ---------------------------------------------------------------- generate

// Per sample of two planes (k and k+1; they take turns as plane k), the vertex id of each
// crossed edge it owns, counted from its row's first vertex: 16 bits wherever a row has at
// most 65536 edges (nx <= kMaxNxFor16BitIds), which halves the table and its cache lines;
// 32 bits above. A sample's six slots (3 per plane: x, y, z) sit side by side, at
// kSampleSlots * (x + nx * y) + 3 * half + axis: the line that takes a sample's ids of plane
// k + 1 holds its ids of plane k, which the cells below read next, and a cell reads two rows
// of lines, not four (-7 % generate on 2 threads, sphere f32 512³; even on u8 and gyroid).
// Slots of edges that do not cross are never read, so nothing is written here. A cell edge's
// id is at a fixed offset from its cell's sample slot (`slots(lower)[e]`, for plane k in the
// lower or upper half), plus the base of the row it is in (`rows_of()[e]`: 0 and 1 for rows
// y and y + 1 of plane k, 2 and 3 of plane k + 1). In huge pages where large: a cell row reads
// ids from rows 6 KiB apart at 512², a TLB miss each with 4 KiB pages. From the scratch pool
// (scratch.hpp), not fresh pages every call.
constexpr std::size_t kMaxNxFor16BitIds = 21845;  // 3 * nx - 1 <= 65535

template <class Id>
class EdgeIds {
public:
    static constexpr std::size_t kSampleSlots = 6;

    EdgeIds(std::size_t nx, std::size_t ny)
        : row_(kSampleSlots * nx),
          storage_(acquire_scratch(row_ * ny * sizeof(Id), Pages::Huge)) {
        // Never read before written, but zeroed all the same: that brings the table's lines
        // into the cache before the id writes, which otherwise each wait on memory (A/B
        // generate -1 to -3 %, sphere u8 256³ and 512³, 2 threads).
        std::memset(storage_.get(), 0, row_ * ny * sizeof(Id));
        for (unsigned e = 0; e < 12; ++e) {
            const CellEdge& edge = kCellEdge[e];
            row_of_[e] = edge.dy + 2u * edge.dz;
            for (unsigned half = 0; half < 2; ++half) {
                const std::ptrdiff_t z = edge.dz ? (half == 0 ? 3 : -3) : 0;
                slot_[half][e] = z + static_cast<std::ptrdiff_t>(row_ * edge.dy + kSampleSlots * edge.dx + edge.axis);
            }
        }
    }

    // Slot 0 of sample (0, j) of a half; sample x's slots follow at kSampleSlots * x.
    Id* row(unsigned half, std::size_t j) { return static_cast<Id*>(storage_.get()) + j * row_ + 3 * half; }
    const std::ptrdiff_t* slots(unsigned half) const { return slot_[half]; }
    const unsigned* rows_of() const { return row_of_; }

private:
    std::size_t row_;                // slots per row
    std::shared_ptr<void> storage_;  // both planes' ids
    std::ptrdiff_t slot_[2][12];
    unsigned row_of_[12];
};

// GCC on x86-64 builds a second copy of the generator for AVX2/BMI (Generator::run_avx2).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define VOXMESH_GENERATOR_AVX2 1
#endif

template <class T, class Id>
class Generator {
public:
    Generator(const CpuChunkPlan& plan, const VolumeView& volume, const Options& options, const MeshOut& out,
              T threshold)
        : plan_(plan),
          options_(options),
          out_(out),
          bits_(volume, threshold),
          vertex_(volume, options.iso, options.inside_below),
          nx_(volume.dims[0]),
          ny_(volume.dims[1]),
          nz_(volume.dims[2]),
          words_(bits_.stride()),
          ids_(nx_, ny_) {
        for (auto& b : planes_) bits_.resize(b);
    }

    // Meshes planes [a, b) of the range: vertices of sample planes a..b-1 and triangles of
    // cell planes a..b-1, reading ids of plane b as well.
    void run(std::size_t a, std::size_t b) {
#ifdef VOXMESH_GENERATOR_AVX2
        if (cpu_has_avx2_bmi2()) return run_avx2(a, b);
#endif
        run_body(a, b);
    }

private:
#ifdef VOXMESH_GENERATOR_AVX2
    // The same code with everything it calls inlined and compiled for AVX2 and BMI (VEX
    // three-operand arithmetic, tzcnt/blsr, shlx/shrx: -13 % instructions). No FMA: fused
    // multiply-adds would round differently, and every engine must give the same bits.
    [[gnu::target("avx2,bmi,bmi2,popcnt"), gnu::flatten]] void run_avx2(std::size_t a, std::size_t b) {
        run_body(a, b);
    }
#endif

    void run_body(std::size_t a, std::size_t b) {
        fill_bits(a, 0);
        if (a + 1 < nz_) fill_bits(a + 1, 1);
        if (a + 2 < nz_) fill_bits(a + 2, 2);
        build_edges(a, planes_[0], a + 1 < nz_ ? &planes_[1] : nullptr, lower_, true);
        for (std::size_t k = a; k < b; ++k) {
            if (k + 1 < nz_) {
                build_edges(k + 1, planes_[1], k + 2 < nz_ ? &planes_[2] : nullptr, 1 - lower_, k + 1 < b);
                emit_triangles(k);
            }
            lower_ = 1 - lower_;
            std::rotate(planes_, planes_ + 1, planes_ + 3);
            if (k + 3 < nz_ && k + 1 < b) fill_bits(k + 3, 2);
        }
    }

    const RowInfo* meta_rows(std::size_t z) const {
        const std::size_t p = z - plan_.range.begin;
        return p < plan_.meta_planes ? plan_.rows.data() + p * ny_ : nullptr;
    }

    void fill_bits(std::size_t z, int slot) {
        const std::size_t p = z - plan_.range.begin;
        const bool kept = plan_.keeps_bits() && p < plan_.meta_planes;
        bits_.fill(planes_[slot], z, meta_rows(z), kept ? plan_.kept_bits(p) : nullptr);
    }

    void build_edges(std::size_t z, const BitPlane& plane, const BitPlane* up, unsigned half, bool write_vertices) {
        const RowInfo* rows = meta_rows(z);
        // Rows in order: each row's first vertex follows the previous row's last.
        std::uint32_t row_first = static_cast<std::uint32_t>(plan_.planes[z - plan_.range.begin].first_vertex);
        NormalBatch* normals = write_vertices && out_.normals ? &normals_ : nullptr;
        if (normals) normals->start(out_.normals + 3 * static_cast<std::size_t>(row_first));
        for (std::size_t j = 0; j < ny_; ++j) {
            const std::uint32_t base = row_first;
            row_first += rows[j].vertices;
            if (rows[j].empty()) continue;
            const Word* row = plane.row(j);
            const Word* next_y = plane.row(j + 1 < ny_ ? j + 1 : j);  // the row itself: no edge
            const Word* next_z = (up ? *up : plane).row(j);
            Id* id = ids_.row(half, j);
            std::uint32_t next_id = base;
            const WordSpan span = row_words(rows[j]);
            const typename EdgeVertex<T>::Row vertex_row = vertex_.row(j, z);
            for (std::size_t q = span.begin; q < span.end; ++q) {
                const EdgeMasks m = edge_masks(row, next_y, next_z, q, words_, nx_);
                for (Word any = m.any(); any; any &= any - 1) {
                    const unsigned r = static_cast<unsigned>(std::countr_zero(any));
                    const std::size_t i = 64 * q + r;
                    const unsigned c = static_cast<unsigned>((m.x >> r & 1) | (m.y >> r & 1) << 1 | (m.z >> r & 1) << 2);
                    if (write_vertices) {
                        const std::size_t at = 3 * static_cast<std::size_t>(next_id);
                        vertex_.sample(vertex_row, i, c, out_.positions + at, normals);
                    }
                    // All three slots, without branches: a slot whose edge does not cross is never read.
                    for (unsigned axis = 0; axis < 3; ++axis) {
                        id[EdgeIds<Id>::kSampleSlots * i + axis] = static_cast<Id>(next_id - base);
                        next_id += c >> axis & 1;
                    }
                }
            }
            if (kRepacked && next_id != row_first) [[unlikely]] throw_volume_changed(z);
        }
        if (normals) normals->flush();
    }

    void emit_triangles(std::size_t k) {
        const RowInfo* rows = meta_rows(k);
        const RowInfo* upper_rows = meta_rows(k + 1);
        const bool flip = options_.inside_below;
        const std::ptrdiff_t* slot = ids_.slots(lower_);
        const unsigned* row_of = ids_.rows_of();
        // The first vertex (global id) of rows j of planes k and k + 1, and the first triangle
        // of cell row j, advanced row by row from the planes' scan results.
        const PlaneCounts& lower = plan_.planes[k - plan_.range.begin];
        const PlaneCounts& upper = plan_.planes[k + 1 - plan_.range.begin];
        std::uint32_t lower_first = out_.vertex_base + static_cast<std::uint32_t>(lower.first_vertex);
        std::uint32_t upper_first = out_.vertex_base + static_cast<std::uint32_t>(upper.first_vertex);
        std::uint32_t* out = out_.indices + 3 * lower.first_triangle;
        for (std::size_t j = 0; j + 1 < ny_; ++j) {
            const std::uint32_t row_base[4] = {lower_first, lower_first + rows[j].vertices, upper_first,
                                               upper_first + upper_rows[j].vertices};
            lower_first = row_base[1];
            upper_first = row_base[3];
            if (!cell_row_active(rows[j], rows[j + 1])) continue;
            const Word *a = planes_[0].row(j), *b = planes_[0].row(j + 1),
                       *c = planes_[1].row(j), *d = planes_[1].row(j + 1);
            const Id* row_ids = ids_.row(lower_, j);
            // First the row's cell cases, asking for the lines of each cell's corner ids (one
            // per row of ids; written a plane ago, they are mostly in L3 by now); then its
            // triangles. Reading the ids right after the case took the lookups' whole latency
            // chain (case, table entry, edge offset, id) after every mispredicted triangle
            // count (-3 to -8 % generate time, sphere 512³).
            std::uint64_t* cases = cell_cases_.data();
            std::size_t n = 0;
            const WordSpan span = cell_row_words(rows[j], rows[j + 1]);
            for (std::size_t q = span.begin; q < span.end; ++q) {
                const CellWord cell(a, b, c, d, q, words_);
                for (Word cells = cell.nonuniform(q, nx_); cells; cells &= cells - 1) {
                    const unsigned r = static_cast<unsigned>(std::countr_zero(cells));
                    const std::size_t i = 64 * q + r;
                    for (unsigned e : kIdRowEdges) prefetch(row_ids + EdgeIds<Id>::kSampleSlots * i + slot[e]);
                    cases[n++] = static_cast<std::uint64_t>(i) << 8 | cell.cell_case(r);
                }
            }
            [[maybe_unused]] const std::uint32_t* row_start = out;
            for (std::size_t m = 0; m < n; ++m) {
                const CaseEntry& entry = kCaseTable[cases[m] & 255];
                const Id* cell_ids = row_ids + EdgeIds<Id>::kSampleSlots * static_cast<std::size_t>(cases[m] >> 8);
                for (unsigned t = 0; t < entry.count; ++t) {
                    std::uint32_t v[3];
                    for (unsigned c = 0; c < 3; ++c) {
                        const auto e = static_cast<unsigned>(entry.edges[3 * t + c]);
                        v[c] = row_base[row_of[e]] + cell_ids[slot[e]];
                    }
                    out[0] = v[0];
                    out[1] = flip ? v[2] : v[1];
                    out[2] = flip ? v[1] : v[2];
                    out += 3;
                }
            }
            if (kRepacked && static_cast<std::size_t>(out - row_start) != 3 * std::size_t{rows[j].triangles}) [[unlikely]]
                throw_volume_changed(k);
        }
    }

    // 8-bit rows with crossings are packed again from the volume (classify keeps no bits for
    // them): each row's vertices and cell row's triangles are checked against classify's counts
    // once written, in case the volume changed in between (throw_volume_changed). A row that
    // has more writes into the next rows' room, or into the spare row allocate_output leaves.
    // Checks per vertex or per word cost 3-10 % of generate (gyroid u8 256³, in-process A/B).
    static constexpr bool kRepacked = sizeof(T) == 1;

    // One x-edge of each row of id lines a cell reads (j and j + 1).
    static constexpr unsigned kIdRowEdges[2] = {0, 2};

    const CpuChunkPlan& plan_;
    const Options& options_;
    MeshOut out_;
    PlaneBits<T> bits_;
    EdgeVertex<T> vertex_;
    NormalBatch normals_;
    std::size_t nx_, ny_, nz_, words_;
    BitPlane planes_[3];
    EdgeIds<Id> ids_;
    std::vector<std::uint64_t> cell_cases_ = std::vector<std::uint64_t>(nx_);  // x << 8 | case, per cell row
    unsigned lower_ = 0;  // the half of ids_ that holds plane k
};

// Slabs per thread, pulled in order: a thread that finishes early (the cost model is an
// estimate, and on a VM a core can stall) takes the next slab instead of waiting for the
// slowest one. Each slab packs a plane or two again at its ends and builds the ids of the
// next slab's first plane, so not too many: 8 and 16 per thread cost 2 threads 3-5 % of the
// total over 4 and 6 (in-process A/B, sphere and gyroid, 256³ and 512³), and 2 and 3
// left gyroid's cores waiting on each other (+5 %). Since the slabs shrink (shrinking_split),
// 4 generate slabs per thread instead of 6: total 0.979-1.009 over nine A/B runs (2 threads,
// extract_into; generate 0.976-1.002), 3 per thread up to +2.2 % on gyroid u8 512³, and 3
// classify slabs per thread no better than 4.
constexpr unsigned kClassifySlabsPerThread = 4, kGenerateSlabsPerThread = 4;

}  // namespace

// The mesh's arrays sized for the counts, in parallel (array_sizing.hpp: a new Mesh's fresh
// pages are most of what that costs; a 10 M-triangle mesh, 230 MB, took 70 ms into a new
// Mesh and 27 ms into a reused one on the H200 machine's 16 cores, with one thread per array).
double allocate_output(Mesh& mesh, std::uint64_t vertices, std::uint64_t triangles, bool normals, unsigned threads,
                       std::size_t row_samples) {
    const auto t0 = Clock::now();
    vertices += 3 * std::uint64_t{row_samples};
    triangles += 5 * std::uint64_t{row_samples};
    ArraySizing sizing;
    sizing.add(mesh.indices, static_cast<std::size_t>(3 * triangles));
    sizing.add(mesh.positions, static_cast<std::size_t>(3 * vertices));
    if (normals) sizing.add(mesh.normals, static_cast<std::size_t>(3 * vertices));
    else mesh.normals.clear();  // a reused mesh may have had normals
    sizing.run(std::max(threads, 1u));
    return sizing.replaced() ? seconds_since(t0) : 0;
}

std::size_t spare_row_samples(const CpuChunkPlan& plan, const VolumeView& volume) {
    if (scalar_size(volume.type) != 1 || plan.uniform || (plan.vertices == 0 && plan.triangles == 0)) return 0;
    return std::min(volume.dims[0], 64 * plan.widest_words);
}

void trim_output(Mesh& mesh, std::uint64_t vertices, std::uint64_t triangles) {
    mesh.indices.resize(static_cast<std::size_t>(3 * triangles));
    mesh.positions.resize(static_cast<std::size_t>(3 * vertices));
    if (!mesh.normals.empty()) mesh.normals.resize(static_cast<std::size_t>(3 * vertices));
}

// Infinite samples are refused with NaN: t = (iso - v0) / (v1 - v0) is undefined for them.
NonFiniteSamples::NonFiniteSamples(std::size_t plane)
    : Error("volume has NaN or infinite samples (first seen in z-plane " + std::to_string(plane) +
            "); replace them with finite values before meshing"),
      plane(plane) {}

void throw_non_finite(std::size_t plane) { throw NonFiniteSamples(plane); }

void throw_volume_changed(std::size_t plane) {
    throw Error("the volume's samples changed while it was being meshed (z-plane " + std::to_string(plane) +
                " read twice gave other crossings); keep the volume unchanged until extract returns");
}

std::size_t first_non_finite_plane(const VolumeView& volume) {
    return dispatch_scalar(volume.type,
                           [&](auto tag) { return first_non_finite<decltype(tag)>(volume, ZRange{0, volume.dims[2]}); });
}

void throw_too_many_vertices() {
    throw Error("the mesh would have more than 2^32-1 vertices; 32-bit indices cannot address it "
                "(mesh a sub-volume or a coarser volume)");
}

void check_samples_readable(const VolumeView& volume) {
    if (!volume.data) throw Error("volume has no data");
    // The engines read samples as their type: a misaligned address is undefined behaviour.
    if (const std::size_t size = scalar_size(volume.type); reinterpret_cast<std::uintptr_t>(volume.data) % size != 0)
        throw Error(std::string("volume data at an address that is not a multiple of ") + std::to_string(size) +
                    " bytes, the size of a " + scalar_name(volume.type) +
                    " sample; copy the samples to aligned memory (a std::vector of the sample type is)");
}

void validate_volume(const VolumeView& volume) {
    for (int d = 0; d < 3; ++d)
        if (volume.dims[d] < 2)
            throw Error("volume dimension " + std::string(1, "xyz"[d]) + " is " + std::to_string(volume.dims[d]) +
                        "; marching cubes needs at least 2 samples along every axis");
    checked_volume_bytes(volume.dims, volume.type);
    // Per-row counts are 32-bit (RowInfo, the kernels' row counts): up to 5 triangles a cell.
    if (volume.dims[0] > kMaxRowSamples)
        throw Error("volume rows of " + std::to_string(volume.dims[0]) + " samples are longer than the " +
                    std::to_string(kMaxRowSamples) + " supported (mesh it in parts along x)");
    check_samples_readable(volume);
    for (int d = 0; d < 3; ++d)
        if (!(volume.spacing[d] > 0) || !std::isfinite(volume.spacing[d]) || !std::isfinite(volume.origin[d]))
            throw Error("volume spacing must be positive and finite, origin finite");
    if (const int d = axis_beyond_float(volume.dims, volume.spacing, volume.origin); d >= 0)
        throw Error("volume origin and spacing put samples along " + std::string(1, "xyz"[d]) +
                    " beyond the range of float vertex coordinates");
}

CpuChunkPlan cpu_classify(const VolumeView& volume, const Options& options, ZRange range, unsigned threads) {
    const auto t0 = Clock::now();
    CpuChunkPlan plan;
    plan.range = range;
    const std::size_t ny = volume.dims[1], nz = volume.dims[2];
    dispatch_scalar(volume.type, [&](auto tag) {
        using T = decltype(tag);
        const Threshold<T> threshold = make_threshold<T>(options.iso);
        if (threshold.uniform != Uniform::Mixed) {
            check_finite<T>(volume, range);
            plan.uniform = true;
            return;
        }
        plan.meta_planes = std::min(range.end + 1, nz) - range.begin;
        plan.rows = ScratchArray<RowInfo>(plan.meta_planes * ny, Pages::Huge);  // every row is written
        plan.planes.assign(plan.meta_planes, PlaneCounts{});
        if (sizeof(T) >= 2) {
            plan.plane_bit_words = ny * words_per_row(volume.dims[0]);
            // Small pages: a plane uses the start of its room, and huge pages would make all of
            // it resident (CT i16 512³: 8.7 % of volume + mesh above them at peak, not 6.0 %).
            plan.plane_bits = ScratchArray<Word>(plan.meta_planes * plan.plane_bit_words, Pages::Small);
        }
        const unsigned slabs = slab_count(threads, plan.meta_planes, kClassifySlabsPerThread);
        // Every plane alike: its work is not known before classify has run.
        const auto cuts = shrinking_split(std::vector<double>(plan.meta_planes, 1.0), slabs);
        run_slabs(slabs, threads, [&](unsigned w, unsigned) {
            if (cuts[w] == cuts[w + 1]) return;  // the shrinking split can leave a last slab empty
            classify_planes<T>(plan, volume, threshold.value, range.begin + cuts[w], range.begin + cuts[w + 1],
                               plan.rows.data(), plan.planes.data());
        });
    });
    if (plan.uniform) return plan;
    const auto t1 = Clock::now();
    plan.classify_seconds = std::chrono::duration<double>(t1 - t0).count();

    // Scan: exclusive prefix sums of the plane sums give every plane its first vertex and
    // triangle (generate walks each plane's rows from there).
    std::uint64_t vertices = 0, triangles = 0;
    const std::size_t owned_planes = range.end - range.begin;
    for (std::size_t p = 0; p < plan.meta_planes; ++p) {
        if (p == owned_planes) plan.vertices = vertices;
        if (p < owned_planes) plan.widest_words = std::max(plan.widest_words, plan.planes[p].widest_words);
        plan.planes[p].first_vertex = vertices;
        plan.planes[p].first_triangle = triangles;
        vertices += plan.planes[p].vertices;
        triangles += plan.planes[p].triangles;
    }
    if (owned_planes == plan.meta_planes) plan.vertices = vertices;
    check_vertex_count(vertices);
    plan.triangles = triangles;
    plan.scan_seconds = seconds_since(t1);
    return plan;
}

void cpu_generate(const CpuChunkPlan& plan, const VolumeView& volume, const Options& options, unsigned threads,
                  const MeshOut& out) {
    // A range can own vertices and no triangles: the volume's last plane alone has no cells.
    if (plan.uniform || (plan.vertices == 0 && plan.triangles == 0)) return;
    const std::size_t planes = plan.range.end - plan.range.begin;
    // Balance by work (classify's estimate per plane), not by planes.
    std::vector<double> cost(planes);
    for (std::size_t p = 0; p < planes; ++p) cost[p] = plan.planes[p].cost;
    threads = std::max(threads, 1u);
    const unsigned slabs = slab_count(threads, planes, kGenerateSlabsPerThread);
    const auto cuts = shrinking_split(cost, slabs);
    dispatch_scalar(volume.type, [&](auto tag) {
        using T = decltype(tag);
        const T threshold = make_threshold<T>(options.iso).value;
        // One generator per thread, reused for its slabs: its scratch planes are touched
        // (page-faulted) once, not once per slab.
        const auto run = [&](auto id_tag) {
            using Id = decltype(id_tag);
            std::vector<std::unique_ptr<Generator<T, Id>>> generators(std::min(slabs, resolve_threads(0)));
            run_slabs(slabs, threads, [&](unsigned slab, unsigned worker) {
                if (cuts[slab] == cuts[slab + 1]) return;
                auto& generator = generators[worker];
                if (!generator) generator = std::make_unique<Generator<T, Id>>(plan, volume, options, out, threshold);
                generator->run(plan.range.begin + cuts[slab], plan.range.begin + cuts[slab + 1]);
            });
        };
        if (volume.dims[0] <= kMaxNxFor16BitIds) run(std::uint16_t{});
        else run(std::uint32_t{});
    });
}

Mesh cpu_extract(const VolumeView& volume, const Options& options, Stats& stats, Mesh storage, double* grown_sizing_s) {
    const auto t0 = Clock::now();
    validate_volume(volume);
    const unsigned threads = resolve_threads(options.threads);
    stats.backend = Backend::Cpu;
    stats.threads = threads;
    stats.workers = running_threads(threads);

    CpuChunkPlan plan = cpu_classify(volume, options, ZRange{0, volume.dims[2]}, threads);
    stats.times.classify = plan.classify_seconds;
    stats.times.scan = plan.scan_seconds;

    // Output allocation counts toward generate: it is the first write of the output.
    const auto t = Clock::now();
    Mesh mesh = std::move(storage);
    const double grown = allocate_output(mesh, plan.vertices, plan.triangles, options.normals, threads,
                                        spare_row_samples(plan, volume));
    if (grown_sizing_s) *grown_sizing_s = grown;

    cpu_generate(plan, volume, options, threads,
                 MeshOut{mesh.positions.data(), options.normals ? mesh.normals.data() : nullptr, mesh.indices.data(), 0});
    trim_output(mesh, plan.vertices, plan.triangles);
    stats.times.generate = seconds_since(t);
    stats.times.total = seconds_since(t0);

    DeviceStats cpu;
    cpu.name = "cpu";
    cpu.chunks = 1;
    cpu.voxels = volume.dims[0] * volume.dims[1] * volume.dims[2];
    cpu.wall_s = stats.times.total;
    stats.devices.push_back(cpu);
    return mesh;
}

}  // namespace voxmesh::detail
