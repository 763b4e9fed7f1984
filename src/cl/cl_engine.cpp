// The OpenCL engine: z-chunks from one shared queue, pulled by every selected device (and by
// the CPU engine in Hybrid), each chunk meshed by the bit-row kernels of marching_cubes.cl
// (classify: pack + per-row counts, scan over rows, generate: vertices + triangles), and the
// chunks assembled into the canonical mesh.
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
#include <exception>
#include <limits>
#include <set>
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

enum : unsigned { kData, kBits, kVBase, kTBase, kCellGroups, kWordBase, kPositions, kNormals, kIndices, kNan };

std::atomic<bool> g_pretend_no_fp64{false};  // test hook: run the float paths on fp64 devices
std::atomic<bool> g_pretend_discrete{false};  // test hook: copy in and out as for a discrete GPU

// The kernels index samples with uint: a chunk's samples stay below 2^31.
constexpr std::size_t kMaxChunkSamples = std::size_t(1) << 31;

// Thrown inside a worker when a chunk does not fit the device: cut it smaller.
struct TooBig {};

struct ChunkShape {
    std::size_t planes, zlo, zhi, cell_end;  // cell_end: first cell plane the chunk does not own
    std::size_t rows, owned_rows, cell_rows;  // meta rows; rows of owned sample planes; cell rows
    std::size_t words, bit_rows, bit_words;   // words per bit row; bit rows; their words
    std::size_t data_samples;
};

struct Piece {  // one meshed z-range, with chunk-local vertex ids
    ZRange range;
    std::uint64_t vertices = 0;  // owned; indices may refer to the next chunk's first plane too
    Mesh mesh;
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

std::size_t round_up(std::size_t n, std::size_t m) { return (n + m - 1) / m * m; }

constexpr std::size_t kLocalSize = 256;  // work-group size of marching_cubes.cl launches, where allowed

// What one call needs to know about a device: how samples reach it and the kernel arguments
// that do not change from chunk to chunk.
struct DeviceJob {
    std::shared_ptr<Device> device;
    ScalarType device_type = ScalarType::F32;  // the type the kernels read
    bool fp64 = false;                         // kernels interpolate in double
    bool convert = false;                      // f64 without cl_khr_fp64: converted to f32 per chunk
    bool cpu_only = false;                     // converted, but iso is out of float range
    std::string options;
    std::vector<unsigned char> threshold;      // bytes of a device_type value
    std::size_t limit = 0;                     // bytes one chunk may use
    std::size_t local = kLocalSize;            // work-group size of every launch
    std::size_t word_id_bytes = 4;             // of the per-word vertex id bases (2 or 4)
    DeviceStats stats;
    double pass_seconds[3] = {0, 0, 0};
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
    std::size_t fixed_bytes(const DeviceJob& job, const ChunkShape& s) const;
    bool fits(const DeviceJob& job, const ChunkShape& s) const;
    std::vector<ZRange> make_chunks(const std::vector<DeviceJob>& jobs) const;
    void device_worker(DeviceJob& job);
    void process(DeviceJob& job, ZRange range, std::vector<Piece>& out);
    Piece run_on_device(DeviceJob& job, ZRange range);
    Piece run_on_cpu(ZRange range, unsigned threads);
    void cpu_worker();
    Mesh assemble(std::vector<std::vector<Piece>>& results);
    void warn(const std::string& message);
    bool next_chunk(std::size_t& index);
    Mesh take_storage();

    const VolumeView& volume_;
    const Options& options_;
    bool hybrid_;
    Mesh storage_;  // the caller's arrays to reuse: for the one piece of a single chunk, or the assembled mesh
    std::atomic<bool> storage_taken_{false};
    std::size_t nx_, ny_, nz_, plane_;
    unsigned threads_;

    std::vector<ZRange> chunks_;
    std::vector<std::vector<Piece>> results_;
    std::atomic<std::size_t> next_{0};
    std::atomic<bool> abort_{false};
    std::mutex mutex_;  // warnings_, fallback_ stats
    std::vector<std::string> warnings_;
    DeviceStats cpu_stats_, fallback_stats_;
    double cpu_pass_seconds_[3] = {0, 0, 0};
};

// The caller's storage for the first taker; an empty mesh after that.
Mesh Engine::take_storage() {
    if (storage_taken_.exchange(true)) return Mesh{};
    return std::move(storage_);
}

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

void Engine::prepare(DeviceJob& job) {
    const DeviceInfo& info = job.device->info;
    job.stats.name = info.name;
    job.fp64 = info.fp64 && !g_pretend_no_fp64;
    job.convert = volume_.type == ScalarType::F64 && !job.fp64;
    job.device_type = job.convert ? ScalarType::F32 : volume_.type;
    job.options = std::string("-cl-std=CL1.2 -DVOXEL_T=") + cl_type_name(job.device_type);
    if (is_integer(job.device_type)) job.options += " -DVOXEL_INTEGER";
    if (job.device->info.type == DeviceType::Cpu) job.options += " -DCPU_PREFETCH";
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
    std::size_t limit = info.global_memory / 2;
    if (options_.memory_budget > 0) limit = std::min(limit, options_.memory_budget);
    job.limit = limit;
    // Build now, in the caller's thread, so that a build failure surfaces at once. Programs
    // are cached per device and options: only the first call pays for them.
    const auto t0 = Clock::now();
    std::lock_guard<std::mutex> lock(job.device->mutex);
    const std::size_t built = job.device->programs_built;
    for (const char* name : {"classify_pack", "classify_rows", "generate_vertices", "generate_triangles"}) {
        const std::size_t most =
            job.device->mc_kernel(job.options, name).getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(job.device->device);
        while (job.local > most && job.local > 1) job.local /= 2;
    }
    job.device->scan_local_size();
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

// Device bytes of a chunk, outputs excluded: samples, bits, a vertex id per row word, two
// counts and a word-group mask per row (+ the scan's block sums).
std::size_t Engine::fixed_bytes(const DeviceJob& job, const ChunkShape& s) const {
    return s.data_samples * scalar_size(job.device_type) + s.bit_words * 4 + s.rows * s.words * job.word_id_bytes +
           s.rows * 16 + s.rows / 128 + 64;
}

// Whether a chunk can fit the device before its outputs are known: the fixed part must
// leave at least as much again for vertices and triangles.
bool Engine::fits(const DeviceJob& job, const ChunkShape& s) const {
    const std::size_t max_allocation = job.device->info.max_allocation;
    return s.data_samples <= kMaxChunkSamples && s.data_samples * scalar_size(job.device_type) <= max_allocation &&
           s.bit_words * 4 <= max_allocation && s.rows * s.words * job.word_id_bytes <= max_allocation &&
           2 * fixed_bytes(job, s) <= job.limit;
}

std::vector<ZRange> Engine::make_chunks(const std::vector<DeviceJob>& jobs) const {
    std::size_t planes = nz_;
    if (options_.chunk_planes > 0) {
        planes = options_.chunk_planes;
    } else {
        // Largest chunk every device can take; with several workers, about four chunks
        // each so that faster workers pull more.
        for (const DeviceJob& job : jobs) {
            std::size_t lo = 1, hi = nz_;
            while (lo < hi) {
                const std::size_t mid = (lo + hi + 1) / 2;
                if (fits(job, shape(worst_range(mid)))) lo = mid; else hi = mid - 1;
            }
            planes = std::min(planes, lo);
        }
        const std::size_t workers = jobs.size() + (hybrid_ ? 1 : 0);
        if (workers > 1) planes = std::min(planes, std::max<std::size_t>(1, (nz_ + 4 * workers - 1) / (4 * workers)));
    }
    planes = std::max<std::size_t>(planes, 1);
    std::vector<ZRange> chunks;
    for (std::size_t z = 0; z < nz_; z += planes) chunks.push_back(ZRange{z, std::min(z + planes, nz_)});
    return chunks;
}

bool Engine::next_chunk(std::size_t& index) {
    if (abort_) return false;
    index = next_++;
    return index < chunks_.size();
}

Piece Engine::run_on_cpu(ZRange range, unsigned threads) {
    Piece piece;
    piece.range = range;
    CpuChunkPlan plan = cpu_classify(volume_, options_, range, threads);
    piece.vertices = plan.vertices;
    if (chunks_.size() == 1) piece.mesh = take_storage();
    allocate_output(piece.mesh, plan.vertices, plan.triangles, options_.normals, threads);
    cpu_generate(plan, volume_, options_, threads,
                 MeshOut{piece.mesh.positions.data(), options_.normals ? piece.mesh.normals.data() : nullptr,
                         piece.mesh.indices.data(), 0});
    return piece;
}

Piece Engine::run_on_device(DeviceJob& job, ZRange range) {
    Device& d = *job.device;
    const ChunkShape s = shape(range);
    const DeviceInfo& info = d.info;
    if (!fits(job, s)) {
        if (s.planes > 1) throw TooBig{};
        if (s.data_samples > kMaxChunkSamples || s.data_samples * scalar_size(job.device_type) > info.max_allocation ||
            fixed_bytes(job, s) > job.limit)
            throw TooBig{};
    }
    const std::size_t sample_bytes = scalar_size(job.device_type);
    const std::size_t first_sample = (range.begin - s.zlo) * plane_;  // of plane `begin` in the device's samples

    EventLog log;
    std::vector<float> converted;
    Piece piece;
    piece.range = range;
    const auto u = [](std::size_t v) { return static_cast<cl_uint>(v); };
    // Fixed work-group size: PoCL compiles a kernel once per local size it is launched with.
    const auto launch = [&](cl::Kernel& k, std::size_t n, Pass pass) {
        d.queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(round_up(n, job.local)), cl::NDRange(job.local),
                                     nullptr, &log.add(pass));
    };
    try {
        // Upload the planes, in place (or converted from f64 keeping every inside bit). A device
        // that shares the host's memory reads the caller's samples where they are.
        const bool host_memory = info.host_memory && !g_pretend_discrete;
        const bool zero_copy = host_memory && !job.convert;
        cl::Buffer in_place;
        cl::Buffer& data = zero_copy ? in_place : d.buffer(kData, s.data_samples * sample_bytes);
        const auto* bytes =
            static_cast<const unsigned char*>(volume_.data) + s.zlo * plane_ * scalar_size(volume_.type);
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
        if (zero_copy)
            in_place = cl::Buffer(d.context, CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, s.data_samples * sample_bytes,
                                  const_cast<unsigned char*>(bytes));  // read only: the kernels never write it
        else
            d.queue.enqueueWriteBuffer(data, CL_FALSE, 0, s.data_samples * sample_bytes, bytes, nullptr,
                                       &log.add(Pass::Transfer));
        cl::Buffer& bits = d.buffer(kBits, s.bit_words * 4);
        cl::Buffer& vbase = d.buffer(kVBase, s.rows * 4);  // per row: counts, then their prefix sums
        cl::Buffer& tbase = d.buffer(kTBase, s.rows * 4);
        cl::Buffer& cell_groups = d.buffer(kCellGroups, s.rows * 8);  // per cell row: word groups to visit
        cl::Buffer& nan = d.buffer(kNan, sizeof(cl_int));
        const cl_int no_nan = INT_MAX;
        d.queue.enqueueFillBuffer(nan, no_nan, 0, sizeof(cl_int), nullptr, &log.add(Pass::Transfer));

        cl::Kernel& pack = d.mc_kernel(job.options, "classify_pack");
        set_args(pack, data, ArgBytes{job.threshold}, u(nx_), u(ny_), u(s.words), u(range.begin), u(first_sample),
                 u(s.bit_rows), bits, nan);
        launch(pack, s.bit_rows, Pass::Classify);

        cl::Kernel& count = d.mc_kernel(job.options, "classify_rows");
        set_args(count, bits, u(nx_), u(ny_), u(nz_), u(s.words), u(range.begin), u(s.cell_end), u(s.rows),
                 d.case_table, vbase, tbase, cell_groups);
        launch(count, s.rows, Pass::Classify);

        const std::uint64_t all_vertices = scan(d, vbase, s.rows, log);
        const std::uint64_t triangles = scan(d, tbase, s.rows, log);
        cl_int nan_plane = INT_MAX;
        d.queue.enqueueReadBuffer(nan, CL_TRUE, 0, sizeof(nan_plane), &nan_plane, nullptr, &log.add(Pass::Transfer));
        if (nan_plane != INT_MAX)
            throw Error("volume has NaN or infinite samples (first seen in z-plane " + std::to_string(nan_plane) +
                        "); replace them with finite values before meshing");
        if (all_vertices > std::numeric_limits<std::uint32_t>::max() ||
            triangles > std::numeric_limits<std::uint32_t>::max())
            throw TooBig{};
        std::uint64_t vertices = all_vertices;
        if (s.owned_rows < s.rows) {  // plane `end`'s first vertex id: its first row's base
            cl_uint v = 0;
            d.queue.enqueueReadBuffer(vbase, CL_TRUE, s.owned_rows * 4, sizeof(v), &v, nullptr,
                                      &log.add(Pass::Transfer));
            vertices = v;
        }
        // Outputs, sized by the scan totals.
        const std::size_t out_bytes = vertices * (12 + (options_.normals ? 12 : 0)) + triangles * 12;
        if (vertices * 12 > info.max_allocation || triangles * 12 > info.max_allocation ||
            fixed_bytes(job, s) + out_bytes > job.limit) {
            if (s.planes > 1) throw TooBig{};
        }
        piece.vertices = vertices;
        if (chunks_.size() == 1) piece.mesh = take_storage();
        allocate_output(piece.mesh, vertices, triangles, options_.normals, threads_);
        // Where the device shares host memory, the kernels write the mesh where it will stay.
        const auto output = [&](unsigned slot, auto& host, std::size_t bytes) -> cl::Buffer {
            if (host_memory)
                return cl::Buffer(d.context, CL_MEM_WRITE_ONLY | CL_MEM_USE_HOST_PTR, bytes, host.data());
            return d.buffer(slot, bytes);
        };
        const auto fetch = [&](const cl::Buffer& buffer, auto& host, std::size_t bytes) {
            if (host_memory) {  // a mapped USE_HOST_PTR buffer is the host array, up to date
                void* p = d.queue.enqueueMapBuffer(buffer, CL_TRUE, CL_MAP_READ, 0, bytes);
                d.queue.enqueueUnmapMemObject(buffer, p, nullptr, &log.add(Pass::Transfer));
            } else {
                d.queue.enqueueReadBuffer(buffer, CL_FALSE, 0, bytes, host.data(), nullptr, &log.add(Pass::Transfer));
            }
        };
        // Per meta row and word, the id of the word's first vertex: written with the vertices.
        cl::Buffer& word_base = d.buffer(kWordBase, s.rows * s.words * job.word_id_bytes);
        if (all_vertices > 0) {
            cl::Buffer positions = vertices > 0 ? output(kPositions, piece.mesh.positions, vertices * 12)
                                                : d.buffer(kPositions, 16);
            cl::Buffer normals = options_.normals && vertices > 0
                                     ? output(kNormals, piece.mesh.normals, vertices * 12)
                                     : d.buffer(kNormals, 16);
            cl::Kernel& k = d.mc_kernel(job.options, "generate_vertices");
            set_args(k, data, bits, ArgBytes{job.threshold},
                     ArgVertexFormula{options_.iso, is_integer(job.device_type), job.fp64, volume_.origin,
                                      volume_.spacing},
                     u(nx_), u(ny_), u(nz_), u(s.words), u(range.begin), u(first_sample), u(s.owned_rows), u(s.rows),
                     u(all_vertices), vbase, static_cast<cl_int>(options_.inside_below),
                     static_cast<cl_int>(options_.normals), positions, normals, word_base);
            launch(k, s.rows, Pass::Generate);
            if (vertices > 0) fetch(positions, piece.mesh.positions, vertices * 12);
            if (options_.normals && vertices > 0) fetch(normals, piece.mesh.normals, vertices * 12);
        }
        if (triangles > 0) {
            cl::Buffer indices = output(kIndices, piece.mesh.indices, triangles * 12);
            cl::Kernel& k = d.mc_kernel(job.options, "generate_triangles");
            set_args(k, bits, u(nx_), u(ny_), u(nz_), u(s.words), u(range.begin), u(s.cell_rows), u(s.rows),
                     u(triangles), tbase, vbase, word_base, cell_groups, d.case_corners,
                     static_cast<cl_int>(options_.inside_below), indices);
            launch(k, s.cell_rows, Pass::Generate);
            fetch(indices, piece.mesh.indices, triangles * 12);
        }
        d.queue.finish();
    } catch (...) {
        // Nothing may still read from or write into host memory we are about to free.
        try {
            d.queue.finish();
        } catch (const cl::Error&) {
        }
        throw;
    }
    for (const auto& [pass, event] : log.events) {
        const double s = event_seconds(event);
        if (pass == Pass::Transfer) {
            job.stats.transfer_s += s;
        } else {
            job.stats.kernel_s += s;
            job.pass_seconds[static_cast<int>(pass)] += s;
        }
    }
    return piece;
}

void Engine::process(DeviceJob& job, ZRange range, std::vector<Piece>& out) {
    const std::size_t planes = range.end - range.begin;
    if (!job.cpu_only) {
        bool too_big = false;
        try {
            out.push_back(run_on_device(job, range));
            job.stats.chunks += 1;
            job.stats.voxels += planes * plane_;
            return;
        } catch (const TooBig&) {
            too_big = true;
        } catch (const cl::Error& e) {
            if (!is_out_of_memory(e.err()))
                throw Error("OpenCL error on device '" + job.device->info.name + "' in " + e.what() + ": " +
                            error_name(e.err()));
            job.device->drop_buffers();
            too_big = true;
        }
        if (too_big && planes > 1) {
            warn("a " + std::to_string(planes) + "-plane chunk does not fit OpenCL device '" + job.device->info.name +
                 "' (out of memory, max allocation or memory budget); using smaller chunks");
            const ZRange a{range.begin, range.begin + planes / 2}, b{range.begin + planes / 2, range.end};
            process(job, a, out);
            process(job, b, out);
            return;
        }
        warn("OpenCL device '" + job.device->info.name + "' cannot hold even one z-plane of this volume within " +
             "its memory limits; those chunks run on the CPU engine");
    }
    const auto t0 = Clock::now();
    out.push_back(run_on_cpu(range, 1));
    std::lock_guard<std::mutex> lock(mutex_);
    fallback_stats_.chunks += 1;
    fallback_stats_.voxels += planes * plane_;
    fallback_stats_.wall_s += seconds_since(t0);
}

void Engine::device_worker(DeviceJob& job) {
    const auto t0 = Clock::now();
    std::lock_guard<std::mutex> lock(job.device->mutex);
    std::size_t index;
    while (next_chunk(index)) process(job, chunks_[index], results_[index]);
    job.stats.wall_s = seconds_since(t0);
}

void Engine::cpu_worker() {
    const auto t0 = Clock::now();
    std::size_t index;
    while (next_chunk(index)) {
        const ZRange range = chunks_[index];
        const auto t = Clock::now();
        results_[index].push_back(run_on_cpu(range, threads_));
        cpu_pass_seconds_[2] += seconds_since(t);
        cpu_stats_.chunks += 1;
        cpu_stats_.voxels += (range.end - range.begin) * plane_;
    }
    cpu_stats_.wall_s = seconds_since(t0);
}

Mesh Engine::assemble(std::vector<std::vector<Piece>>& results) {
    std::vector<Piece*> pieces;
    for (auto& chunk : results)
        for (Piece& p : chunk) pieces.push_back(&p);
    if (pieces.size() == 1) {  // one chunk: its ids are already global, nothing to copy
        return std::move(pieces[0]->mesh);
    }
    std::vector<std::uint64_t> vbase(pieces.size()), tbase(pieces.size());
    std::uint64_t vertices = 0, triangles = 0;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        vbase[i] = vertices;
        tbase[i] = triangles;
        vertices += pieces[i]->vertices;
        triangles += pieces[i]->mesh.indices.size() / 3;
    }
    check_vertex_count(vertices);
    Mesh mesh = take_storage();
    allocate_output(mesh, vertices, triangles, options_.normals, threads_);
    const unsigned workers = static_cast<unsigned>(std::min<std::size_t>(threads_, std::max<std::size_t>(pieces.size(), 1)));
    run_workers(workers, [&](unsigned w) {
        for (std::size_t i = w; i < pieces.size(); i += workers) {
            const Mesh& piece = pieces[i]->mesh;
            std::copy(piece.positions.begin(), piece.positions.end(), mesh.positions.begin() + 3 * vbase[i]);
            if (options_.normals)
                std::copy(piece.normals.begin(), piece.normals.end(), mesh.normals.begin() + 3 * vbase[i]);
            const auto base = static_cast<std::uint32_t>(vbase[i]);
            std::transform(piece.indices.begin(), piece.indices.end(), mesh.indices.begin() + 3 * tbase[i],
                           [base](std::uint32_t id) { return id + base; });
        }
    });
    return mesh;
}

Mesh Engine::run(Stats& stats) {
    const auto t0 = Clock::now();
    stats.backend = hybrid_ ? Backend::Hybrid : Backend::OpenCL;
    stats.threads = hybrid_ ? threads_ : 0;
    auto report = [&] {
        for (const std::string& w : warnings_) {
            stats.warnings.push_back(w);
            if (options_.log) options_.log(w);
        }
    };

    const auto chosen = select_devices();
    if (chosen.empty()) {
        const auto all = cl_engine::devices();
        const bool only_cpus = hybrid_ && !all.empty() && options_.device_type == DeviceType::Any &&
                               std::all_of(all.begin(), all.end(),
                                           [](const auto& d) { return d->info.type == DeviceType::Cpu; });
        const std::string why = all.empty()   ? "no OpenCL platform or usable device was found"
                                : only_cpus ? "the only OpenCL devices run on this CPU and would compete with the CPU "
                                              "engine's threads (name one in Options::devices, or set device_type "
                                              "to Cpu, to use it anyway)"
                                            : "no OpenCL device matches the requested devices/device_type";
        if (!hybrid_) throw Error(why + "; use Backend::Cpu, Backend::Auto or check the OpenCL installation (clinfo)");
        warn(why + "; the hybrid backend runs the CPU engine alone");
        report();
        return cpu_extract(volume_, options_, stats, take_storage());
    }
    // A threshold no sample can cross: nothing to mesh; the CPU engine only checks the samples.
    const bool uniform = dispatch_scalar(volume_.type, [&](auto tag) {
        return make_threshold<decltype(tag)>(options_.iso).uniform != Uniform::Mixed;
    });
    if (uniform) return cpu_extract(volume_, options_, stats, take_storage());

    std::vector<DeviceJob> jobs(chosen.size());
    for (std::size_t i = 0; i < chosen.size(); ++i) {
        jobs[i].device = chosen[i];
        prepare(jobs[i]);
    }
    chunks_ = make_chunks(jobs);
    results_.assign(chunks_.size(), {});
    cpu_stats_.name = "cpu";
    fallback_stats_.name = "cpu (fallback)";

    const unsigned workers = static_cast<unsigned>(jobs.size() + (hybrid_ ? 1 : 0));
    run_workers(workers, [&](unsigned w) {
        try {
            if (w < jobs.size()) device_worker(jobs[w]);
            else cpu_worker();
        } catch (...) {
            abort_ = true;
            throw;
        }
    });
    Mesh mesh = assemble(results_);

    for (DeviceJob& job : jobs) {
        stats.devices.push_back(job.stats);
        for (int p = 0; p < 3; ++p) cpu_pass_seconds_[p] += job.pass_seconds[p];
    }
    if (hybrid_) stats.devices.push_back(cpu_stats_);
    if (fallback_stats_.chunks > 0) stats.devices.push_back(fallback_stats_);
    stats.times.classify = cpu_pass_seconds_[0];
    stats.times.scan = cpu_pass_seconds_[1];
    stats.times.generate = cpu_pass_seconds_[2];
    stats.times.total = seconds_since(t0);
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

std::vector<DeviceInfo> opencl_devices() {
    std::vector<DeviceInfo> out;
    for (const auto& d : cl_engine::devices()) out.push_back(d->info);
    return out;
}

std::vector<std::uint32_t> opencl_exclusive_scan(const std::vector<std::uint32_t>& values, int device) {
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
    const std::uint64_t total = scan(d, buffer, values.size(), log);
    d.queue.enqueueReadBuffer(buffer, CL_TRUE, 0, values.size() * 4, out.data());
    out.back() = static_cast<std::uint32_t>(total);
    return out;
}

void opencl_split_devices(bool split) { cl_engine::split_devices(split); }

void opencl_build_program(const std::string& source, const std::string& options, int device) {
    const auto all = cl_engine::devices();
    if (device < 0 || static_cast<std::size_t>(device) >= all.size())
        throw Error("OpenCL device index " + std::to_string(device) + " does not exist");
    std::lock_guard<std::mutex> lock(all[static_cast<std::size_t>(device)]->mutex);
    all[static_cast<std::size_t>(device)]->build(source, options);
}

void opencl_pretend_no_fp64(bool pretend) { g_pretend_no_fp64 = pretend; }

void opencl_pretend_discrete(bool pretend) { g_pretend_discrete = pretend; }

}  // namespace voxmesh::detail
