// Sculpting: an editable volume whose surface is kept as a mesh split into fixed-size
// blocks, so that an edit re-meshes only the blocks it can affect.
//
// Blocks: block (bx, by, bz) holds the marching-cubes cells [b*B, min((b+1)*B, n-1)) on each
// axis (B = SculptOptions::block_size). Its mesh is self-contained: every vertex its
// triangles use (one per crossed edge inside the block's closed box, in canonical order:
// sample linear index, then axis) is stored in the block, so a renderer can upload one
// block alone. Vertices on the faces shared by two blocks are stored by both.
//
// Vertex positions and normals are computed on the whole volume with the same formula as
// voxmesh::extract (normals use true central differences across block borders), so they
// are bit-identical to extract's. mesh() welds the blocks by global edge identity and
// returns exactly extract's canonical mesh (same vertex order, same triangle order).
//
// Dirty tracking: a block's mesh reads the samples [c0-1, c1+1] on each axis (its cells'
// corners plus the one-sample margin of central-difference normals). An edit marks every
// block whose range contains a sample whose value changed (an edit at a block corner marks
// up to 8 blocks). Edits are clipped to the volume; a brush entirely outside does nothing.
//
// Threads: a Sculpt is used from one thread at a time. update() re-meshes on a pool of
// worker threads the Sculpt keeps for its lifetime, or on an OpenCL device
// (SculptOptions::backend): one batch of launches per update, every block mesh identical to
// the CPU's (same vertices, triangles and indices; positions and normals bit-identical on
// devices with fp64, within a few ulps without).
//
// Coordinates: brushes work in sample (index) coordinates unless Units::World is given,
// where a point p maps to (p - origin) / spacing and a radius r to r / spacing per axis.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace voxmesh {

struct VoxelizeOptions;  // voxelize.hpp

struct SculptOptions {
    double iso = 0;               // inside where value >= iso
    unsigned threads = 0;         // update() workers; 0 = all cores (never more than this process may use)
    std::size_t block_size = 32;  // cells per block side, 2..256 (why 32: src/sculpt/sculpt.cpp)
    bool normals = true;
    bool inside_below = false;    // as Options::inside_below: flips winding and normals only
    // Field-value change of an Add/Subtract brush of strength 1 at its centre. For a signed
    // distance field in model units, the voxel spacing makes strength "samples of surface
    // displacement" (from_stl sets it so when left at 0). 0 = 1 for other volumes.
    double strength_scale = 0;
    // Where update() re-meshes: Cpu (threads), OpenCL (device), or Auto (a GPU or accelerator
    // when there is one, else the CPU). Hybrid is not supported (an Error). Without a usable
    // OpenCL device, OpenCL and Auto mesh on the CPU; OpenCL says so through `log`.
    Backend backend = Backend::Cpu;
    int device = -1;  // OpenCL device: an index into list_devices(); -1 = a GPU/accelerator, else the first;
                      // other negative values are an Error
    std::function<void(const std::string&)> log;  // warnings (fallback to the CPU); may be empty
};

enum class BrushOp {
    Add,       // value += strength * strength_scale * falloff   (falloff = (1 - d²/r²)³ inside r)
    Subtract,  // value -= strength * strength_scale * falloff
    Smooth,    // value += clamp(strength, 0, 1) * falloff * (mean of 6 neighbours - value)
    Set,       // every sample in the box center ± radius := strength (clamped to the type)
};
const char* brush_op_name(BrushOp op);  // "add", "subtract", "smooth", "set"
BrushOp parse_brush_op(const std::string& name);  // throws Error

enum class Units { Samples, World };

// One brush application.
struct Dab {
    BrushOp op = BrushOp::Add;
    std::array<double, 3> center{0, 0, 0};
    double radius = 8;    // > 0; Set: half-side of the box
    double strength = 1;  // see BrushOp
};

// A read-only view of one block's self-contained mesh; valid until the next update().
struct BlockMesh {
    std::size_t index = 0;                        // linear block index: bx + nbx * (by + nby * bz)
    std::array<std::size_t, 3> coord{0, 0, 0};    // (bx, by, bz)
    std::array<std::size_t, 3> cell_begin{0, 0, 0}, cell_end{0, 0, 0};  // cells [begin, end)
    std::span<const float> positions;             // xyz per vertex
    std::span<const float> normals;               // xyz per vertex; empty when normals are off
    std::span<const std::uint32_t> indices;       // three per triangle, into this block's vertices
    std::size_t vertex_count() const { return positions.size() / 3; }
    std::size_t triangle_count() const { return indices.size() / 3; }
};

struct UpdateResult {
    std::vector<std::size_t> changed;  // blocks re-meshed that are or were non-empty (ascending)
    std::size_t remeshed = 0;          // dirty blocks re-meshed (including empty ones)
    double seconds = 0;
};

struct SculptMemory {           // bytes
    std::size_t block_meshes = 0;   // capacity of every block's positions, normals, indices
    std::size_t block_table = 0;    // per-block bookkeeping (vectors, dirty flags)
    // Per-worker meshing scratch (about (B+1)^3 * 6 bytes a worker, plus its largest block's
    // triangle list, at most 60 bytes a cell) and the smooth brush's two plane buffers (16
    // bytes a sample of the largest x-y extent smoothed).
    std::size_t scratch = 0;
    std::size_t volume = 0;         // the editable samples
};

class Sculpt {
public:
    // Copies the samples (u8, u16 or f32; other types are an Error: convert first). All
    // blocks start dirty: the first update() meshes everything.
    Sculpt(const VolumeView& volume, const SculptOptions& options = {});
    // A dims volume of `type` filled with f(x, y, z) at sample coordinates (called from
    // several threads; must be thread-safe), rounded and clamped for integer types.
    static Sculpt from_function(std::array<std::size_t, 3> dims, ScalarType type,
                                const std::function<double(double, double, double)>& f,
                                const SculptOptions& options = {});
    // A closed model voxelized (voxelize, Distance field) at `resolution`: f32, positive inside,
    // iso 0, in the model's units; strength_scale defaults to the voxel spacing (strength =
    // samples of displacement).
    static Sculpt from_mesh(const Mesh& model, std::size_t resolution, const SculptOptions& options = {});
    // The same with the voxelization chosen (voxelize.hpp): more `padding` gives a surface room
    // to be built up before it meets the volume's border, where its mesh is cut open (the
    // resolution-only form leaves 2 samples). The field must be Distance.
    static Sculpt from_mesh(const Mesh& model, const VoxelizeOptions& voxelize, const SculptOptions& options = {});
    // The voxelization the resolution-only from_mesh uses, to start from: `resolution`, the
    // default padding, band 4 (a smooth field for the brushes), options.threads.
    static VoxelizeOptions model_voxelization(std::size_t resolution, const SculptOptions& options = {});
    // from_mesh(read_stl(path)); read_mesh (io.hpp) also reads .ply and .obj models.
    static Sculpt from_stl(const std::string& path, std::size_t resolution, const SculptOptions& options = {});

    // A moved-from Sculpt may only be assigned to or destroyed.
    Sculpt(Sculpt&&) noexcept;
    Sculpt& operator=(Sculpt&&) noexcept;
    Sculpt(const Sculpt&) = delete;
    Sculpt& operator=(const Sculpt&) = delete;
    ~Sculpt();

    // ---- edits (mark dirty blocks; nothing is meshed until update())
    void apply(const Dab& dab, Units units = Units::Samples);
    void add(std::array<double, 3> center, double radius, double strength, Units units = Units::Samples);
    void subtract(std::array<double, 3> center, double radius, double strength, Units units = Units::Samples);
    void smooth(std::array<double, 3> center, double radius, double strength, Units units = Units::Samples);
    // Every sample with lo <= coordinate <= hi on each axis := value (clamped to the type).
    void set_region(std::array<double, 3> lo, std::array<double, 3> hi, double value, Units units = Units::Samples);
    // Marks every block dirty (after writing to the samples through data()); an Error, marking
    // nothing, where the samples now hold NaN or infinities.
    void invalidate_all();

    // ---- meshing
    // Re-meshes dirty blocks in parallel. Out of memory is an Error, and the blocks stay dirty
    // for the next update(). An OpenCL error (the device's memory running out included) drops
    // the device with a warning through `log` naming it: this update() and the later ones
    // re-mesh on the CPU, and backend() says Cpu. In a child forked after its OpenCL device was
    // opened, the CPU re-meshes instead (with a warning): the device is the parent's runtime's.
    UpdateResult update();
    bool dirty() const;                   // edits not yet meshed
    std::size_t block_count() const;
    std::array<std::size_t, 3> block_grid() const;  // blocks per axis
    BlockMesh block(std::size_t index) const;
    // The whole welded mesh, identical to extract(view(), {iso, threads, normals,
    // inside_below}); runs update() first when edits are pending.
    Mesh mesh();

    // ---- the volume
    VolumeView view() const;
    void* data();  // the samples, for bulk writes; call invalidate_all() afterwards
    const SculptOptions& options() const;  // strength_scale resolved
    Backend backend() const;               // where update() re-meshes: Cpu or OpenCL
    std::string device_name() const;       // "cpu" or the OpenCL device's name
    std::array<double, 3> to_samples(std::array<double, 3> world) const;
    SculptMemory memory() const;

    struct Impl;  // opaque; declared here only so the implementation's helpers can name it

private:
    explicit Sculpt(std::unique_ptr<Impl> impl);
    // Takes over the samples of a volume Volume::allocate made (writable; a reader's may be
    // a read-only map), instead of copying them: from_mesh's grid is then held once.
    static Sculpt adopting(Volume&& volume, const SculptOptions& options);
    std::unique_ptr<Impl> impl_;
};

// A bumpy sphere: f32 distance-like field in samples, positive inside, iso 0, radius about
// 0.35 n around the centre of an n³ volume. The benchmark's analytic model.
Sculpt make_sculpt_sphere(std::size_t n, const SculptOptions& options = {});

// ---------------------------------------------------------------- stroke scripts
//
// One dab per line:  op x y z radius strength   (op: add | subtract | smooth | set)
// '#' starts a comment; blank lines are skipped. A line `units world` or `units samples`
// switches how later dabs' coordinates and radii are read (default: samples).
struct ScriptDab {
    Dab dab;
    Units units = Units::Samples;
    std::size_t line = 0;  // 1-based line in the script
};
// Throws Error "NAME:LINE: problem" on a malformed line.
std::vector<ScriptDab> parse_stroke_script(std::istream& in, const std::string& name = "strokes");
std::vector<ScriptDab> read_stroke_script(const std::string& path);

struct StrokeFrame {
    std::size_t frame = 0;  // 0-based dab number
    ScriptDab dab;
    double edit_seconds = 0;    // apply()
    double update_seconds = 0;  // update()
    std::size_t blocks_changed = 0, blocks_remeshed = 0;
};
// Applies each dab, then update(), and calls on_frame (may be empty) after each one.
void run_strokes(Sculpt& sculpt, const std::vector<ScriptDab>& dabs,
                 const std::function<void(const StrokeFrame&)>& on_frame);
// read_stroke_script + run_strokes.
void run_stroke_script(Sculpt& sculpt, const std::string& path,
                       const std::function<void(const StrokeFrame&)>& on_frame);

// n_dabs (>= 1) dabs in sample coordinates along a curve winding over the surface of
// make_sculpt_sphere(n) for a volume of `dims`: mostly add/subtract, every fifth a smooth,
// radius varying between radius_min and radius_max samples. Every dim must be >= 2 (Error).
std::vector<ScriptDab> builtin_stroke_path(std::size_t n_dabs, std::array<std::size_t, 3> dims,
                                           double radius_min = 8, double radius_max = 16);

// ---------------------------------------------------------------- benchmark

struct LatencySummary {  // milliseconds
    double p50 = 0, p95 = 0, p99 = 0, max = 0, mean = 0;
    std::size_t count = 0;
};
LatencySummary summarize_latencies(std::vector<double> milliseconds);  // nearest rank

struct SculptBenchOptions {
    std::size_t resolution = 256;   // n of the n³ make_sculpt_sphere model
    std::size_t dabs = 300;
    unsigned threads = 0;           // 0 = all cores
    std::size_t block_size = 32;
    double radius_min = 8, radius_max = 16;
    std::size_t extract_repeats = 3;  // full extract() timings (median reported); 0 = skip
    Backend backend = Backend::Cpu;   // where update() re-meshes (SculptOptions::backend)
    int device = -1;                  // SculptOptions::device
    double pause_ms = 0;              // sleep before each dab, as between an interactive program's frames
    // Asked before each dab; true ends the stroke there (the latencies are those of the dabs
    // done). Empty: every dab.
    std::function<bool()> stop;
};

struct SculptBenchResult {
    SculptBenchOptions options;
    unsigned threads = 0;           // resolved: options.threads, or the cores for 0
    unsigned workers = 0;           // the threads update() runs: `threads` capped at the cores
    Backend backend = Backend::Cpu; // what update() ran on (Cpu after a fallback)
    std::string device = "cpu";     // Sculpt::device_name()
    std::vector<std::string> warnings;  // e.g. the fallback to the CPU
    double build_model_ms = 0;      // volume generation
    double initial_update_ms = 0;   // first update(): every block
    LatencySummary update;          // per dab: update() latency
    LatencySummary frame;           // per dab: apply() + update()
    LatencySummary update_cpu;      // per dab: CPU time of update(), all workers (std::clock; steadier
                                    // than wall time on a loaded machine)
    double mean_blocks_remeshed = 0;
    double full_extract_ms = 0;     // median of extract_repeats full extract() runs (CPU engine)
    double mesh_assembly_ms = 0;    // one Sculpt::mesh() at the end
    std::size_t vertices = 0, triangles = 0;  // of the final mesh
    std::size_t full_mesh_bytes = 0;          // positions + normals + indices of the final mesh
    SculptMemory memory;
};
// Builds make_sculpt_sphere(resolution), replays builtin_stroke_path, times everything.
// `log` (may be empty) gets progress lines.
SculptBenchResult run_sculpt_benchmark(const SculptBenchOptions& options,
                                       const std::function<void(const std::string&)>& log = {});
// A multi-line human-readable report of a result.
std::string format_sculpt_benchmark(const SculptBenchResult& result);

}  // namespace voxmesh
