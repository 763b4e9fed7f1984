// The multi-threaded CPU engine: classify, scan and generate over z-slabs.
//
// It meshes a range of sample planes [begin, end): those planes own their vertices (the
// crossed +x, +y, +z edges of their samples) and cell planes [begin, min(end, nz-1)) own
// their triangles. Vertex ids are local to the range and continue, in canonical order,
// into plane `end` (the next range's first plane), so a chunk's global vertex id is
// always its vertex base plus the local id. The OpenCL engine follows the same rule.
#pragma once

#include "row_packer.hpp"
#include "scratch.hpp"

#include <voxmesh/voxmesh.hpp>

#include <cstdint>
#include <limits>
#include <vector>

namespace voxmesh::detail {

struct ZRange {
    std::size_t begin = 0, end = 0;
};

constexpr std::uint32_t kEmptyRow = std::numeric_limits<std::uint32_t>::max();

// What the classify pass learns about one sample row (y, z) and the cell row it starts.
struct RowInfo {
    std::uint32_t first = kEmptyRow;  // first x whose owned edges cross; kEmptyRow if none
    std::uint32_t last = 0;           // last such x; a row without crossings keeps its inside bit here
    std::uint32_t vertices = 0;       // crossed edges owned by the row
    std::uint32_t triangles = 0;      // triangles of cells (x, y, z) for all x
    std::uint32_t bits_at = 0;        // with crossings: where its inside bits are in the plane's store

    bool empty() const { return first == kEmptyRow; }
    std::uint32_t uniform_bit() const { return last; }  // only for an empty row
};

// One meta plane's rows summed by classify, and where its first vertex (local id) and first
// triangle go, from the scan. Generate derives each row's bases by walking the plane's rows
// in order, so there is no per-row table of bases and the scan is over planes, not rows.
struct PlaneCounts {
    std::uint64_t vertices = 0, triangles = 0;
    std::uint64_t first_vertex = 0, first_triangle = 0;
    double cost = 0;  // generate's work on the plane, an estimate to balance slabs by
    // The most words generate walks in one of the plane's rows or cell rows (row_words,
    // cell_row_words): what bounds a re-read row's writes past classify's counts.
    std::size_t widest_words = 0;
};

// Classify + scan result for one z-range: per-row counts, per-plane sums and their prefix sums.
struct CpuChunkPlan {
    ZRange range;
    std::size_t meta_planes = 0;             // planes with RowInfo: the range plus plane `end` if it exists
    // meta_planes * ny, in scratch kept from call to call (scratch.hpp): classify writes
    // every row's first, last, vertices and triangles (bits_at where it keeps bits).
    ScratchArray<RowInfo> rows;
    // Per meta plane, the inside bits classify packed for the rows with crossings (the only
    // rows generate reads samples of), so generate does not read and pack them again: plane
    // p's rows one after another from kept_bits(p). Kept for samples of 2 bytes or more only,
    // where they cost at most 1/16 of the volume; 8-bit samples are cheaper to pack again
    // than to keep.
    ScratchArray<Word> plane_bits;
    std::size_t plane_bit_words = 0;         // room per plane: ny rows' words
    bool keeps_bits() const { return plane_bits.size() > 0; }
    Word* kept_bits(std::size_t p) const { return plane_bits.data() + p * plane_bit_words; }
    std::vector<PlaneCounts> planes;         // meta_planes
    std::uint64_t vertices = 0;   // owned by the range (excludes plane `end`)
    std::uint64_t triangles = 0;
    std::size_t widest_words = 0;  // the largest of the owned planes' widest_words
    bool uniform = false;         // no sample can cross iso: nothing to generate
    double classify_seconds = 0, scan_seconds = 0;
};

// Where generate writes: positions/normals of vertex 0 of the range, its first triangle,
// and the global id of its first vertex (added to every index). normals may be null.
struct MeshOut {
    float* positions = nullptr;
    float* normals = nullptr;
    std::uint32_t* indices = nullptr;
    std::uint32_t vertex_base = 0;
};

CpuChunkPlan cpu_classify(const VolumeView& volume, const Options& options, ZRange range, unsigned threads);
void cpu_generate(const CpuChunkPlan& plan, const VolumeView& volume, const Options& options, unsigned threads,
                  const MeshOut& out);

// Sizes the mesh's arrays (normals only when asked for). std::vector zero-fills on resize,
// and for a large mesh that first touch of every page is a pass of its own: the arrays are
// filled on up to `threads` workers at once.
// Each array gets the room of `row_samples` samples past the counts (0: none): generate checks
// a re-read 8-bit row against classify's counts only once it is written, so a volume changed
// during the call may write one row's vertices (3 a sample) and one cell row's triangles (5 a
// cell) more before it throws; only within the words classify found the row's crossings in
// (spare_row_samples). trim_output cuts the arrays to the counts.
// Returns the seconds it took where some array's storage was too small and was replaced (a new
// Mesh, or a reused one whose surface grew), else 0: Hybrid leaves that out of the time it
// compares its modes by, since it comes once where a reused mesh grows.
double allocate_output(Mesh& mesh, std::uint64_t vertices, std::uint64_t triangles, bool normals, unsigned threads,
                       std::size_t row_samples);
void trim_output(Mesh& mesh, std::uint64_t vertices, std::uint64_t triangles);
// The spare room allocate_output needs after the CPU engine's plan: none where generate reads
// no row again (samples of 2 bytes or more use classify's bits; nothing to generate), else the
// widest stretch of a row generate walks, not the whole row (a 2^24-sample row of an empty u8
// volume made 2.1 GB of spare room).
std::size_t spare_row_samples(const CpuChunkPlan& plan, const VolumeView& volume);

// Whole-volume extraction written straight into the mesh (no merge copy).
// `storage`: a mesh whose arrays' capacity the result reuses (extract_into).
// `grown_sizing_s`: where given, allocate_output's return.
Mesh cpu_extract(const VolumeView& volume, const Options& options, Stats& stats, Mesh storage = {},
                 double* grown_sizing_s = nullptr);

// The longest row (nx) a volume may have: a row's vertex and triangle counts stay 32-bit.
constexpr std::size_t kMaxRowSamples = std::size_t{1} << 29;

// Throws Error unless every dimension is >= 2, data is set, the size is addressable, rows are
// at most kMaxRowSamples long and every sample's position fits a float.
void validate_volume(const VolumeView& volume);
// Its part that any pass reading the samples needs: data set and aligned to the sample size.
void check_samples_readable(const VolumeView& volume);

// Throws Error when a mesh of `vertices` vertices cannot be indexed by 32-bit indices. Every
// engine assembling vertex ids (CPU, OpenCL, sculpting) asks here, so they refuse alike.
[[noreturn]] void throw_too_many_vertices();
inline void check_vertex_count(std::uint64_t vertices) {
    if (vertices > std::numeric_limits<std::uint32_t>::max()) throw_too_many_vertices();
}

// NaN or infinite samples, found by an engine in z-plane `plane`. Engines throw it from
// whichever slab, chunk or device saw one; extract() names the volume's first such plane
// instead (first_non_finite_plane), so the message does not depend on the schedule.
struct NonFiniteSamples : Error {
    explicit NonFiniteSamples(std::size_t plane);
    std::size_t plane;
};
[[noreturn]] void throw_non_finite(std::size_t plane);

// Generate read a row's samples again and found other crossings than classify counted: the
// volume was written to during the call (another thread; Python releases the GIL). Its
// vertices and triangles go where classify's counts put them; a row is checked once written,
// so one that has more wrote into the next rows' room or allocate_output's spare row, never
// past the mesh's arrays.
[[noreturn]] void throw_volume_changed(std::size_t plane);
// The first z-plane holding a NaN or infinite sample; dims[2] when there is none.
std::size_t first_non_finite_plane(const VolumeView& volume);

}  // namespace voxmesh::detail
