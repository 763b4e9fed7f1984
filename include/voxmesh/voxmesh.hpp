// voxmesh: marching cubes on every compute device a machine has.
// The whole public API: plain structs and free functions, no OpenCL types.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "version.h"  // VOXMESH_VERSION_MAJOR, _MINOR, _PATCH, _STRING

namespace voxmesh {

// Every failure throws this, with a message a user can act on.
struct Error : std::runtime_error {
    using std::runtime_error::runtime_error;
};
// An Error where memory ran out during a call (an allocation failed); its message says what
// was being done. Unlike the input's faults it may pass with more memory, smaller inputs or
// later. A check made before allocating (a file's samples larger than the memory available)
// is a plain Error.
struct OutOfMemoryError : Error {
    using Error::Error;
};

enum class ScalarType { U8, I8, U16, I16, U32, I32, F32, F64 };
std::size_t scalar_size(ScalarType type);
const char* scalar_name(ScalarType type);  // "u8", "i16", "f32", ...

// Hybrid meshes with the OpenCL devices and the CPU threads together; with one device, a call
// runs whichever of that split, the CPU engine alone and the device alone earlier calls on the
// same volume (or, for a new one, volume shape) found quickest (the mesh is the same whichever
// runs; see the README).
enum class Backend { Auto, Cpu, OpenCL, Hybrid };
const char* backend_name(Backend backend);  // "auto", "cpu", "opencl", "hybrid"

// A non-owning view of x-fastest samples: index = x + nx * (y + ny * z). `data` must be
// aligned to the sample size (an Error otherwise), as any array of the sample type is.
struct VolumeView {
    const void* data = nullptr;
    ScalarType type = ScalarType::F32;
    std::array<std::size_t, 3> dims{0, 0, 0};
    std::array<double, 3> spacing{1, 1, 1};
    std::array<double, 3> origin{0, 0, 0};
};

// An owning volume, as readers return it. `storage` keeps the samples alive (a heap block
// or a memory map); `data` points at the first sample.
struct Volume {
    ScalarType type = ScalarType::F32;
    std::array<std::size_t, 3> dims{0, 0, 0};
    std::array<double, 3> spacing{1, 1, 1};
    std::array<double, 3> origin{0, 0, 0};
    std::shared_ptr<void> storage;
    void* data = nullptr;

    // Zero-filled samples; throws Error when the size overflows or cannot be allocated.
    static Volume allocate(ScalarType type, std::array<std::size_t, 3> dims);
    std::size_t sample_count() const;
    std::size_t byte_size() const;
    VolumeView view() const;
};

// The checked product nx*ny*nz*scalar_size; throws Error on overflow.
std::size_t checked_volume_bytes(std::array<std::size_t, 3> dims, ScalarType type);

enum class DeviceType { Any, Cpu, Gpu, Accelerator };

struct Options {
    double iso = 0;
    Backend backend = Backend::Auto;
    // CPU worker threads; 0 = all cores this process may use (its affinity mask, capped by a
    // cgroup CPU quota), counted when the library is loaded. Copies to a discrete GPU run on as
    // many; Hybrid's on the cores its CPU worker leaves (at least 2), or on all cores in a call
    // where Hybrid runs the device alone (it found that quicker than sharing: see README).
    unsigned threads = 0;
    bool normals = true;
    bool inside_below = false;  // flip: inside where value < iso (SDFs); winding and normals only

    // OpenCL device choice: indices into list_devices(); empty = every device of device_type.
    std::vector<int> devices;
    DeviceType device_type = DeviceType::Any;
    std::size_t chunk_planes = 0;   // z-planes per chunk; 0 = automatic
    std::size_t memory_budget = 0;  // bytes per device for one chunk; 0 = the device's limits
    // Warnings (fallback to the CPU engine, smaller chunks after an allocation failure, ...).
    std::function<void(const std::string&)> log;
};

// One vertex per crossed edge, welded; see README "The canonical mesh".
struct Mesh {
    std::vector<float> positions;  // xyz per vertex
    std::vector<float> normals;    // xyz per vertex, unit, outward; empty when normals are off
    std::vector<std::uint32_t> indices;  // three per triangle, counter-clockwise seen from outside

    std::size_t vertex_count() const { return positions.size() / 3; }
    std::size_t triangle_count() const { return indices.size() / 3; }
};

struct PassTimes {  // seconds
    double classify = 0, scan = 0, generate = 0, total = 0;
};

struct DeviceStats {
    std::string name;           // "cpu" or the OpenCL device name
    std::size_t chunks = 0;     // chunks it meshed (one split to fit the device counts once)
    std::size_t voxels = 0;     // samples in the chunks it meshed
    double kernel_s = 0;        // device execution time (profiling events)
    double transfer_s = 0;      // host<->device copies
    double wall_s = 0;
    double setup_s = 0;         // OpenCL: kernel builds and set-up in this call (0 once cached)
    std::size_t programs_built = 0;  // OpenCL programs compiled in this call (0 once cached)
    // Hybrid: chunks this device counted that the CPU worker, out of work of its own, meshed
    // instead because that was quicker than waiting (counted in the CPU's `chunks` and `voxels`,
    // not in this device's).
    std::size_t chunks_handed_over = 0;
};

struct Stats {
    // What actually ran: Cpu where OpenCL was asked for and every chunk ran on the CPU engine
    // instead (no device could mesh one; the warnings say why). Hybrid stays Hybrid.
    Backend backend = Backend::Cpu;
    // Options::threads resolved (0 becomes the usable CPUs): the CPU slabs, which run on no more
    // threads than the process may use at once; 0 for the OpenCL engine alone.
    unsigned threads = 0;
    PassTimes times;
    std::vector<DeviceStats> devices;
    std::vector<std::string> warnings;  // also sent to Options::log
    // The most CPU threads that ran the slabs at once: `threads` capped at the CPUs this
    // process may use (a volume too thin for that many slabs runs on fewer); 0 where no CPU
    // worker ran (the OpenCL engine, Hybrid running the device alone). A Hybrid split counts its
    // CPU worker even where the plan left it no chunk.
    // (Last, so that the fields before it keep their places for code built against 0.1.0.)
    unsigned workers = 0;
};

// The iso-surface of `volume` at options.iso, as the canonical mesh.
// Callable from several threads at once, with any backends: the calls share the CPU thread
// pool and the OpenCL devices (a device meshes for one call at a time, the others wait for
// it), and each still returns the canonical mesh.
// The samples are read more than once: keep them unchanged until the call returns. Written to
// meanwhile (a data race), a call may throw Error ("the volume's samples changed while it was
// being meshed") or mesh a mix of old and new samples (each vertex finite, on its edge); it
// never writes past the mesh.
// In a child forked after the parent used OpenCL, the parent's devices are not listed (their
// runtime's threads stayed in the parent): Auto meshes on the CPU, OpenCL throws an Error.
// The child may fork while other threads are inside calls; its own calls still work.
Mesh extract(const VolumeView& volume, const Options& options);
Mesh extract(const VolumeView& volume, const Options& options, Stats& stats);

// As extract(), into `mesh`, reusing the storage its arrays already have. Meshing again into
// the same Mesh (a sculpting loop, an animation, a benchmark) writes memory that is already
// mapped, where a new Mesh takes fresh pages that the kernel zeroes on first touch and
// std::vector zeroes again (5–12 % of a 512³ sphere or 256³ gyroid extract on the CPU engine
// here). The previous contents are replaced; on an exception `mesh` is left empty.
void extract_into(const VolumeView& volume, const Options& options, Mesh& mesh, Stats& stats);

// A volume's samples summed up in one pass on all cores (threads as Options::threads): the
// smallest and the largest finite sample (both 0 when none is), the NaN and infinite ones (float
// types) with the first in index order, and, where `equal_to` is given, how many finite samples
// equal it exactly (-0.0 equals 0.0; a min or max of zero reads +0.0). Samples exactly at iso are inside here and outside for tools that mesh value > iso
// (scikit-image): they are where the two meshes differ.
struct ValueRange {
    double min = 0, max = 0;
    std::uint64_t nonfinite = 0;
    std::array<std::size_t, 3> first_nonfinite{0, 0, 0};  // (x, y, z); meaningful when nonfinite > 0
    std::uint64_t equal = 0;                               // samples == equal_to (0 without one)
};
ValueRange value_range(const VolumeView& volume, std::optional<double> equal_to = std::nullopt, unsigned threads = 0);

// The crossed edge under each vertex of extract(volume, options with this iso), for data kept
// per sample or per cell (labels, a second field) carried onto the mesh without meshing again.
// The canonical mesh has one vertex per edge whose ends lie on either side of iso, ordered by
// the edge's lower end, then axis; so vertex i lies on the edge
//   edges[i] = 3 * (x + nx * (y + ny * z)) + axis   (axis 0 x, 1 y, 2 z; (x, y, z) its lower end).
// inside_below and the backend do not change it. Errors as extract's: dims below 2, NaN or
// infinite samples (naming the first z-plane holding one); threads as Options::threads.
std::vector<std::uint64_t> vertex_edges(const VolumeView& volume, double iso, unsigned threads = 0);
// As vertex_edges, into memory the caller has (a binding's array): returns how many crossed
// edges there are, and writes them when `edges` has room for them all, else writes nothing
// (an empty span asks for the count alone).
std::size_t vertex_edges_into(const VolumeView& volume, double iso, std::span<std::uint64_t> edges, unsigned threads = 0);

// The cell each triangle of extract(volume, options with this iso) lies in, for data kept per
// cell (a mask, a material, a region) carried onto the triangles, or triangles picked by cell
// without meshing again. The canonical mesh writes each cell's triangles together, cells in
// index order, so triangle i lies in the cell
//   cells[i] = x + (nx - 1) * (y + (ny - 1) * z)   ((x, y, z) its lowest corner),
// one entry per triangle (a cell with two triangles appears twice, in a row). inside_below and
// the backend do not change it. Errors as vertex_edges'.
std::vector<std::uint64_t> triangle_cells(const VolumeView& volume, double iso, unsigned threads = 0);
// As triangle_cells, into memory the caller has; returns the triangle count, writing as
// vertex_edges_into does.
std::size_t triangle_cells_into(const VolumeView& volume, double iso, std::span<std::uint64_t> cells, unsigned threads = 0);

// For each of `edges` (vertex_edges' numbering; an edge the volume does not hold is an Error),
// the largest range, maximum sample minus minimum, over the cells around it: the up to four
// cells the volume holds that share the edge, and of those only the ones `cell_mask` marks
// nonzero when it is given ((nx-1)(ny-1)(nz-1) bytes, x fastest, a cell by its lowest corner);
// 0 where no cell counts. Each range is (max - offset) - (min - offset) in double, rounded to
// float (infinity beyond float's range): with offset = the level, scikit-image's `values` from
// marching_cubes. Samples must be finite (vertex_edges refuses others); ranges over NaN are
// unspecified.
std::vector<float> edge_cell_ranges(const VolumeView& volume, std::span<const std::uint64_t> edges,
                                    double offset = 0, const std::uint8_t* cell_mask = nullptr,
                                    unsigned threads = 0);
// As edge_cell_ranges, into `ranges` (one float per edge; another size is an Error), for a
// caller whose memory is already there (a binding's array).
void edge_cell_ranges_into(const VolumeView& volume, std::span<const std::uint64_t> edges, std::span<float> ranges,
                           double offset = 0, const std::uint8_t* cell_mask = nullptr, unsigned threads = 0);

// The CPU engine keeps its scratch memory (per-row counts, the inside bits it keeps for 16-
// to 64-bit samples, vertex-id tables) from one extract to the next, at most 512 MB, so that
// a later extract does not page-fault it in again: after a 512³ volume on 2 threads, 28 MB
// for float samples and 11 MB for 8-bit ones. A kept block left unused while later calls
// made 128 requests for scratch (about 35 calls on 2 threads) is freed by the pool itself.
// The OpenCL devices keep their buffers and pinned copy blocks between calls too (on PoCL in
// host memory). This frees what both engines keep at once, for a program done meshing large
// volumes; the next extract allocates anew. Compiled programs stay, and no device is opened
// by it. A device another thread is meshing on keeps its buffers.
void release_scratch_memory();

// Writes .stl (binary), .ply (binary), .obj or .glb (binary glTF 2.0: the arrays as they
// are, one scene of one mesh; glTF viewers read its coordinates as metres with +Y up, so a
// mesh in millimetres looks a thousand times too large there until scaled, and a mesh with
// vertices but no triangles is written as points; normals must be of unit length there, as
// glTF asks: the engines' are), chosen by extension, through a temporary
// file renamed into place: a failure never leaves a partial file. A malformed mesh (see
// analyze_topology) or a NaN or infinite coordinate or normal is an Error; nothing is written.
// A symbolic link at `path` is written through (the file it names is replaced, the link
// kept), a file replaced keeps its permission bits (and its owner, where the process may set
// it), a file the process may not write is an Error, and a FIFO or device is written into
// rather than replaced, as a shell's `>` would do. A file with other hard links becomes a new
// file under `path`; its other names keep the old contents.
void write_mesh(const std::string& path, const Mesh& mesh);
// The bytes write_mesh would write, in memory, for a service to send or store without a file:
// `name` stands for the path ("part.stl"; its extension picks the format, errors name it).
std::vector<unsigned char> write_mesh_to_memory(const Mesh& mesh, const std::string& name);

// Removes the temporary files of writes in progress (write_mesh, write_nrrd), for a program's
// SIGINT / SIGTERM handler to call before the program dies, so that an interrupted write
// leaves nothing behind. Async-signal-safe. The voxmesh command line tool does this (its
// copy of standard input is listed among them).
void remove_partial_outputs() noexcept;

// Topology summary: closed means every edge is in exactly two triangles. An edge joins two
// different vertices: a triangle with a repeated corner (a, a, b) has the one edge {a, b} (it
// still counts in F), and one with three equal corners has none.
struct MeshTopology {
    std::size_t boundary_edges = 0;      // edges in one triangle
    std::size_t nonmanifold_edges = 0;   // edges in three or more
    long long euler = 0;                 // V - E + F over referenced vertices (summed over components)
    std::size_t components = 0;          // connected pieces: triangles sharing a vertex are in one
    bool closed() const { return boundary_edges == 0 && nonmanifold_edges == 0; }
};
// Throws Error, as write_mesh does, for arrays that are not whole triples, normals for a
// different number of vertices, or an index past the last vertex; out of memory is an Error
// too, as from extract.
MeshTopology analyze_topology(const Mesh& mesh);

// The `count` connected pieces with the most triangles (triangles sharing a vertex are in one
// piece, as in VTK's vtkPolyDataConnectivityFilter; of pieces with equal triangle counts, the
// one whose first triangle comes first), e.g. a CT's surface without the specks of noise
// around it. Kept triangles and vertices stay in their order, so a piece of a canonical mesh
// is exactly what extract gives for a volume holding that piece alone (the same samples
// around it, nothing else crossing iso). Normals are kept.
// Throws Error for count 0, for the malformed arrays analyze_topology rejects, and when out
// of memory.
Mesh keep_largest_components(const Mesh& mesh, std::size_t count = 1);

// OpenCL devices as plain structs (empty without OpenCL or without a platform).
struct DeviceInfo {
    int index = 0;
    std::string platform, name, version;
    DeviceType type = DeviceType::Cpu;
    unsigned compute_units = 0;
    std::uint64_t global_memory = 0, max_allocation = 0;
    bool fp64 = false;
    bool host_memory = false;  // shares the host's memory: volume read and mesh written in place (zero-copy)
};
std::vector<DeviceInfo> list_devices();
bool opencl_available();  // built with OpenCL and at least one usable device

}  // namespace voxmesh
