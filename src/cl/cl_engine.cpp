// The OpenCL engine: z-chunks from one shared queue, pulled by every selected device (and by
// the CPU engine in Hybrid), each chunk meshed by the bit-row kernels of marching_cubes.cl
// (classify: pack + per-row counts, scan over rows, generate: vertices + triangles). Every
// chunk is counted first; then the mesh is allocated once and each chunk generates straight
// into it at its offsets (no per-chunk meshes, no copy).
//
// A chunk is a z-range [begin, end) with the CPU engine's ownership rule (cpu_engine.hpp):
// it owns the vertices of sample planes [begin, end) and the triangles of cell planes
// [begin, min(end, nz-1)); its local vertex ids continue into plane `end`. So its device
// buffers hold sample planes [begin-1, end+2) (clamped): one plane below and two above for
// the gradients at the chunk's faces and the crossed edges of plane `end`.
//
// Where the device shares host memory (PoCL, integrated GPUs) nothing is copied: the kernels
// read the caller's samples and write the mesh's arrays in place (CL_MEM_USE_HOST_PTR).

#include "cl_runtime.hpp"
#include "hybrid_schedule.hpp"
#include "pinned_staging.hpp"

#include "core/cpu_engine.hpp"
#include "core/opencl_hook.hpp"
#include "core/parallel.hpp"
#include "core/scalar_dispatch.hpp"
#include "core/threshold.hpp"

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cstring>
#include <chrono>
#include <climits>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <tuple>
#include <thread>

namespace voxmesh::detail {

namespace {

using namespace cl_engine;
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Buffer slots of a device.
// Word bases (a row word's first vertex id, counted from the row's first vertex) fit 16 bits
// while the last word starts at most 65535 edges in: 3 * 32 * (words - 1) <= 65535.
constexpr std::size_t kMaxWordsFor16BitBases = 65535 / 96 + 1;  // 683 words, nx <= 21856

enum : unsigned { kData, kBits, kWordBase, kPositions, kNormals, kIndices, kCounts, kRowState };
// Piece i's row buffers (counts, then their prefix sums; word groups) in a call: kept like the
// others, so that calls after the first allocate nothing (for the first kKeptPieceRows
// pieces; more take buffers of their own). Ids above the scan's.
constexpr unsigned kPieceRows = 1000, kKeptPieceRows = 1024;
// Likewise a discrete device's resident samples and bits of piece i (above the row buffers'
// ids): allocating device memory costs a GPU about a millisecond a piece.
constexpr unsigned kPieceSamples = kPieceRows + 3 * kKeptPieceRows;

std::atomic<bool> g_pretend_no_fp64{false};  // test hook: run the float paths on fp64 devices
std::atomic<bool> g_pretend_discrete{false};  // test hook: copy in and out as for a discrete GPU
std::atomic<bool> g_pretend_gpu_build{false};  // test hook: kernels built and scans shaped as for a GPU
// Test hook: a slower device (per chunk counted, per piece generated), a slower CPU worker
// (per chunk counted, its own or taken over), a CPU worker that starts late (before its first run).
std::atomic<double> g_slow_count_s{0}, g_slow_generate_s{0}, g_slow_cpu_count_s{0}, g_slow_cpu_start_s{0};
// Test hook: every device takes its first chunk before any takes a second, and in Hybrid the
// CPU worker its first run too (the chunks are otherwise pulled, so which worker counts how
// many depends on timing).
std::atomic<bool> g_deal_first_chunks{false};

// Test hook: Hybrid always splits (no choice of the CPU engine or the device alone), for tests
// of the split's schedule.
std::atomic<bool> g_hybrid_split_only{false};

// Test hook: run by Hybrid's CPU worker before it counts a device's piece again.
std::mutex g_before_take_over_mutex;
std::function<void()> g_before_take_over;

// Test hook: run before a device's piece is generated, on the device (false) or on the CPU
// engine after it counted the piece again (true).
std::mutex g_before_generate_mutex;
std::function<void(bool)> g_before_generate;

void before_generate(bool recounted) {
    std::lock_guard<std::mutex> lock(g_before_generate_mutex);
    if (g_before_generate) g_before_generate(recounted);
}

// Sleeps `times` × the hook's seconds (a chunk count for per-chunk hooks); nothing when unset.
void pretend_slow(const std::atomic<double>& seconds, std::size_t times = 1) {
    if (const double s = seconds; s > 0)
        std::this_thread::sleep_for(std::chrono::duration<double>(s * static_cast<double>(times)));
}

// Hybrid's rates from earlier calls, per device, volume shape and settings (hybrid_schedule.hpp).
struct RatesKey {
    const Device* device;
    ScalarType type;
    bool normals;
    unsigned threads;
    std::size_t nx, ny, nz;
    bool operator<(const RatesKey& o) const {
        return std::tie(device, type, normals, threads, nx, ny, nz) <
               std::tie(o.device, o.type, o.normals, o.threads, o.nx, o.ny, o.nz);
    }
};
std::mutex g_rates_mutex;
std::map<RatesKey, HybridRates> g_rates;
HybridModeBook<RatesKey> g_modes;  // under g_rates_mutex too
constexpr std::size_t kMaxRates = 64;  // shapes remembered; the map starts over beyond that

// Seconds and samples of one side's pass in this call.
struct Measured {
    double seconds = 0, samples = 0;
    void add(double s, double n) {
        seconds += s;
        samples += n;
    }
    double per_sample(double before) const { return samples > 0 ? seconds / samples : before; }
};

// The kernels index samples with uint: a chunk's samples stay below 2^31.
constexpr std::size_t kMaxChunkSamples = std::size_t(1) << 31;

// The scans count a chunk's vertices and triangles in 32 bits (uint): whatever its surface, a
// chunk may hold at most 2^32 - 1 of either, at 3 vertices per sample of its meta rows and 5
// triangles per cell (the case table's most). Past that the totals wrapped, and the mesh came
// out with other counts than the CPU engine's, silently.
constexpr std::uint64_t kMaxChunkCount = std::numeric_limits<std::uint32_t>::max();
constexpr std::uint64_t kMaxVerticesPerSample = 3, kMaxTrianglesPerCell = 5;

// Thrown inside a worker when a chunk does not fit the device: cut it smaller.
struct TooBig {};

struct ChunkShape {
    std::size_t planes, zlo, zhi, cell_end;  // cell_end: first cell plane the chunk does not own
    std::size_t rows, owned_rows, cell_rows;  // meta rows; rows of owned sample planes; cell rows
    std::size_t words, bit_rows, bit_words;   // words per bit row; bit rows; their words
    std::size_t data_samples;
};

// One z-range meshed by one worker in two phases. Every worker first counts its ranges
// (classify + scan); once all counts are known the mesh is allocated once, at its final
// size, and every range is generated straight into it at its offsets: no range is meshed
// into a mesh of its own and copied, so the mesh exists once, however many chunks there are.
struct Piece {
    ZRange range;
    unsigned worker = 0;   // who counted it and generates it: a device job's index, or the CPU worker
    bool on_cpu = false;   // counted by the CPU engine (Hybrid's CPU worker, or a device's fallback)
    unsigned cpu_threads = 1;
    CpuChunkPlan plan;     // on_cpu: the CPU engine's classify + scan
    // On a device: the scanned per-row vertex and triangle counts and the word groups of each
    // cell row, kept on the device between the phases.
    cl::Buffer vbase, tbase, cell_groups;
    // A discrete device's own copy of the piece's samples and bits, resident between the
    // phases while they fit (empty: the device's kept kData / kBits buffers, shared in turn).
    cl::Buffer data, bits;
    bool uploaded = false;  // into `data`
    std::uint64_t all_vertices = 0;  // on a device: the range's id space, plane `end`'s vertices included
    std::uint64_t vertices = 0, triangles = 0;          // owned by the range
    std::uint64_t first_vertex = 0, first_triangle = 0;  // where they go in the mesh
};

const char* cl_type_name(ScalarType type) {
    switch (type) {
        case ScalarType::U8: return "uchar";
        case ScalarType::I8: return "char";
        case ScalarType::U16: return "ushort";
        case ScalarType::I16: return "short";
        case ScalarType::U32: return "uint";
        case ScalarType::I32: return "int";
        case ScalarType::F32: return "float";
        case ScalarType::F64: return "double";
    }
    return "float";
}

bool is_integer(ScalarType type) { return type != ScalarType::F32 && type != ScalarType::F64; }

bool same_range(ZRange a, ZRange b) { return a.end > a.begin && a.begin == b.begin && a.end == b.end; }

std::size_t round_up(std::size_t n, std::size_t m) { return (n + m - 1) / m * m; }

// Runs `enqueue` (work on d's queue) and waits for the queue. If anything throws, it still
// waits for what was enqueued before rethrowing: no kernel may go on reading or writing host
// memory (the caller's samples, the mesh) that is about to be freed.
template <class F>
void run_on_queue(Device& d, F&& enqueue) {
    try {
        enqueue();
        d.queue.finish();
    } catch (...) {
        try {
            d.queue.finish();
        } catch (const cl::Error&) {
        }
        throw;
    }
}

constexpr std::size_t kLocalSize = 256;  // work-group size of marching_cubes.cl launches, where allowed

// A device that shares host memory holds its working buffers (bits, word bases, row counts)
// in the process's memory: automatic chunks keep them within this share of the volume's
// bytes (at least kMinWorkingBytes), so that meshing stays within volume + mesh + 10 %.
// Where a device gets several chunks, generate packs a chunk's bits again (one more read of
// its samples) instead of keeping every chunk's bits.
constexpr double kHostWorkingShare = 0.07;
constexpr std::size_t kMinWorkingBytes = std::size_t{6} << 20;

// What one call needs to know about a device: how samples reach it and the kernel arguments
// that do not change from chunk to chunk.
struct DeviceJob {
    std::shared_ptr<Device> device;
    ScalarType device_type = ScalarType::F32;  // the type the kernels read
    bool fp64 = false;                         // kernels interpolate in double
    bool convert = false;                      // f64 without cl_khr_fp64: converted to f32 per chunk
    bool cpu_only = false;                     // converted, but iso is out of float range
    bool host_memory = false;                  // the mesh is written in place; buffers live in host memory
    bool zero_copy = false;                    // ... and the kernels read the caller's samples in place
    std::string options;
    std::vector<unsigned char> threshold;      // bytes of a device_type value
    std::size_t limit = 0;                     // bytes one chunk may use
    std::size_t local = kLocalSize;            // work-group size of every launch
    std::size_t word_id_bytes = 4;             // of the per-word vertex id bases (2 or 4)
    std::size_t pieces_counted = 0;            // in this call
    std::size_t fronts_taken = 0;              // single chunks take_front gave it, in this call
    bool counting_done = false;                // its count worker returned (g_deal_first_chunks)
    std::size_t resident_bytes = 0;            // of pieces' own samples and bits
    // The range whose samples / bits the kData / kBits buffers hold now (empty: none), and
    // those buffers' handles then: generate uploads or packs again only when they differ.
    ZRange data_of, bits_of;
    cl_mem data_mem = nullptr, bits_mem = nullptr;
    DeviceStats stats;
    double pass_seconds[3] = {0, 0, 0};
    // Hybrid's estimates (Engine::queue_mutex_): seconds per chunk counted, per piece generated.
    double count_chunk_s = 0, generate_piece_s = 0;
    // The pieces it counted, in z order, while generating: it takes them from the back, the CPU
    // worker may take them over from the front (Engine::queue_mutex_).
    std::vector<Piece*> to_generate;
    std::size_t generate_front = 0, generate_back = 0;
    std::size_t taken_over = 0, taken_over_voxels = 0;  // by the CPU worker
    Measured counted, generated;  // on the device, for the next call's plan
};

class Engine {
public:
    Engine(const VolumeView& volume, const Options& options, bool hybrid, Mesh storage)
        : volume_(volume), options_(options), hybrid_(hybrid), storage_(std::move(storage)) {
        nx_ = volume.dims[0];
        ny_ = volume.dims[1];
        nz_ = volume.dims[2];
        plane_ = nx_ * ny_;
        threads_ = resolve_threads(options.threads);
    }

    Mesh run(Stats& stats);

private:
    std::vector<std::shared_ptr<Device>> select_devices() const;
    void prepare(DeviceJob& job);
    ChunkShape shape(ZRange range) const;
    // A chunk of `planes` planes with the most samples (one below and two above).
    ZRange worst_range(std::size_t planes) const {
        return planes >= nz_ ? ZRange{0, nz_} : ZRange{1, std::min(1 + planes, nz_)};
    }
    std::size_t working_bytes(const DeviceJob& job, const ChunkShape& s) const;
    std::size_t fixed_bytes(const DeviceJob& job, const ChunkShape& s) const;
    bool fits(const DeviceJob& job, const ChunkShape& s) const;
    bool counts_fit(const ChunkShape& s) const {
        return std::uint64_t{s.rows} * nx_ * kMaxVerticesPerSample <= kMaxChunkCount &&
               std::uint64_t{s.cell_rows} * (nx_ - 1) * kMaxTrianglesPerCell <= kMaxChunkCount;
    }
    std::vector<ZRange> make_chunks(const std::vector<DeviceJob>& jobs) const;
    // Phase 1: count.
    void device_count_worker(DeviceJob& job, unsigned worker);
    bool take_front(DeviceJob& job, std::size_t& first, std::size_t& count);
    // Planes and samples of a chunk (all but the last have the first's size).
    std::size_t chunk_planes() const { return chunks_.front().end - chunks_.front().begin; }
    double chunk_samples() const { return static_cast<double>(chunk_planes() * plane_); }
    // Chunks a piece covers (a run of them, or 1 for part of one).
    std::size_t chunks_in(ZRange r) const {
        return std::max<std::size_t>(1, (r.end - r.begin + chunk_planes() / 2) / chunk_planes());
    }
    // Chunks whose first plane a piece holds, for the stats: the halves of a chunk split to fit
    // a device count it once between them (each counted as a chunk before).
    std::size_t chunks_starting_in(ZRange r) const {
        const std::size_t p = chunk_planes();
        return (r.end + p - 1) / p - (r.begin + p - 1) / p;
    }
    enum class Take { Run, Later, Done };  // a run of chunks; none yet, ask again; none left
    Take take_back(std::size_t& first, std::size_t& count);
    void count(DeviceJob& job, unsigned worker, ZRange range, std::vector<Piece>& out);
    void count_on_device(DeviceJob& job, Piece& piece);
    Piece count_on_cpu(ZRange range, unsigned worker, unsigned threads);
    void cpu_count_worker(unsigned worker);
    // Phase 2: generate into the mesh.
    void generate_pieces(std::vector<DeviceJob>& jobs, unsigned worker, Mesh& mesh);
    void cpu_generate_worker(std::vector<DeviceJob>& jobs, unsigned worker, Mesh& mesh);
    Piece* take_over(std::vector<DeviceJob>& jobs, DeviceJob*& from, bool& wait);
    void generate_counted_on_cpu(const Piece& counted, unsigned worker, unsigned threads, Mesh& mesh);
    void generate_on_device(DeviceJob& job, Piece& piece, Mesh& mesh);
    void generate_on_cpu(Piece& piece, Mesh& mesh);
    cl::Buffer samples_on_device(DeviceJob& job, Piece& piece, const ChunkShape& s, EventLog& log);
    cl::Buffer& bits_of(DeviceJob& job, Piece& piece, const ChunkShape& s);
    void recover_from_out_of_memory(DeviceJob& job, const cl::Error& e);
    void launch(DeviceJob& job, cl::Kernel& k, std::size_t n, Pass pass, EventLog& log);
    void add_times(DeviceJob& job, const EventLog& log);
    void warn(const std::string& message);
    // Host threads copying to and from a discrete device: the call's; in Hybrid, where those
    // run the CPU worker, the cores it leaves (at least two).
    unsigned copy_threads() const {
        const unsigned cores = resolve_threads(0);
        return hybrid_ ? std::max(2u, cores > threads_ ? cores - threads_ : 0u) : threads_;
    }

    const VolumeView& volume_;
    const Options& options_;
    bool hybrid_;
    Mesh storage_;  // the caller's arrays for the mesh to reuse
    std::size_t nx_, ny_, nz_, plane_;
    unsigned threads_;

    std::vector<ZRange> chunks_;
    std::vector<std::vector<Piece>> results_;  // per chunk, its pieces in z order
    std::atomic<bool> abort_{false};
    // Chunks not taken yet: [lo_, hi_). Devices take from the front, Hybrid's CPU worker runs
    // of chunks from the back (hybrid_schedule.hpp); the estimates beside them, in seconds.
    std::mutex queue_mutex_;
    std::condition_variable dealt_;  // a worker took its first chunk or run (g_deal_first_chunks)
    bool cpu_took_ = false;          // Hybrid's CPU worker has taken a run
    std::size_t lo_ = 0, hi_ = 0;
    std::vector<DeviceJob>* jobs_ = nullptr;
    double cpu_count_chunk_s_ = 0;  // the CPU worker's latest run, per chunk
    Clock::time_point cpu_free_at_{};
    // Hybrid with one device and rates from an earlier call: the device's planned chunks, how
    // many it has taken, whether the CPU worker has taken its planned run.
    static constexpr std::size_t kNoPlan = std::numeric_limits<std::size_t>::max();
    std::size_t planned_device_chunks_ = kNoPlan, device_taken_ = 0;
    bool cpu_run_planned_taken_ = false;
    bool cpu_waiting_ = false;      // the CPU worker is done with its run and waits to mend the plan
    bool device_declined_ = false;  // the device left its last planned chunks to the CPU worker
    // Mending a plan: whether the device, at its measured pace, needs longer to count the
    // `device_left` planned chunks it has not taken than the CPU worker to count and generate one.
    bool device_behind(std::size_t device_left) const;
    void cpu_took();  // under queue_mutex_: the CPU worker took a run (wakes dealt_ waiters)
    HybridRates rates_;  // the earlier call's (planned) or none
    Measured cpu_counted_, cpu_generated_;
    Measured cpu_taken_over_;  // the CPU worker's pieces taken over from devices: counted again and generated
    void plan_hybrid(const std::vector<DeviceJob>& jobs);
    void remember_rates(const std::vector<DeviceJob>& jobs);
    RatesKey rates_key(const Device* device) const {
        return RatesKey{device, volume_.type, options_.normals, threads_, nx_, ny_, nz_};
    }
    RatesKey rates_key(const DeviceJob& job) const { return rates_key(job.device.get()); }
    // Hybrid with one device and automatic chunks: which mode this call runs, and what it took.
    bool chooses_mode(const std::vector<std::shared_ptr<Device>>& chosen) const {
        return hybrid_ && chosen.size() == 1 && options_.chunk_planes == 0 && !g_hybrid_split_only;
    }
    HybridMode choose_mode(const RatesKey& key) const;
    void record_mode(const RatesKey& key, HybridMode mode, double seconds, std::uint64_t triangles, bool settled) const;
    std::mutex mutex_;  // warnings_, fallback_ stats
    std::vector<std::string> warnings_;
    DeviceStats cpu_stats_, fallback_stats_;
    double cpu_pass_seconds_[3] = {0, 0, 0};
};

void Engine::warn(const std::string& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (std::find(warnings_.begin(), warnings_.end(), message) == warnings_.end()) warnings_.push_back(message);
}

std::vector<std::shared_ptr<Device>> Engine::select_devices() const {
    const auto all = cl_engine::devices();
    std::vector<std::shared_ptr<Device>> chosen;
    if (!options_.devices.empty()) {
        std::set<int> seen;
        for (int index : options_.devices) {
            if (index < 0 || static_cast<std::size_t>(index) >= all.size())
                throw Error("OpenCL device index " + std::to_string(index) + " does not exist; list_devices() has " +
                            std::to_string(all.size()) + " device(s)");
            if (seen.insert(index).second) chosen.push_back(all[static_cast<std::size_t>(index)]);
        }
        return chosen;
    }
    for (const auto& d : all)
        if (options_.device_type == DeviceType::Any || d->info.type == options_.device_type) chosen.push_back(d);
    // Hybrid already runs the CPU engine on every core; an OpenCL device that is this same
    // CPU (PoCL) would only take cores from it, and does less with them, so it joins only
    // when asked for by index or by type.
    if (hybrid_ && options_.device_type == DeviceType::Any)
        chosen.erase(std::remove_if(chosen.begin(), chosen.end(),
                                    [](const auto& d) { return d->info.type == DeviceType::Cpu; }),
                     chosen.end());
    return chosen;
}

// The caller holds the device's mutex (run() holds every selected device's for the call).
void Engine::prepare(DeviceJob& job) {
    const DeviceInfo& info = job.device->info;
    job.stats.name = info.name;
    job.fp64 = info.fp64 && !g_pretend_no_fp64;
    job.convert = volume_.type == ScalarType::F64 && !job.fp64;
    job.device_type = job.convert ? ScalarType::F32 : volume_.type;
    job.host_memory = info.host_memory && !g_pretend_discrete;
    job.zero_copy = job.host_memory && !job.convert;
    job.options = std::string("-cl-std=CL1.2 -DVOXEL_T=") + cl_type_name(job.device_type);
    if (is_integer(job.device_type)) job.options += " -DVOXEL_INTEGER";
    if (job.device_type == ScalarType::F64) job.options += " -DVOXEL_DOUBLE";
    if (job.device->info.type == DeviceType::Cpu && !g_pretend_gpu_build) job.options += " -DCPU_PREFETCH";
    job.word_id_bytes = (nx_ + 31) / 32 <= kMaxWordsFor16BitBases ? 2 : 4;
    job.options += job.word_id_bytes == 2 ? " -Dword_id=ushort" : " -Dword_id=uint";
    if (job.fp64) job.options += " -DUSE_FP64";
    dispatch_scalar(job.device_type, [&](auto tag) {
        using T = decltype(tag);
        const Threshold<T> t = make_threshold<T>(options_.iso);
        if (t.uniform != Uniform::Mixed) job.cpu_only = true;  // only reachable for converted f64
        job.threshold.resize(sizeof(T));
        std::memcpy(job.threshold.data(), &t.value, sizeof(T));
    });
    if (job.cpu_only)
        warn("OpenCL device '" + info.name + "' has no fp64 and iso " + std::to_string(options_.iso) +
             " is outside the float range; its chunks run on the CPU engine");
    // The kernels take nz and a chunk's first plane as 32-bit (nx and ny are bounded by a chunk's
    // 2^31 samples). Not reachable in practice (the CPU engine's row state alone is 130 GB).
    if (nz_ > std::numeric_limits<cl_uint>::max() && !job.cpu_only) {
        job.cpu_only = true;
        warn("the volume has more z-planes than OpenCL device '" + info.name +
             "' is given in 32 bits; its chunks run on the CPU engine");
    }
    std::size_t limit = info.global_memory / 2;
    if (options_.memory_budget > 0) limit = std::min(limit, options_.memory_budget);
    job.limit = limit;
    // Build now, in the caller's thread, so that a build failure surfaces at once. Programs
    // are cached per device and options: only the first call pays for them.
    const auto t0 = Clock::now();
    const std::size_t built = job.device->programs_built;
    for (const char* name :
         {"classify_pack", "classify_rows", "classify_repack", "generate_vertices", "generate_triangles"}) {
        const std::size_t most =
            job.device->mc_kernel(job.options, name).getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(job.device->device);
        while (job.local > most && job.local > 1) job.local /= 2;
    }
    job.device->scan_shape();
    job.stats.programs_built = job.device->programs_built - built;
    job.stats.setup_s = seconds_since(t0);
}

// The index spaces of a chunk (kernels/marching_cubes.cl): sample planes [zlo, zhi) reach
// the device, bit rows cover planes [begin, zhi), the scans run over the meta rows.
ChunkShape Engine::shape(ZRange range) const {
    ChunkShape s;
    s.planes = range.end - range.begin;
    s.zlo = range.begin > 0 ? range.begin - 1 : 0;
    s.zhi = std::min(range.end + 2, nz_);
    s.cell_end = std::min(range.end, nz_ - 1);
    s.rows = (std::min(range.end + 1, nz_) - range.begin) * ny_;
    s.owned_rows = s.planes * ny_;
    s.cell_rows = (s.cell_end > range.begin ? s.cell_end - range.begin : 0) * ny_;
    s.words = (nx_ + 31) / 32;
    s.bit_rows = (s.zhi - range.begin) * ny_;
    s.bit_words = s.bit_rows * s.words;
    s.data_samples = (s.zhi - s.zlo) * plane_;
    return s;
}

// Device bytes of a chunk besides its samples and outputs: bits, a vertex id per row word,
// two counts and a word-group mask per row (+ the scan's block sums).
std::size_t Engine::working_bytes(const DeviceJob& job, const ChunkShape& s) const {
    return s.bit_words * 4 + s.bit_rows + s.rows * s.words * job.word_id_bytes + s.rows * 16 + s.rows / 128 + 64;
}

// Device bytes of a chunk, outputs excluded.
std::size_t Engine::fixed_bytes(const DeviceJob& job, const ChunkShape& s) const {
    return s.data_samples * scalar_size(job.device_type) + working_bytes(job, s);
}

// Whether a chunk can fit the device before its outputs are known: the fixed part must
// leave at least as much again for vertices and triangles.
bool Engine::fits(const DeviceJob& job, const ChunkShape& s) const {
    const std::size_t max_allocation = job.device->info.max_allocation;
    return s.data_samples <= kMaxChunkSamples && counts_fit(s) &&
           s.data_samples * scalar_size(job.device_type) <= max_allocation &&
           s.bit_words * 4 <= max_allocation && s.rows * s.words * job.word_id_bytes <= max_allocation &&
           2 * fixed_bytes(job, s) <= job.limit;
}

std::vector<ZRange> Engine::make_chunks(const std::vector<DeviceJob>& jobs) const {
    std::size_t planes = nz_;
    if (options_.chunk_planes > 0) {
        planes = options_.chunk_planes;
    } else {
        // Largest chunk every device can take (a device in host memory: within its share of
        // the volume's bytes); with several workers, about four chunks each so that faster
        // workers pull more. Chunks of about equal size.
        const std::size_t volume_bytes = nx_ * ny_ * nz_ * scalar_size(volume_.type);
        const std::size_t host_working = std::max(
            kMinWorkingBytes, static_cast<std::size_t>(kHostWorkingShare * static_cast<double>(volume_bytes)));
        for (const DeviceJob& job : jobs) {
            const auto ok = [&](std::size_t n) {
                const ChunkShape s = shape(worst_range(n));
                return fits(job, s) && (!job.host_memory || working_bytes(job, s) <= host_working);
            };
            std::size_t lo = 1, hi = nz_;
            while (lo < hi) {
                const std::size_t mid = (lo + hi + 1) / 2;
                if (ok(mid)) lo = mid; else hi = mid - 1;
            }
            planes = std::min(planes, lo);
        }
        const std::size_t workers = jobs.size() + (hybrid_ ? 1 : 0);
        if (hybrid_) {
            // Many small chunks, so that a device's last one ends close to the CPU worker's
            // last run (which takes many chunks at once): about 64, of at least 2^20 samples
            // where that still leaves 8.
            const std::size_t enough = (std::size_t{1} << 20) / std::max<std::size_t>(plane_, 1) + 1;
            planes = std::min({planes, std::max((nz_ + 63) / 64, enough), (nz_ + 7) / 8});
        } else if (workers > 1) {
            planes = std::min(planes, std::max<std::size_t>(1, (nz_ + 4 * workers - 1) / (4 * workers)));
        }
        const std::size_t count = (nz_ + planes - 1) / planes;
        planes = (nz_ + count - 1) / count;
    }
    planes = std::max<std::size_t>(planes, 1);
    std::vector<ZRange> chunks;
    for (std::size_t z = 0; z < nz_; z += planes) chunks.push_back(ZRange{z, std::min(z + planes, nz_)});
    return chunks;
}

bool Engine::take_front(DeviceJob& job, std::size_t& first, std::size_t& count) {
    std::unique_lock<std::mutex> lock(queue_mutex_);
    if (g_deal_first_chunks && job.fronts_taken > 0) {
        // Until every device has taken a chunk (or stopped taking) and the CPU worker a run.
        // The queue can also empty, or a worker fail, without a notify: the wait looks again
        // every millisecond, and a worker that failed before taking a chunk must not hang the
        // others: a time limit.
        const auto dealt = [&] {
            return abort_ || lo_ >= hi_ ||
                   (std::all_of(jobs_->begin(), jobs_->end(),
                                [](const DeviceJob& j) { return j.fronts_taken > 0 || j.counting_done; }) &&
                    (!hybrid_ || cpu_took_));
        };
        const auto until = Clock::now() + std::chrono::seconds(10);
        while (!dealt() && Clock::now() < until) dealt_.wait_for(lock, std::chrono::milliseconds(1));
    }
    if (abort_ || lo_ >= hi_) return false;
    first = lo_;
    count = 1;
    if (planned_device_chunks_ != kNoPlan) {
        // Its planned chunks, no more: three quarters of those left at a time, as one piece (a
        // piece costs a discrete GPU a fraction of a millisecond whatever its size), so that
        // the CPU worker can still take the last ones should the device fall behind.
        const std::size_t left = std::min(hi_ - lo_, planned_device_chunks_ - std::min(device_taken_, planned_device_chunks_));
        if (left == 0) return false;
        if (cpu_waiting_ && job.count_chunk_s > 0 && device_behind(left)) {  // the idle CPU is quicker
            device_declined_ = true;
            return false;
        }
        count = std::max<std::size_t>(1, left * 3 / 4);
        device_taken_ += count;
        lo_ += count;
        return true;
    }
    if (hybrid_) {
        const double cpu_busy_s = std::chrono::duration<double>(cpu_free_at_ - Clock::now()).count();
        if (!hybrid_device_takes(job.count_chunk_s, cpu_count_chunk_s_, cpu_busy_s, hi_ - lo_)) return false;
    }
    lo_ += 1;
    if (++job.fronts_taken == 1) dealt_.notify_all();
    return true;
}

bool Engine::device_behind(std::size_t device_left) const {
    const double device_s = jobs_->front().count_chunk_s > 0 ? jobs_->front().count_chunk_s
                                                             : rates_.device_count * chunk_samples();
    const double cpu_s = (cpu_count_chunk_s_ > 0 ? cpu_count_chunk_s_ : rates_.cpu_count * chunk_samples()) +
                         rates_.cpu_generate * chunk_samples();
    return static_cast<double>(device_left) * device_s > cpu_s;
}

Engine::Take Engine::take_back(std::size_t& first, std::size_t& count) {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (abort_ || lo_ >= hi_) return Take::Done;
    if (planned_device_chunks_ != kNoPlan) {
        const std::size_t left = hi_ - lo_, device_left = std::min(left, planned_device_chunks_ - device_taken_);
        if (!cpu_run_planned_taken_) {  // everything the plan leaves the device, in one run
            cpu_run_planned_taken_ = true;
            count = left - device_left;
        } else if (device_declined_) {
            count = left;
        } else {  // mending the plan: one of the device's chunks at a time while it is behind
            count = device_behind(device_left) ? 1 : 0;
        }
        cpu_waiting_ = count == 0 && device_left > 0;
        if (count == 0) return cpu_waiting_ ? Take::Later : Take::Done;
        hi_ -= count;
        first = hi_;
        cpu_took();
        return Take::Run;
    }
    double device_rate = 0;
    for (const DeviceJob& job : *jobs_)
        if (job.count_chunk_s > 0) device_rate += 1.0 / job.count_chunk_s;
    count = hybrid_cpu_run(hi_ - lo_, cpu_count_chunk_s_, device_rate);
    hi_ -= count;
    first = hi_;
    cpu_free_at_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(cpu_count_chunk_s_ * static_cast<double>(count)));
    cpu_took();
    return Take::Run;
}

void Engine::cpu_took() {
    if (!cpu_took_) {
        cpu_took_ = true;
        dealt_.notify_all();
    }
}

// Hybrid with one device: where an earlier call on this device and volume shape measured
// both sides, the split comes from those rates (hybrid_device_chunks).
void Engine::plan_hybrid(const std::vector<DeviceJob>& jobs) {
    if (!hybrid_ || jobs.size() != 1 || options_.chunk_planes > 0 || chunks_.empty()) return;
    {
        std::lock_guard<std::mutex> lock(g_rates_mutex);
        const auto it = g_rates.find(rates_key(jobs.front()));
        if (it == g_rates.end() || !it->second.known()) return;
        rates_ = it->second;
    }
    planned_device_chunks_ = hybrid_device_chunks(chunks_.size(), chunk_samples(), rates_);
}

HybridMode Engine::choose_mode(const RatesKey& key) const {
    std::lock_guard<std::mutex> lock(g_rates_mutex);
    return g_modes.choose(key, volume_.data);
}

void Engine::record_mode(const RatesKey& key, HybridMode mode, double seconds, std::uint64_t triangles,
                         bool settled) const {
    std::lock_guard<std::mutex> lock(g_rates_mutex);
    g_modes.record(key, volume_.data, mode, seconds, triangles, settled);
}

// This call's rates, for the next call's plan; a side that did no work in a pass keeps the
// earlier call's rate for it, made more hopeful (hybrid_hope_for_idle).
void Engine::remember_rates(const std::vector<DeviceJob>& jobs) {
    if (!hybrid_ || jobs.size() != 1 || options_.chunk_planes > 0) return;
    const DeviceJob& job = jobs.front();
    std::lock_guard<std::mutex> lock(g_rates_mutex);
    HybridRates& r = g_rates[rates_key(job)];
    if (planned_device_chunks_ == kNoPlan) r = rates_;
    r.cpu_count = cpu_counted_.per_sample(r.cpu_count);
    r.cpu_generate = cpu_generated_.per_sample(r.cpu_generate);
    r.device_count = job.counted.per_sample(r.device_count);
    r.device_generate = job.generated.per_sample(r.device_generate);
    hybrid_hope_for_idle(r, cpu_counted_.samples > 0, job.counted.samples > 0);
    if (g_rates.size() > kMaxRates) {
        const HybridRates keep = r;
        g_rates.clear();
        g_rates[rates_key(job)] = keep;
    }
}

void Engine::launch(DeviceJob& job, cl::Kernel& k, std::size_t n, Pass pass, EventLog& log) {
    // Fixed work-group size: PoCL compiles a kernel once per local size it is launched with.
    job.device->queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(round_up(n, job.local)),
                                           cl::NDRange(job.local), nullptr, &log.add(pass));
}

void Engine::add_times(DeviceJob& job, const EventLog& log) {
    for (const auto& [pass, event] : log.events) {
        const double s = event_seconds(event);
        if (pass == Pass::Transfer) {
            job.stats.transfer_s += s;
        } else {
            job.stats.kernel_s += s;
            job.pass_seconds[static_cast<int>(pass)] += s;
        }
    }
}

// The piece's sample planes on the device: the caller's samples in place where the device
// shares host memory, else uploaded (or converted from f64 keeping every inside bit) into
// its own buffer or the kData buffer, unless that holds them already.
cl::Buffer Engine::samples_on_device(DeviceJob& job, Piece& piece, const ChunkShape& s, EventLog& log) {
    Device& d = *job.device;
    const std::size_t sample_bytes = scalar_size(job.device_type);
    const auto* bytes = static_cast<const unsigned char*>(volume_.data) + s.zlo * plane_ * scalar_size(volume_.type);
    if (job.zero_copy)  // read only: the kernels never write it
        return cl::Buffer(d.context, CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, s.data_samples * sample_bytes,
                          const_cast<unsigned char*>(bytes));
    const bool own = piece.data() != nullptr;
    cl::Buffer& data = own ? piece.data : d.buffer(kData, s.data_samples * sample_bytes);
    if (own ? piece.uploaded : same_range(job.data_of, piece.range) && job.data_mem == data()) return data;
    std::vector<float> converted;
    if (job.convert) {
        const double* src = reinterpret_cast<const double*>(bytes);
        float thr;
        std::memcpy(&thr, job.threshold.data(), sizeof(thr));
        converted.resize(s.data_samples);
        for (std::size_t i = 0; i < s.data_samples; ++i) {
            const double v = src[i];
            float f = static_cast<float>(std::clamp(v, -static_cast<double>(FLT_MAX), static_cast<double>(FLT_MAX)));
            if (!std::isfinite(v)) f = std::numeric_limits<float>::quiet_NaN();  // refused in the kernel
            else if (v >= options_.iso && !(f >= thr)) f = thr;
            else if (v < options_.iso && f >= thr) f = std::nextafter(thr, -std::numeric_limits<float>::infinity());
            converted[i] = f;
        }
        bytes = reinterpret_cast<const unsigned char*>(converted.data());
    }
    if (!job.host_memory) {  // through pinned blocks: returns once `bytes` may be freed
        d.staging().upload(data, 0, bytes, s.data_samples * sample_bytes, copy_threads(), log);
    } else {
        // Blocking when converted: `converted` is freed on return.
        d.queue.enqueueWriteBuffer(data, job.convert ? CL_TRUE : CL_FALSE, 0, s.data_samples * sample_bytes, bytes,
                                   nullptr, &log.add(Pass::Transfer));
    }
    if (own) {
        piece.uploaded = true;
    } else {
        job.data_of = piece.range;
        job.data_mem = data();
    }
    return data;
}

// The buffer for the piece's inside bits: its own, or the kBits buffer.
cl::Buffer& Engine::bits_of(DeviceJob& job, Piece& piece, const ChunkShape& s) {
    return piece.bits() != nullptr ? piece.bits : job.device->buffer(kBits, s.bit_words * 4);
}

void Engine::count_on_device(DeviceJob& job, Piece& piece) {
    Device& d = *job.device;
    const ZRange range = piece.range;
    const ChunkShape s = shape(range);
    const DeviceInfo& info = d.info;
    if (!fits(job, s)) {
        if (s.planes > 1) throw TooBig{};
        if (s.data_samples > kMaxChunkSamples || !counts_fit(s) ||
            s.data_samples * scalar_size(job.device_type) > info.max_allocation ||
            fixed_bytes(job, s) > job.limit)
            throw TooBig{};
    }
    const auto u = [](std::size_t v) { return static_cast<cl_uint>(v); };
    pretend_slow(g_slow_count_s);
    EventLog log;
    run_on_queue(d, [&] {
        // This piece's buffer in slot `slot` of the device, kept for the next call (the first
        // kKeptPieceRows pieces), or its own.
        const auto piece_buffer = [&](std::size_t slot, std::size_t bytes) {
            if (job.pieces_counted >= kKeptPieceRows) return cl::Buffer(d.context, CL_MEM_READ_WRITE, bytes);
            return d.buffer(static_cast<unsigned>(slot), bytes);
        };
        // A discrete device keeps further pieces' samples and bits in buffers of their own
        // while they fit half its budget, so generate neither uploads nor packs them again.
        const std::size_t own_bytes = s.data_samples * scalar_size(job.device_type) + s.bit_words * 4;
        if (!job.host_memory && job.pieces_counted > 0 && job.resident_bytes + own_bytes <= job.limit / 2) {
            const std::size_t slot = kPieceSamples + 2 * job.pieces_counted;
            piece.data = piece_buffer(slot, s.data_samples * scalar_size(job.device_type));
            piece.bits = piece_buffer(slot + 1, s.bit_words * 4);
        }
        const cl::Buffer data = samples_on_device(job, piece, s, log);
        cl::Buffer& bits = bits_of(job, piece, s);
        // What the host needs back, read at once after the scans: the first z-plane with a NaN
        // (INT_MAX: none; classify_pack's nan_plane), the vertex and triangle totals, and plane
        // `end`'s first vertex.
        enum { kNanPlane, kVertexTotal, kTriangleTotal, kEndPlaneVertex, kCountWords };
        cl::Buffer& counts = d.buffer(kCounts, kCountWords * sizeof(cl_uint));
        const cl_int no_nan = INT_MAX;
        d.queue.enqueueFillBuffer(counts, no_nan, kNanPlane * sizeof(cl_int), sizeof(cl_int), nullptr,
                                  &log.add(Pass::Transfer));
        const std::size_t first_sample = (range.begin - s.zlo) * plane_;  // of plane `begin` in the device's samples
        // Each bit row's kind (all outside, all inside, both) for classify_rows, this piece only.
        cl::Buffer& row_state = d.buffer(kRowState, s.bit_rows);
        cl::Kernel& pack = d.mc_kernel(job.options, "classify_pack");
        set_args(pack, data, ArgBytes{job.threshold}, u(nx_), u(ny_), u(s.words), u(range.begin), u(first_sample),
                 u(s.bit_rows), bits, row_state, counts);
        launch(job, pack, s.bit_rows, Pass::Classify, log);
        if (piece.bits() == nullptr) {
            job.bits_of = range;
            job.bits_mem = bits();
        }
        // Per row: counts, then their prefix sums; per cell row: word groups to visit.
        const std::size_t rows_slot = kPieceRows + 3 * job.pieces_counted;
        piece.vbase = piece_buffer(rows_slot, s.rows * 4);
        piece.tbase = piece_buffer(rows_slot + 1, s.rows * 4);
        piece.cell_groups = piece_buffer(rows_slot + 2, s.rows * 8);
        job.pieces_counted += 1;
        cl::Kernel& rows = d.mc_kernel(job.options, "classify_rows");
        set_args(rows, bits, row_state, u(nx_), u(ny_), u(nz_), u(s.words), u(range.begin),
                 u(s.cell_end), u(s.rows), d.pair_corners, piece.vbase, piece.tbase, piece.cell_groups);
        launch(job, rows, s.rows, Pass::Classify, log);

        scan_into(d, piece.vbase, s.rows, counts, kVertexTotal, log, g_pretend_gpu_build);
        scan_into(d, piece.tbase, s.rows, counts, kTriangleTotal, log, g_pretend_gpu_build);
        if (s.owned_rows < s.rows)  // plane `end`'s first vertex id: its first row's base
            d.queue.enqueueCopyBuffer(piece.vbase, counts, s.owned_rows * sizeof(cl_uint),
                                      kEndPlaneVertex * sizeof(cl_uint), sizeof(cl_uint), nullptr,
                                      &log.add(Pass::Transfer));
        cl_uint got[kCountWords] = {};
        d.queue.enqueueReadBuffer(counts, CL_TRUE, 0, sizeof(got), got, nullptr, &log.add(Pass::Transfer));
        piece.all_vertices = got[kVertexTotal];
        piece.triangles = got[kTriangleTotal];
        const auto nan_plane = static_cast<cl_int>(got[kNanPlane]);
        if (nan_plane != INT_MAX) throw_non_finite(static_cast<std::size_t>(nan_plane));
        if (piece.all_vertices > std::numeric_limits<std::uint32_t>::max() ||
            piece.triangles > std::numeric_limits<std::uint32_t>::max())
            throw TooBig{};
        piece.vertices = s.owned_rows < s.rows ? got[kEndPlaneVertex] : piece.all_vertices;
        // Outputs in device memory, sized by the scan totals, must fit beside the rest.
        const std::size_t out_bytes = piece.vertices * (12 + (options_.normals ? 12 : 0)) + piece.triangles * 12;
        if (!job.host_memory && (piece.vertices * 12 > info.max_allocation || piece.triangles * 12 > info.max_allocation ||
                                 fixed_bytes(job, s) + out_bytes > job.limit)) {
            if (s.planes > 1) throw TooBig{};
        }
        if (piece.data() != nullptr) job.resident_bytes += own_bytes;
    });
    add_times(job, log);
}

Piece Engine::count_on_cpu(ZRange range, unsigned worker, unsigned threads) {
    Piece piece;
    piece.range = range;
    piece.worker = worker;
    piece.on_cpu = true;
    piece.cpu_threads = threads;
    piece.plan = cpu_classify(volume_, options_, range, threads);
    piece.vertices = piece.plan.vertices;
    piece.triangles = piece.plan.triangles;
    return piece;
}

// An OpenCL error other than running out of memory ends the call; out of memory frees the
// device's kept buffers (and forgets what they held) so that the caller can go smaller.
void Engine::recover_from_out_of_memory(DeviceJob& job, const cl::Error& e) {
    if (!is_out_of_memory(e.err()))
        throw Error("OpenCL error on device '" + job.device->info.name + "' in " + e.what() + ": " +
                    error_name(e.err()));
    job.device->drop_buffers();
    job.bits_of = job.data_of = ZRange{};
}

void Engine::count(DeviceJob& job, unsigned worker, ZRange range, std::vector<Piece>& out) {
    const std::size_t planes = range.end - range.begin;
    if (!job.cpu_only) {
        bool too_big = false;
        try {
            Piece piece;
            piece.range = range;
            piece.worker = worker;
            count_on_device(job, piece);
            out.push_back(std::move(piece));
            job.stats.chunks += chunks_starting_in(range);
            job.stats.voxels += planes * plane_;
            return;
        } catch (const TooBig&) {
            too_big = true;
        } catch (const cl::Error& e) {
            recover_from_out_of_memory(job, e);
            too_big = true;
        }
        if (too_big && planes > 1) {
            warn("a " + std::to_string(planes) + "-plane chunk does not fit OpenCL device '" + job.device->info.name +
                 "' (out of memory, max allocation, memory budget or 32-bit counts); using smaller chunks");
            const ZRange a{range.begin, range.begin + planes / 2}, b{range.begin + planes / 2, range.end};
            count(job, worker, a, out);
            count(job, worker, b, out);
            return;
        }
        // A plane of more than ~716 M samples may hold more vertices than the scans' 32-bit
        // counts: say so, not memory (the device may have plenty).
        const bool counts = !counts_fit(shape(range));
        warn("OpenCL device '" + job.device->info.name + "' cannot hold even one z-plane of this volume within " +
             (counts ? "the kernels' 32-bit vertex and triangle counts" : "its memory limits") +
             "; those chunks run on the CPU engine");
    }
    const auto t0 = Clock::now();
    out.push_back(count_on_cpu(range, worker, 1));
    std::lock_guard<std::mutex> lock(mutex_);
    fallback_stats_.chunks += chunks_starting_in(range);
    fallback_stats_.voxels += planes * plane_;
    fallback_stats_.wall_s += seconds_since(t0);
}

void Engine::device_count_worker(DeviceJob& job, unsigned worker) {
    const auto t0 = Clock::now();
    std::size_t first = 0, n = 0;
    while (take_front(job, first, n)) {
        const ZRange range{chunks_[first].begin, chunks_[first + n - 1].end};
        const auto t = Clock::now();
        count(job, worker, range, results_[first]);
        const double s = seconds_since(t);
        std::lock_guard<std::mutex> lock(queue_mutex_);
        job.count_chunk_s = s / static_cast<double>(n);  // the latest: the first also pays for set-up
        job.counted.add(s, static_cast<double>((range.end - range.begin) * plane_));
    }
    {
        std::lock_guard<std::mutex> lock(queue_mutex_);
        job.counting_done = true;
    }
    dealt_.notify_all();
    job.stats.wall_s += seconds_since(t0);
}

// Hybrid's CPU worker: runs of chunks from the back, each one piece meshed by all its threads
// (kept with the run's first chunk; the others stay empty, so pieces remain in z order).
void Engine::cpu_count_worker(unsigned worker) {
    const auto t0 = Clock::now();
    std::size_t first = 0, n = 0;
    pretend_slow(g_slow_cpu_start_s);
    for (Take take; (take = take_back(first, n)) != Take::Done;) {
        if (take == Take::Later) {
            std::this_thread::sleep_for(std::chrono::microseconds(50));
            continue;
        }
        const ZRange range{chunks_[first].begin, chunks_[first + n - 1].end};
        const auto t = Clock::now();
        results_[first].push_back(count_on_cpu(range, worker, threads_));
        pretend_slow(g_slow_cpu_count_s, n);
        const double s = seconds_since(t);
        cpu_pass_seconds_[0] += s;
        cpu_stats_.chunks += n;
        cpu_stats_.voxels += (range.end - range.begin) * plane_;
        std::lock_guard<std::mutex> lock(queue_mutex_);
        cpu_count_chunk_s_ = s / static_cast<double>(n);
        cpu_counted_.add(s, static_cast<double>((range.end - range.begin) * plane_));
    }
    cpu_stats_.wall_s += seconds_since(t0);
}

void Engine::generate_on_cpu(Piece& piece, Mesh& mesh) {
    cpu_generate(piece.plan, volume_, options_, piece.cpu_threads,
                 MeshOut{mesh.positions.data() + 3 * piece.first_vertex,
                         options_.normals ? mesh.normals.data() + 3 * piece.first_vertex : nullptr,
                         mesh.indices.data() + 3 * piece.first_triangle,
                         static_cast<std::uint32_t>(piece.first_vertex)});
    piece.plan = CpuChunkPlan{};  // its rows and kept bits are not needed any more
}

void Engine::generate_on_device(DeviceJob& job, Piece& piece, Mesh& mesh) {
    Device& d = *job.device;
    const ChunkShape s = shape(piece.range);
    const auto u = [](std::size_t v) { return static_cast<cl_uint>(v); };
    pretend_slow(g_slow_generate_s);
    before_generate(false);
    EventLog log;
    run_on_queue(d, [&] {
        const cl::Buffer data = samples_on_device(job, piece, s, log);
        cl::Buffer& bits = bits_of(job, piece, s);
        const std::size_t first_sample = (piece.range.begin - s.zlo) * plane_;
        if (piece.bits() == nullptr && (!same_range(job.bits_of, piece.range) || job.bits_mem != bits())) {
            // Packed again, but rows without crossings are filled, not read (classify_repack).
            cl::Kernel& k = d.mc_kernel(job.options, "classify_repack");
            set_args(k, data, ArgBytes{job.threshold}, u(nx_), u(s.words), u(first_sample), u(s.bit_rows), u(s.rows),
                     u(piece.all_vertices), piece.vbase, bits);
            launch(job, k, s.bit_rows, Pass::Classify, log);
            job.bits_of = piece.range;
            job.bits_mem = bits();
        }
        // Where the device shares host memory, the kernels write the mesh where it stays.
        const auto output = [&](unsigned slot, auto* host, std::size_t bytes) -> cl::Buffer {
            if (job.host_memory) return cl::Buffer(d.context, CL_MEM_WRITE_ONLY | CL_MEM_USE_HOST_PTR, bytes, host);
            return d.buffer(slot, bytes);
        };
        const auto fetch = [&](const cl::Buffer& buffer, auto* host, std::size_t bytes) {
            if (job.host_memory) {  // a mapped USE_HOST_PTR buffer is the host array, up to date
                void* p = d.queue.enqueueMapBuffer(buffer, CL_TRUE, CL_MAP_READ, 0, bytes);
                d.queue.enqueueUnmapMemObject(buffer, p, nullptr, &log.add(Pass::Transfer));
            } else {  // through pinned blocks, after the kernels enqueued before
                d.staging().download(buffer, 0, host, bytes, copy_threads(), log);
            }
        };
        // Per meta row and word, the id of the word's first vertex: written with the vertices.
        cl::Buffer& word_base = d.buffer(kWordBase, s.rows * s.words * job.word_id_bytes);
        const std::uint64_t vertices = piece.vertices;
        float* positions_at = mesh.positions.data() + 3 * piece.first_vertex;
        float* normals_at = options_.normals ? mesh.normals.data() + 3 * piece.first_vertex : nullptr;
        std::uint32_t* indices_at = mesh.indices.data() + 3 * piece.first_triangle;
        // Both kernels first, then the reads: the triangles are computed while nothing waits.
        cl::Buffer positions, normals, indices;
        if (piece.all_vertices > 0) {
            positions = vertices > 0 ? output(kPositions, positions_at, vertices * 12) : d.buffer(kPositions, 16);
            normals = options_.normals && vertices > 0 ? output(kNormals, normals_at, vertices * 12) : d.buffer(kNormals, 16);
            cl::Kernel& k = d.mc_kernel(job.options, "generate_vertices");
            set_args(k, data, bits, ArgBytes{job.threshold},
                     ArgVertexFormula{options_.iso, is_integer(job.device_type), job.fp64, volume_.origin,
                                      volume_.spacing},
                     u(nx_), u(ny_), u(nz_), u(s.words), u(piece.range.begin), u(first_sample), u(s.owned_rows),
                     u(s.rows), u(piece.all_vertices), piece.vbase, static_cast<cl_int>(options_.inside_below),
                     static_cast<cl_int>(options_.normals), positions, normals, word_base);
            launch(job, k, s.rows, Pass::Generate, log);
        }
        if (piece.triangles > 0) {
            indices = output(kIndices, indices_at, piece.triangles * 12);
            cl::Kernel& k = d.mc_kernel(job.options, "generate_triangles");
            set_args(k, bits, u(nx_), u(ny_), u(nz_), u(s.words), u(piece.range.begin), u(s.cell_rows), u(s.rows),
                     u(piece.triangles), piece.tbase, piece.vbase, u(piece.first_vertex), word_base, piece.cell_groups,
                     d.pair_corners, static_cast<cl_int>(options_.inside_below), indices);
            launch(job, k, s.cell_rows, Pass::Generate, log);
        }
        if (vertices > 0) fetch(positions, positions_at, vertices * 12);
        if (options_.normals && vertices > 0) fetch(normals, normals_at, vertices * 12);
        if (piece.triangles > 0) fetch(indices, indices_at, piece.triangles * 12);
    });
    piece.vbase = piece.tbase = piece.cell_groups = piece.data = piece.bits = cl::Buffer();
    add_times(job, log);
}

// Meshes a piece a device counted on the CPU engine instead: counted again there, to the
// same counts (both follow the canonical mesh), and generated at the piece's offsets.
void Engine::generate_counted_on_cpu(const Piece& counted, unsigned worker, unsigned threads, Mesh& mesh) {
    Piece cpu = count_on_cpu(counted.range, worker, threads);
    // Both follow the canonical mesh, so other counts mean other samples: the caller's thread
    // wrote to the volume between the two counts (reported as "internal error" before).
    if (cpu.vertices != counted.vertices || cpu.triangles != counted.triangles)
        throw_volume_changed(counted.range.begin);
    before_generate(true);
    cpu.first_vertex = counted.first_vertex;
    cpu.first_triangle = counted.first_triangle;
    generate_on_cpu(cpu, mesh);
}

// Worker `worker` generates the pieces it counted. A device takes them last counted first:
// that one's bits (and samples) are still on the device. In Hybrid the CPU worker may take
// pieces over from the other end.
void Engine::generate_pieces(std::vector<DeviceJob>& jobs, unsigned worker, Mesh& mesh) {
    if (worker >= jobs.size()) return cpu_generate_worker(jobs, worker, mesh);
    DeviceJob& job = jobs[worker];
    const auto t0 = Clock::now();
    for (;;) {
        Piece* p = nullptr;
        {
            std::lock_guard<std::mutex> lock(queue_mutex_);
            if (abort_ || job.generate_front == job.generate_back) break;
            p = job.to_generate[--job.generate_back];
        }
        const auto t = Clock::now();
        try {
            generate_on_device(job, *p, mesh);
        } catch (const cl::Error& e) {
            recover_from_out_of_memory(job, e);
            warn("OpenCL device '" + job.device->info.name + "' ran out of memory generating a chunk; it runs on " +
                 "the CPU engine");
            generate_counted_on_cpu(*p, worker, 1, mesh);
        }
        const double s = seconds_since(t);
        std::lock_guard<std::mutex> lock(queue_mutex_);
        job.generate_piece_s = s;
        job.generated.add(s, static_cast<double>((p->range.end - p->range.begin) * plane_));
    }
    // Chunks that did not fit the device, counted by the CPU engine (one thread each).
    for (auto& chunk : results_)
        for (Piece& p : chunk) {
            if (abort_) return;
            if (p.worker != worker || !p.on_cpu) continue;
            const auto t = Clock::now();
            generate_on_cpu(p, mesh);
            std::lock_guard<std::mutex> lock(mutex_);
            fallback_stats_.wall_s += seconds_since(t);
        }
    job.stats.wall_s += seconds_since(t0);
}

// A device's piece for the CPU worker to mesh, when taking it over is quicker than waiting for
// the device (hybrid_schedule.hpp); null when there is none. `wait` is set while a device has
// pieces left but no measured time yet.
Piece* Engine::take_over(std::vector<DeviceJob>& jobs, DeviceJob*& from, bool& wait) {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    wait = false;
    if (abort_) return nullptr;
    // Counting again and generating, per chunk: from its own pieces, or where it counted none
    // (the devices took every chunk before it started), from the pieces it took over.
    double cpu_chunk_s = cpu_count_chunk_s_ + cpu_generated_.per_sample(0) * chunk_samples();
    if (cpu_count_chunk_s_ <= 0) cpu_chunk_s = cpu_taken_over_.per_sample(0) * chunk_samples();
    for (DeviceJob& job : jobs) {
        const std::size_t left = job.generate_back - job.generate_front;
        if (left == 0) continue;
        if (job.generate_piece_s <= 0) {
            wait = true;
            continue;
        }
        const Piece* next = job.to_generate[job.generate_front];
        if (cpu_chunk_s <= 0) {
            // Nothing measured on the CPU yet: one piece of one chunk to measure, while the
            // device has another to work on (a slow device would otherwise mesh every piece
            // alone). Not where a plan left the CPU out: a planned device's pieces are large.
            if (left < 2 || planned_device_chunks_ != kNoPlan || chunks_in(next->range) != 1) continue;
            from = &job;
            return job.to_generate[job.generate_front++];
        }
        const double chunks = static_cast<double>(next->range.end - next->range.begin) / static_cast<double>(chunk_planes());
        if (hybrid_cpu_takes_over(cpu_chunk_s * chunks, job.generate_piece_s, left)) {
            from = &job;
            return job.to_generate[job.generate_front++];
        }
    }
    return nullptr;
}

void Engine::cpu_generate_worker(std::vector<DeviceJob>& jobs, unsigned worker, Mesh& mesh) {
    const auto t0 = Clock::now();
    std::size_t planes = 0;
    for (auto& chunk : results_)
        for (Piece& p : chunk)
            if (p.worker == worker) {
                planes += p.range.end - p.range.begin;
                generate_on_cpu(p, mesh);
            }
    if (planes > 0) cpu_generated_.add(seconds_since(t0), static_cast<double>(planes * plane_));
    for (;;) {
        DeviceJob* from = nullptr;
        bool wait = false;
        Piece* p = take_over(jobs, from, wait);
        if (p == nullptr) {
            if (!wait) break;
            std::this_thread::sleep_for(std::chrono::microseconds(50));
            continue;
        }
        const auto t = Clock::now();
        {
            std::lock_guard<std::mutex> hook_lock(g_before_take_over_mutex);
            if (g_before_take_over) g_before_take_over();
        }
        generate_counted_on_cpu(*p, worker, threads_, mesh);
        pretend_slow(g_slow_cpu_count_s, chunks_in(p->range));  // it counts the piece again: as slow as its own
        p->vbase = p->tbase = p->cell_groups = p->data = p->bits = cl::Buffer();
        const std::size_t voxels = (p->range.end - p->range.begin) * plane_;
        std::lock_guard<std::mutex> lock(queue_mutex_);
        cpu_taken_over_.add(seconds_since(t), static_cast<double>(voxels));
        from->taken_over += chunks_starting_in(p->range);
        from->taken_over_voxels += voxels;
    }
    cpu_pass_seconds_[2] += seconds_since(t0);
    cpu_stats_.wall_s += seconds_since(t0);
}

Mesh Engine::run(Stats& stats) {
    const auto t0 = Clock::now();
    stats.backend = hybrid_ ? Backend::Hybrid : Backend::OpenCL;
    stats.threads = hybrid_ ? threads_ : 0;
    stats.workers = hybrid_ ? running_threads(threads_) : 0;
    auto report = [&] {
        for (const std::string& w : warnings_) {
            stats.warnings.push_back(w);
            if (options_.log) options_.log(w);
        }
    };

    auto chosen = select_devices();
    if (chosen.empty()) {
        const auto all = cl_engine::devices();
        const bool only_cpus = hybrid_ && !all.empty() && options_.device_type == DeviceType::Any &&
                               std::all_of(all.begin(), all.end(),
                                           [](const auto& d) { return d->info.type == DeviceType::Cpu; });
        const std::string why = all.empty()   ? why_no_devices()
                                : only_cpus ? "the only OpenCL devices run on this CPU and would compete with the CPU "
                                              "engine's threads (name one in Options::devices, or set device_type "
                                              "to Cpu, to use it anyway)"
                                            : "no OpenCL device matches the requested devices/device_type";
        // Auto comes here only with devices or device_type set: advise what applies to the caller.
        const std::string advice = devices_left_in_parent()
                                       ? "use Backend::Cpu or Backend::Auto in the child, or OpenCL in the parent "
                                         "only after it forks"
                                   : all.empty() ? "use Backend::Cpu, Backend::Auto or check the OpenCL installation (clinfo)"
                                               : "list_devices() shows the devices there are; use Backend::Cpu, or "
                                                 "leave devices and device_type unset with Backend::Auto";
        if (!hybrid_) throw Error(why + "; " + advice);
        warn(why + "; the hybrid backend runs the CPU engine alone");
        report();
        return cpu_extract(volume_, options_, stats, std::move(storage_));
    }
    // A threshold no sample can cross: nothing to mesh; the CPU engine only checks the samples.
    const bool uniform = dispatch_scalar(volume_.type, [&](auto tag) {
        return make_threshold<decltype(tag)>(options_.iso).uniform != Uniform::Mixed;
    });
    if (uniform) return cpu_extract(volume_, options_, stats, std::move(storage_));

    const bool choosing = chooses_mode(chosen);
    const RatesKey mode_key = rates_key(chosen.front().get());
    const HybridMode mode = choosing ? choose_mode(mode_key) : HybridMode::Split;
    if (mode == HybridMode::CpuAlone) {
        double grown = 0;
        Mesh mesh = cpu_extract(volume_, options_, stats, std::move(storage_), &grown);
        record_mode(mode_key, mode, seconds_since(t0) - grown, mesh.triangle_count(), true);
        stats.backend = Backend::Hybrid;
        DeviceStats idle;
        idle.name = chosen.front()->info.name;
        stats.devices.insert(stats.devices.begin(), idle);  // as the split lists them: devices, then the CPU
        report();
        return mesh;
    }
    if (mode == HybridMode::DeviceAlone) {
        // The OpenCL engine on this device, its host work (copies, the mesh's first touch) on
        // all the cores, as the split would use them.
        hybrid_ = false;
        threads_ = std::max(threads_, resolve_threads(0));
        stats.workers = 0;
    }

    // The devices are this call's from counting to generating (a piece's counts and bits stay
    // on its device between the phases); taken in one global order, so calls never deadlock.
    std::vector<std::shared_ptr<Device>> by_address = chosen;
    std::sort(by_address.begin(), by_address.end());
    std::vector<std::unique_lock<std::mutex>> locks;
    // Time spent waiting for another thread's call on the devices (its program builds, say)
    // is not this mode's: it is left out of the time Hybrid's choice records.
    const auto wait_start = Clock::now();
    for (const auto& d : by_address) locks.emplace_back(d->mutex);
    const double waited = seconds_since(wait_start);
    // Programs built and buffers made in this call: its time is then not a steady one.
    const auto set_up_count = [&] {
        std::size_t n = 0;
        for (const auto& d : chosen) n += d->programs_built + d->allocations;
        return n;
    };
    const std::size_t set_up_before = set_up_count();

    std::vector<DeviceJob> jobs(chosen.size());
    for (std::size_t i = 0; i < chosen.size(); ++i) {
        jobs[i].device = chosen[i];
        prepare(jobs[i]);
    }
    chunks_ = make_chunks(jobs);
    results_.assign(chunks_.size(), {});
    jobs_ = &jobs;
    lo_ = 0;
    hi_ = chunks_.size();
    plan_hybrid(jobs);
    cpu_stats_.name = "cpu";
    fallback_stats_.name = "cpu (fallback)";

    const unsigned workers = static_cast<unsigned>(jobs.size() + (hybrid_ ? 1 : 0));
    const auto each_worker = [&](auto&& work) {
        run_workers(workers, [&](unsigned w) {
            try {
                work(w);
            } catch (...) {
                abort_ = true;
                throw;
            }
        });
    };
    each_worker([&](unsigned w) {
        if (w < jobs.size()) device_count_worker(jobs[w], w);
        else cpu_count_worker(w);
    });

    // Every piece's place in the canonical mesh: pieces in z order.
    std::uint64_t vertices = 0, triangles = 0;
    for (auto& chunk : results_)
        for (Piece& p : chunk) {
            p.first_vertex = vertices;
            p.first_triangle = triangles;
            vertices += p.vertices;
            triangles += p.triangles;
        }
    check_vertex_count(vertices);
    Mesh mesh = std::move(storage_);
    // Spare room only for what the CPU engine generates (a device's results are copied at the
    // sizes it counted), and as its plans say (spare_row_samples). A device's piece the CPU
    // engine may generate after all is planned only then, after this: a whole row for it.
    // Hybrid's CPU worker takes pieces over, and with either backend a device that runs out of
    // memory generating a piece hands it to the CPU engine (generate_pieces).
    std::size_t spare_samples = 0;
    const bool cpu_may_generate = scalar_size(volume_.type) == 1 && (vertices > 0 || triangles > 0);
    for (const auto& chunk : results_)
        for (const Piece& p : chunk)
            spare_samples = std::max(spare_samples, p.on_cpu ? spare_row_samples(p.plan, volume_)
                                                            : cpu_may_generate ? nx_ : std::size_t{0});
    // Every worker waits for the mesh: in Hybrid the cores the CPU worker leaves help fill it.
    const double grown = allocate_output(mesh, vertices, triangles, options_.normals,
                                         hybrid_ ? threads_ + copy_threads() : threads_, spare_samples);
    for (auto& chunk : results_)
        for (Piece& p : chunk)
            if (p.worker < jobs.size() && !p.on_cpu) jobs[p.worker].to_generate.push_back(&p);
    for (DeviceJob& job : jobs) job.generate_back = job.to_generate.size();
    each_worker([&](unsigned w) { generate_pieces(jobs, w, mesh); });
    trim_output(mesh, vertices, triangles);
    remember_rates(jobs);

    for (DeviceJob& job : jobs) {
        // Pieces the CPU worker took over are the CPU's: it counted and generated them again.
        job.stats.chunks -= job.taken_over;
        job.stats.voxels -= job.taken_over_voxels;
        job.stats.chunks_handed_over = job.taken_over;
        cpu_stats_.chunks += job.taken_over;
        cpu_stats_.voxels += job.taken_over_voxels;
        stats.devices.push_back(job.stats);
        for (int p = 0; p < 3; ++p) cpu_pass_seconds_[p] += job.pass_seconds[p];
    }
    if (hybrid_ || mode == HybridMode::DeviceAlone) stats.devices.push_back(cpu_stats_);
    // By voxels: a chunk cut in halves to fit a device counts where it starts, so a fallback
    // of only its upper half has voxels and no chunk (and was left out of the stats).
    if (fallback_stats_.voxels > 0) stats.devices.push_back(fallback_stats_);
    // No device meshed a sample (each chunk failed there and ran on the CPU engine): the CPU
    // is what ran, as Sculptor::stats() says after its fallback. Hybrid stays Hybrid.
    if (!hybrid_ && mode != HybridMode::DeviceAlone && fallback_stats_.voxels > 0 &&
        std::all_of(jobs.begin(), jobs.end(), [](const DeviceJob& job) { return job.stats.voxels == 0; }))
        stats.backend = Backend::Cpu;
    stats.times.classify = cpu_pass_seconds_[0];
    stats.times.scan = cpu_pass_seconds_[1];
    stats.times.generate = cpu_pass_seconds_[2];
    stats.times.total = seconds_since(t0);
    if (choosing)
        record_mode(mode_key, mode, stats.times.total - grown - waited, triangles, set_up_count() == set_up_before);
    report();
    return mesh;
}

}  // namespace

Mesh opencl_extract(const VolumeView& volume, const Options& options, Stats& stats, bool hybrid, Mesh storage) {
    validate_volume(volume);
    Engine engine(volume, options, hybrid, std::move(storage));
    try {
        return engine.run(stats);
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL error in ") + e.what() + ": " + error_name(e.err()));
    }
}

void opencl_release_memory() { cl_engine::release_kept_memory(); }

std::vector<DeviceInfo> opencl_devices() {
    std::vector<DeviceInfo> out;
    for (const auto& d : cl_engine::devices()) out.push_back(d->info);
    return out;
}

std::vector<std::uint32_t> opencl_exclusive_scan(const std::vector<std::uint32_t>& values, int device,
                                                 bool gpu_shape) {
    const auto all = cl_engine::devices();
    if (device < 0 || static_cast<std::size_t>(device) >= all.size())
        throw Error("OpenCL device index " + std::to_string(device) + " does not exist");
    Device& d = *all[static_cast<std::size_t>(device)];
    std::lock_guard<std::mutex> lock(d.mutex);
    std::vector<std::uint32_t> out(values.size() + 1, 0);
    if (values.empty()) return out;
    cl::Buffer buffer(d.context, CL_MEM_READ_WRITE, values.size() * 4);
    EventLog log;
    d.queue.enqueueWriteBuffer(buffer, CL_TRUE, 0, values.size() * 4, values.data());
    const std::uint64_t total = scan(d, buffer, values.size(), log, gpu_shape);
    d.queue.enqueueReadBuffer(buffer, CL_TRUE, 0, values.size() * 4, out.data());
    out.back() = static_cast<std::uint32_t>(total);
    return out;
}

void opencl_split_devices(bool split) { cl_engine::split_devices(split); }

std::size_t opencl_kept_bytes() { return cl_engine::kept_bytes(); }

void opencl_with_registry_locked(bool as_discovery, const std::function<void()>& f) {
    cl_engine::with_device_registry_locked_for_testing(as_discovery, f);
}

void opencl_build_program(const std::string& source, const std::string& options, int device) {
    const auto all = cl_engine::devices();
    if (device < 0 || static_cast<std::size_t>(device) >= all.size())
        throw Error("OpenCL device index " + std::to_string(device) + " does not exist");
    std::lock_guard<std::mutex> lock(all[static_cast<std::size_t>(device)]->mutex);
    all[static_cast<std::size_t>(device)]->build(source, options);
}

void opencl_pretend_no_fp64(bool pretend) { g_pretend_no_fp64 = pretend; }

void opencl_pretend_discrete(bool pretend) { g_pretend_discrete = pretend; }

void opencl_pretend_gpu_build(bool pretend) { g_pretend_gpu_build = pretend; }

void opencl_staging_block_bytes(std::size_t bytes) { cl_engine::set_staging_block_bytes(bytes); }

void opencl_deal_first_chunks(bool deal) { g_deal_first_chunks = deal; }

void opencl_hybrid_split_only(bool split_only) { g_hybrid_split_only = split_only; }

void opencl_before_take_over(std::function<void()> f) {
    std::lock_guard<std::mutex> lock(g_before_take_over_mutex);
    g_before_take_over = std::move(f);
}

void opencl_before_generate(std::function<void(bool)> f) {
    std::lock_guard<std::mutex> lock(g_before_generate_mutex);
    g_before_generate = std::move(f);
}

void opencl_pretend_slow(double count_s, double generate_s, double cpu_count_s, double cpu_start_s) {
    g_slow_count_s = count_s;
    g_slow_generate_s = generate_s;
    g_slow_cpu_count_s = cpu_count_s;
    g_slow_cpu_start_s = cpu_start_s;
}

}  // namespace voxmesh::detail
