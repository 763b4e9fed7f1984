// Sculpting's OpenCL block mesher (kernels/sculpt_blocks.cl): the dirty blocks of one update
// go to the device in batches; each batch is one upload of the blocks' samples (with their
// one-sample margin), classify -> scan -> vertices + triangles, and one read-back of
// everything. The program is built once per process and device (Device's cache); buffers are
// the Device's reusable ones, under its mutex.
#include "cl_runtime.hpp"

#include "core/threshold.hpp"
#include "sculpt/device_blocks.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>

namespace voxmesh::detail::sculpt {

namespace {

using namespace cl_engine;

// Buffer slots of a Device (the OpenCL engine uses 0..7 and 1000 up, the scan 99 and 100 up).
enum : unsigned { kStage = 200, kMeta, kCodes, kVid, kVCount, kTCount, kPositions, kNormals, kIndices, kTotals };

constexpr unsigned kMetaWords = 16;  // M_WORDS in sculpt_blocks.cl; the word layout is there
constexpr std::size_t kBatchSamples = std::size_t(8) << 20;  // staged samples per batch (32 MiB of f32)

std::atomic<std::size_t> g_batch_samples{0};  // test hooks (set_device_block_tuning)
std::atomic<bool> g_no_fp64{false};
std::atomic<bool> g_gpu_scans{false};

const char* cl_type_name(ScalarType type) {
    switch (type) {
        case ScalarType::U8: return "uchar";
        case ScalarType::U16: return "ushort";
        case ScalarType::F32: return "float";
        default: break;
    }
    throw Error(std::string("sculpt: no OpenCL block mesher for ") + scalar_name(type) + " samples");
}

std::size_t round_up(std::size_t n, std::size_t m) { return (n + m - 1) / m * m; }

// Where one block of a batch lives in the batch's arrays.
struct Placed {
    std::array<std::size_t, 3> lo{}, extent{};  // staged box: global first sample, samples per axis
    std::size_t stage = 0, rows = 0, row = 0, samples = 0, sample = 0;
};

class OpenclBlockMesher final : public DeviceBlockMesher {
public:
    OpenclBlockMesher(std::shared_ptr<Device> device, const DeviceBlockSetup& setup)
        : device_(std::move(device)), setup_(setup) {
        const ScalarType type = setup.volume.type;
        sample_bytes_ = scalar_size(type);
        fp64_ = device_->info.fp64 && !g_no_fp64;
        gpu_scans_ = g_gpu_scans;
        options_ = std::string("-cl-std=CL1.2 -DVOXEL_T=") + cl_type_name(type);
        if (type != ScalarType::F32) options_ += " -DVOXEL_INTEGER";
        if (fp64_) options_ += " -DUSE_FP64";
        threshold_.resize(sample_bytes_);
        switch (type) {
            case ScalarType::U8: store_threshold<std::uint8_t>(); break;
            case ScalarType::U16: store_threshold<std::uint16_t>(); break;
            default: store_threshold<float>(); break;
        }
        std::lock_guard<std::mutex> lock(device_->mutex);
        // A fixed work-group size: PoCL compiles a kernel anew for every local size it meets,
        // and its own choice follows the global size, which changes from update to update.
        std::size_t local = 64;
        for (const char* name : {"block_classify", "block_vertices", "block_triangles"})
            local = std::min<std::size_t>(
                local, device_->sculpt_kernel(options_, name).getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(
                           device_->device));
        local_ = 1;
        while (local_ * 2 <= local) local_ *= 2;
        device_->scan_shape(gpu_scans_);
    }

    const std::string& device_name() const override { return device_->info.name; }
    bool left_in_parent() const override { return devices_left_in_parent(); }

    void mesh(std::span<const BlockBox> boxes,
              const std::function<void(std::size_t, const DeviceBlockMesh&)>& store) override {
        std::lock_guard<std::mutex> lock(device_->mutex);
        std::size_t first = 0;
        while (first < boxes.size()) {
            std::size_t end = first, staged = 0;
            while (end < boxes.size() && (end == first || staged + staged_samples(boxes[end]) <= batch_limit())) {
                staged += staged_samples(boxes[end]);
                ++end;
            }
            try {
                run_batch(boxes.subspan(first, end - first), first, store);
            } catch (const cl::Error& e) {
                finish_quietly();
                device_->drop_buffers();
                throw Error("OpenCL error on device '" + device_->info.name + "' while re-meshing sculpt blocks (" +
                            e.what() + ": " + error_name(e.err()) + ")");
            } catch (...) {
                finish_quietly();
                throw;
            }
            first = end;
        }
    }

private:
    template <class T>
    void store_threshold() {
        const Threshold<T> t = make_threshold<T>(setup_.iso);
        std::memcpy(threshold_.data(), &t.value, sizeof(T));
    }

    std::size_t batch_limit() const {
        const std::size_t limit = g_batch_samples > 0 ? g_batch_samples.load() : kBatchSamples;
        return std::min<std::size_t>(limit, device_->info.max_allocation / 2 / sample_bytes_);
    }

    // The box's samples plus the one-sample margin the normals read, clamped to the volume.
    void staged_box(const BlockBox& box, Placed& p) const {
        for (int d = 0; d < 3; ++d) {
            p.lo[d] = box.c0[d] > 0 ? box.c0[d] - 1 : 0;
            p.extent[d] = std::min(box.c0[d] + box.samples[d] + 1, setup_.volume.dims[d]) - p.lo[d];
        }
    }
    std::size_t staged_samples(const BlockBox& box) const {
        Placed p;
        staged_box(box, p);
        return p.extent[0] * p.extent[1] * p.extent[2];
    }

    void finish_quietly() {
        try {
            device_->queue.finish();
        } catch (const cl::Error&) {
        }
    }

    void run_batch(std::span<const BlockBox> boxes, std::size_t first,
                   const std::function<void(std::size_t, const DeviceBlockMesh&)>& store);

    std::shared_ptr<Device> device_;
    DeviceBlockSetup setup_;
    std::size_t sample_bytes_ = 4;
    bool fp64_ = false;
    bool gpu_scans_ = false;  // test hook (DeviceBlockTuning::gpu_scans)
    std::size_t local_ = 1;  // work-items per group along the rows
    std::string options_;
    std::vector<unsigned char> threshold_;
    // Host buffers reused from batch to batch.
    std::vector<Placed> placed_;
    std::vector<unsigned char> stage_;
    std::vector<cl_uint> meta_, vbase_, tbase_;
    std::vector<float> positions_, normals_;
    std::vector<std::uint32_t> indices_;
};

void OpenclBlockMesher::run_batch(std::span<const BlockBox> boxes, std::size_t first,
                                  const std::function<void(std::size_t, const DeviceBlockMesh&)>& store) {
    Device& d = *device_;
    const VolumeView& vol = setup_.volume;
    const std::size_t nx = vol.dims[0], ny = vol.dims[1], nz = vol.dims[2];

    // Lay the blocks out: staged samples, rows, per-sample arrays.
    placed_.assign(boxes.size(), Placed{});
    std::size_t stage = 0, rows = 0, samples = 0, max_rows = 0;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        Placed& p = placed_[i];
        staged_box(boxes[i], p);
        p.stage = stage;
        p.row = rows;
        p.rows = boxes[i].samples[1] * boxes[i].samples[2];
        p.sample = samples;
        p.samples = boxes[i].samples[0] * p.rows;
        stage += p.extent[0] * p.extent[1] * p.extent[2];
        rows += p.rows;
        samples += p.samples;
        max_rows = std::max(max_rows, p.rows);
    }
    if (samples > std::numeric_limits<cl_uint>::max() / 4)
        throw Error("sculpt: an OpenCL batch is too large (internal error)");

    // Gather the staged samples and the block descriptions.
    stage_.resize(stage * sample_bytes_);
    meta_.assign(kMetaWords * boxes.size(), 0);
    const auto* volume = static_cast<const unsigned char*>(vol.data);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        const Placed& p = placed_[i];
        const std::size_t row_bytes = p.extent[0] * sample_bytes_;
        unsigned char* out = stage_.data() + p.stage * sample_bytes_;
        for (std::size_t z = 0; z < p.extent[2]; ++z)
            for (std::size_t y = 0; y < p.extent[1]; ++y, out += row_bytes)
                std::memcpy(out, volume + ((p.lo[2] + z) * ny + p.lo[1] + y) * nx * sample_bytes_ + p.lo[0] * sample_bytes_,
                            row_bytes);
        const auto u = [](std::size_t v) { return static_cast<cl_uint>(v); };
        cl_uint* m = meta_.data() + kMetaWords * i;
        m[0] = u(p.stage);
        m[1] = u(p.extent[0]);
        m[2] = u(p.extent[1]);
        for (int a = 0; a < 3; ++a) {
            m[3 + a] = u(boxes[i].c0[a] - p.lo[a]);
            m[6 + a] = u(boxes[i].c0[a]);
            m[9 + a] = u(boxes[i].samples[a]);
        }
        m[12] = u(p.row);
        m[13] = u(p.sample);
    }

    EventLog log;
    cl::Buffer& staged = d.buffer(kStage, stage_.size());
    cl::Buffer& meta = d.buffer(kMeta, meta_.size() * sizeof(cl_uint));
    cl::Buffer& codes = d.buffer(kCodes, samples);
    cl::Buffer& vid = d.buffer(kVid, samples * sizeof(cl_uint));
    cl::Buffer& vcount = d.buffer(kVCount, rows * sizeof(cl_uint));
    cl::Buffer& tcount = d.buffer(kTCount, rows * sizeof(cl_uint));
    d.queue.enqueueWriteBuffer(staged, CL_FALSE, 0, stage_.size(), stage_.data());
    d.queue.enqueueWriteBuffer(meta, CL_FALSE, 0, meta_.size() * sizeof(cl_uint), meta_.data());

    const cl::NDRange global(round_up(max_rows, local_), boxes.size()), local(local_, 1);
    cl::Kernel& classify = d.sculpt_kernel(options_, "block_classify");
    set_args(classify, staged, meta, ArgBytes{threshold_}, d.pair_to_case, d.case_table, codes, vcount, tcount);
    d.queue.enqueueNDRangeKernel(classify, cl::NullRange, global, local);

    // In place: vcount/tcount become every row's first vertex/triangle in the batch.
    cl::Buffer& totals = d.buffer(kTotals, 2 * sizeof(cl_uint));
    scan_into(d, vcount, rows, totals, 0, log, gpu_scans_);
    scan_into(d, tcount, rows, totals, 1, log, gpu_scans_);
    cl_uint got[2] = {};
    d.queue.enqueueReadBuffer(totals, CL_TRUE, 0, sizeof(got), got);  // one wait for both totals
    const std::uint64_t vertices = got[0], triangles = got[1];
    if (vertices > std::numeric_limits<cl_uint>::max() || 3 * triangles > std::numeric_limits<cl_uint>::max())
        throw Error("sculpt: an OpenCL batch has too many vertices (internal error)");

    positions_.resize(3 * vertices);
    normals_.resize(setup_.normals ? 3 * vertices : 0);
    indices_.resize(3 * triangles);
    vbase_.resize(rows);
    tbase_.resize(rows);
    d.queue.enqueueReadBuffer(vcount, CL_FALSE, 0, rows * sizeof(cl_uint), vbase_.data());
    d.queue.enqueueReadBuffer(tcount, CL_FALSE, 0, rows * sizeof(cl_uint), tbase_.data());

    if (vertices > 0) {
        cl::Buffer& positions = d.buffer(kPositions, vertices * 12);
        cl::Buffer& normals = d.buffer(kNormals, setup_.normals ? vertices * 12 : 16);
        cl::Kernel& k = d.sculpt_kernel(options_, "block_vertices");
        set_args(k, staged, meta, ArgBytes{threshold_},
                 ArgVertexFormula{setup_.iso, vol.type != ScalarType::F32, fp64_, vol.origin, vol.spacing},
                 static_cast<cl_uint>(nx), static_cast<cl_uint>(ny), static_cast<cl_uint>(nz),
                 static_cast<cl_int>(setup_.inside_below), static_cast<cl_int>(setup_.normals), codes, vcount, vid,
                 positions, normals);
        d.queue.enqueueNDRangeKernel(k, cl::NullRange, global, local);
        d.queue.enqueueReadBuffer(positions, CL_FALSE, 0, vertices * 12, positions_.data());
        if (setup_.normals) d.queue.enqueueReadBuffer(normals, CL_FALSE, 0, vertices * 12, normals_.data());

        if (triangles > 0) {
            cl::Buffer& indices = d.buffer(kIndices, triangles * 12);
            cl::Kernel& t = d.sculpt_kernel(options_, "block_triangles");
            set_args(t, staged, meta, ArgBytes{threshold_}, d.pair_to_case, d.case_corners,
                     static_cast<cl_int>(setup_.inside_below), codes, vid, vcount, tcount, indices);
            d.queue.enqueueNDRangeKernel(t, cl::NullRange, global, local);
            d.queue.enqueueReadBuffer(indices, CL_FALSE, 0, triangles * 12, indices_.data());
        }
    }
    d.queue.finish();

    // Hand each block its slice: rows of a block are contiguous, so are its outputs.
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        const Placed& p = placed_[i];
        const bool last = i + 1 == boxes.size();
        const std::size_t v0 = vbase_[p.row], v1 = last ? vertices : vbase_[placed_[i + 1].row];
        const std::size_t t0 = tbase_[p.row], t1 = last ? triangles : tbase_[placed_[i + 1].row];
        DeviceBlockMesh m;
        m.positions = std::span<const float>(positions_).subspan(3 * v0, 3 * (v1 - v0));
        if (setup_.normals) m.normals = std::span<const float>(normals_).subspan(3 * v0, 3 * (v1 - v0));
        m.indices = std::span<const std::uint32_t>(indices_).subspan(3 * t0, 3 * (t1 - t0));
        store(first + i, m);
    }
}

// Index -1: a GPU or accelerator when there is one (that is what the device path is for),
// else the first device.
std::shared_ptr<Device> pick_device(int index) {
    const auto all = devices();
    if (index >= 0) {
        if (static_cast<std::size_t>(index) >= all.size())
            throw Error("OpenCL device index " + std::to_string(index) + " does not exist; list_devices() has " +
                        std::to_string(all.size()) + " device(s)");
        return all[static_cast<std::size_t>(index)];
    }
    for (const auto& d : all)
        if (d->info.type != DeviceType::Cpu) return d;
    return all.front();
}

}  // namespace

void set_device_block_tuning(const DeviceBlockTuning& tuning) {
    g_batch_samples = tuning.batch_samples;
    g_no_fp64 = tuning.no_fp64;
    g_gpu_scans = tuning.gpu_scans;
}

std::unique_ptr<DeviceBlockMesher> open_opencl_block_mesher(const DeviceBlockSetup& setup, int device,
                                                            std::string& why) {
    if (devices().empty()) {
        why = why_no_devices();
        return nullptr;
    }
    try {
        return std::make_unique<OpenclBlockMesher>(pick_device(device), setup);
    } catch (const cl::Error& e) {
        throw Error(std::string("OpenCL error while preparing the sculpt block mesher (") + e.what() + ": " +
                    error_name(e.err()) + ")");
    }
}

}  // namespace voxmesh::detail::sculpt
