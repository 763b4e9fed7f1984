// Timing one extraction combination, the streaming floor, and peak memory.
#include "bench.hpp"

#include "core/parallel.hpp"

#include <algorithm>
#include <barrier>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <thread>

#if defined(__linux__)
#include <malloc.h>
#include <pthread.h>
#include <sched.h>
#endif

namespace vmbench {

volatile std::sig_atomic_t g_interrupted = 0;

double now_s() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

unsigned hardware_threads() { return voxmesh::detail::resolve_threads(0); }  // the CPUs this process may use

// ---- streaming floor -----------------------------------------------------------------------

namespace {

// The sum of the volume's bytes read as 64-bit words: every byte read once, in the widest
// loads the loop vectorises to, and consumed so that it cannot be optimised away. Not summed
// sample by sample: widening each byte of an 8-bit volume to 64 bits took 2.5 times longer
// than the memory (2 threads here: 8.4 ms for 128 MB against 3.3 ms as words), which made the
// floor of 8- and 16-bit volumes a measure of that arithmetic instead.
std::uint64_t sum_words(const unsigned char* p, std::size_t bytes) {
    std::uint64_t s = 0;
    const std::size_t words = bytes / 8;
    for (std::size_t i = 0; i < words; ++i) {
        std::uint64_t u;
        std::memcpy(&u, p + 8 * i, 8);
        s += u;
    }
    for (std::size_t i = 8 * words; i < bytes; ++i) s += p[i];
    return s;
}

volatile std::uint64_t g_sink = 0;

// Each of timed_rounds' threads on a CPU of its own, when there are no more threads than CPUs.
// Left to the kernel, a thread started (or woken at a barrier) after the process was idle
// for a few ms was put on its starter's CPU on this project's VM and waited there (the
// library's worker threads had the same; src/core/parallel.cpp): the threads' reads then ran
// one after the other, and the floor's speed-up on 2 threads read 1.0 in some runs.
class PinThreads {
public:
    explicit PinThreads(unsigned threads) {
#if defined(__linux__)
        if (sched_getaffinity(0, sizeof allowed_, &allowed_) != 0) return;
        for (int cpu = 0; cpu < CPU_SETSIZE && cpus_.size() < threads; ++cpu)
            if (CPU_ISSET(cpu, &allowed_)) cpus_.push_back(cpu);
        if (cpus_.size() < threads || threads < 2) cpus_.clear();
#else
        (void)threads;
#endif
    }
    void pin(unsigned w) const {  // on thread w
#if defined(__linux__)
        if (cpus_.empty()) return;
        cpu_set_t one;
        CPU_ZERO(&one);
        CPU_SET(cpus_[w], &one);
        sched_setaffinity(0, sizeof one, &one);
#else
        (void)w;
#endif
    }
    void unpin() const {  // on thread 0, at the end
#if defined(__linux__)
        if (!cpus_.empty()) sched_setaffinity(0, sizeof allowed_, &allowed_);
#endif
    }

private:
#if defined(__linux__)
    cpu_set_t allowed_;
    std::vector<int> cpus_;
#endif
};

// The seconds of each of `rounds` rounds of work(w, round) on `threads` threads, started once
// and released together at a barrier each round (so no round includes starting a thread),
// from the first thread's start to the last one's end. Not timed on one thread from the
// barrier: with more threads than cores that thread may start long after the others.
std::vector<double> timed_rounds(unsigned threads, int rounds, const std::function<void(unsigned, int)>& work) {
    std::vector<double> seconds(static_cast<std::size_t>(rounds));
    std::vector<double> start(threads), end(threads);
    std::barrier sync(static_cast<std::ptrdiff_t>(threads));
    const PinThreads pins(threads);
    auto worker = [&](unsigned w) {
        pins.pin(w);
        for (int r = 0; r < rounds; ++r) {
            sync.arrive_and_wait();
            start[w] = now_s();
            work(w, r);
            end[w] = now_s();
            sync.arrive_and_wait();  // the others write start again only after the next one
            if (w == 0)
                seconds[static_cast<std::size_t>(r)] =
                    *std::max_element(end.begin(), end.end()) - *std::min_element(start.begin(), start.end());
        }
    };
    std::vector<std::thread> pool;
    for (unsigned w = 1; w < threads; ++w) pool.emplace_back(worker, w);
    worker(0);
    for (auto& t : pool) t.join();
    pins.unpin();
    return seconds;
}

// Reads of the whole volume by `threads` threads, each its contiguous share (like the
// engine's z-slabs); the seconds of each of warmup + repeat reads (timed_rounds).
std::vector<double> floor_reads(const voxmesh::VolumeView& view, unsigned threads, int warmup, int repeat) {
    // No more readers than cores, as the CPU engine runs no more workers than cores: a thread
    // per requested count (--threads 100000) aborted the process.
    threads = std::clamp(threads, 1u, hardware_threads());
    const std::size_t bytes = voxmesh::scalar_size(view.type) * view.dims[0] * view.dims[1] * view.dims[2];
    const auto* base = static_cast<const unsigned char*>(view.data);
    std::vector<std::uint64_t> sums(threads);
    std::vector<double> seconds = timed_rounds(threads, warmup + std::max(1, repeat), [&](unsigned w, int) {
        const std::size_t b = bytes * w / threads / 64 * 64;
        const std::size_t e = w + 1 == threads ? bytes : bytes * (w + 1) / threads / 64 * 64;
        sums[w] += sum_words(base + b, e - b);
    });
    for (std::uint64_t s : sums) g_sink = g_sink + s;  // consumed: the reads cannot be dropped
    seconds.erase(seconds.begin(), seconds.begin() + warmup);
    return seconds;
}

// A dependent chain of multiplies and shifts: a few cycles an iteration on any core, no loads.
// Latency-bound, so two hyperthreads of one core each run it at almost full speed.
std::uint64_t spin(std::uint64_t iterations, std::uint64_t x) {
    for (std::uint64_t i = 0; i < iterations; ++i) {
        x = x * 6364136223846793005ull + 1442695040888963407ull;
        x ^= x >> 29;
    }
    return x;
}

// Six such chains interleaved: one multiply a cycle and about four operations a cycle, what a
// core issues at most, so a second thread on the same core (a hyperthread) gains little here,
// as it does on the engine's passes (about 2.5 instructions a cycle). No vector form: 64-bit
// multiplies have none below AVX-512.
std::uint64_t spin_wide(std::uint64_t iterations, std::uint64_t x) {
    std::uint64_t c[6];
    for (int k = 0; k < 6; ++k) c[k] = x + 0x9e3779b97f4a7c15ull * std::uint64_t(k + 1);
    for (std::uint64_t i = 0; i < iterations; ++i)
        for (auto& v : c) {
            v = v * 6364136223846793005ull + 1442695040888963407ull;
            v ^= v >> 29;
        }
    return c[0] ^ c[1] ^ c[2] ^ c[3] ^ c[4] ^ c[5];
}

// Rounds per second of `iterations` steps of `loop` split over `threads` threads.
double loop_rate(unsigned threads, std::uint64_t iterations, std::uint64_t (*loop)(std::uint64_t, std::uint64_t)) {
    constexpr int kRounds = 8;  // the first warms up
    threads = std::max(1u, threads);
    std::vector<std::uint64_t> chains(threads);
    std::vector<double> seconds = timed_rounds(threads, kRounds, [&](unsigned w, int r) {
        chains[w] += loop(iterations / threads, w + static_cast<unsigned>(r) + 1);
    });
    for (std::uint64_t x : chains) g_sink = g_sink + x;  // consumed: the chains cannot be dropped
    seconds.erase(seconds.begin());
    const double t = median(seconds);
    return t > 0 ? 1 / t : 0;
}

}  // namespace

double streaming_floor(const voxmesh::VolumeView& view, unsigned threads, int repeat, int warmup) {
    return median(floor_reads(view, std::max(1u, threads), std::max(0, warmup), repeat));
}

// ---- compute ceiling -----------------------------------------------------------------------

ComputeRates compute_rates(unsigned threads) {
    // A few ms on one core each (a wide step is six chains' steps).
    return {loop_rate(threads, 4'000'000, spin), loop_rate(threads, 1'000'000, spin_wide)};
}

// ---- memory --------------------------------------------------------------------------------

namespace {

// VmRSS / VmHWM from /proc/self/status, in MiB; 0 when unavailable.
double status_mb(const char* key) {
    std::ifstream in("/proc/self/status");
    std::string line;
    const std::size_t klen = std::strlen(key);
    while (std::getline(in, line)) {
        if (line.compare(0, klen, key) == 0 && line.size() > klen && line[klen] == ':') {
            std::istringstream s(line.substr(klen + 1));
            double kb = 0;
            s >> kb;
            return kb / 1024.0;
        }
    }
    return 0;
}

bool reset_hwm() {
    // Writing 5 to clear_refs resets the peak RSS (VmHWM) to the current RSS (Linux >= 4.0).
    std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
    if (!f) return false;
    const bool ok = std::fputs("5", f) >= 0;
    return std::fclose(f) == 0 && ok;
}

}  // namespace

bool rss_reset_works() {
    static const bool works = [] {
        if (!reset_hwm()) return false;
        // Touch 32 MiB, release it, reset: the peak must come back down.
        {
            std::vector<char> big(32u << 20);
            for (std::size_t i = 0; i < big.size(); i += 4096) big[i] = 1;
            g_sink = g_sink + std::uint64_t(big[4096]);
        }
        const double high = status_mb("VmHWM");
        if (!reset_hwm()) return false;
        return status_mb("VmHWM") < high - 16;
    }();
    return works;
}

// What a Hybrid call with one device ran (Result::hybrid_modes); 0 for other backends and for
// several devices. Not from who meshed what, since a split can leave either side idle: the
// device alone runs with no CPU workers, and the CPU engine alone lists the device with no time.
char hybrid_mode(const voxmesh::Stats& stats) {
    if (stats.backend != voxmesh::Backend::Hybrid || stats.devices.empty()) return 0;
    const auto opencl_devices = std::count_if(stats.devices.begin(), stats.devices.end(), [](const auto& d) {
        return d.name != "cpu" && d.name != "cpu (fallback)";
    });
    if (opencl_devices != 1) return 0;
    if (stats.workers == 0) return 'D';
    const voxmesh::DeviceStats& device = stats.devices[0];
    return device.wall_s == 0 && device.chunks == 0 ? 'C' : 'S';
}

// ---- one combination -----------------------------------------------------------------------

Runner::Runner(const Input& input, const Combo& combo, const Settings& settings)
    : settings_(settings), view_(input.volume.view()), per_run_rss_(rss_reset_works()) {
    Result& r = result_;
    r.field = input.field;
    r.type = input.type;
    r.dims = input.dims;
    r.iso = input.iso;
    r.backend = voxmesh::backend_name(combo.backend);
    r.backend_ran = r.backend;
    r.device = combo.device;
    r.threads = combo.threads;
    r.normals = settings.normals;
    r.reuse_mesh = settings.reuse_mesh;
    r.interleaved = settings.interleave;
    r.repeat = settings.repeat;
    r.warmup = settings.warmup;
    r.pause_ms = settings.pause_ms;
    r.volume_mb = double(input.volume.byte_size()) / (1024.0 * 1024.0);
    r.rss_scope = per_run_rss_ ? "run" : "process";

    options_.iso = input.iso;
    options_.backend = combo.backend;
    options_.threads = combo.threads;
    options_.normals = settings.normals;
    options_.devices = combo.devices;
}

void Runner::record(const voxmesh::Stats& stats) {
    Result& r = result_;
    classify_.push_back(stats.times.classify);
    scan_.push_back(stats.times.scan);
    generate_.push_back(stats.times.generate);
    total_.push_back(stats.times.total);
    double k = 0, t = 0;
    std::string names;
    for (const auto& d : stats.devices) {
        k += d.kernel_s;
        t += d.transfer_s;
        if (!names.empty()) names += "+";
        names += d.name;
    }
    kernel_.push_back(k);
    transfer_.push_back(t);
    if (stats.backend == voxmesh::Backend::Hybrid) {
        std::size_t cpu = 0, all = 0;
        for (const auto& d : stats.devices) {
            all += d.voxels;
            if (d.name == "cpu") cpu += d.voxels;
        }
        if (all > 0) cpu_share_.push_back(double(cpu) / double(all));
    }
    r.device_names = names;
    for (const auto& w : stats.warnings)
        if (std::find(r.warnings.begin(), r.warnings.end(), w) == r.warnings.end()) r.warnings.push_back(w);
}

bool Runner::run(bool timed) {
    Result& r = result_;
    if (r.status != "ok") return false;
    try {
        // --reuse-mesh: every run meshes into the one kept Mesh (extract_into), as a sculpting
        // loop would; otherwise each run gets a new Mesh from extract(), freed after the timing.
        voxmesh::Mesh fresh;
        voxmesh::Stats stats;
        if (settings_.pause_ms > 0)
            std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(settings_.pause_ms));
        if (per_run_rss_ && timed) reset_hwm();
        const double rss_before = status_mb("VmRSS");
        const double t0 = now_s();
        if (settings_.reuse_mesh) voxmesh::extract_into(view_, options_, kept_, stats);
        else fresh = voxmesh::extract(view_, options_, stats);
        const double t1 = now_s();
        r.backend_ran = voxmesh::backend_name(stats.backend);
        if (const char mode = hybrid_mode(stats))
            r.hybrid_modes += timed ? mode : static_cast<char>(mode + ('a' - 'A'));  // lower case: warm-up
        if (!timed) return true;
        const double hwm = status_mb("VmHWM");
        const voxmesh::Mesh& m = settings_.reuse_mesh ? kept_ : fresh;
        r.times.push_back(t1 - t0);
        record(stats);
        r.triangles = m.triangle_count();
        r.vertices = m.vertex_count();
        r.mesh_mb = double((m.positions.size() + m.normals.size()) * sizeof(float) +
                           m.indices.size() * sizeof(std::uint32_t)) / (1024.0 * 1024.0);
        r.peak_rss_mb = std::max(r.peak_rss_mb, hwm);
        r.extract_rss_mb = std::max(r.extract_rss_mb, hwm - rss_before);
        return true;
    } catch (const voxmesh::Error& e) {
        // An engine or device that cannot run here (no OpenCL device, engine not built, ...).
        r.status = "unavailable";
        r.error = e.what();
    } catch (const std::exception& e) {
        r.status = "error";
        r.error = e.what();
    }
    r.times.clear();
    return false;
}

void Runner::setup() {
    Result& r = result_;
    if (!settings_.setup_first || r.status != "ok") return;
    // The whole volume, once: PoCL compiles a kernel on its first launch for each work-group
    // shape and for grids under or over 65535 items, so only the very launches of a timed
    // call are sure to leave nothing to compile in it (3 planes launched a third of them).
    try {
        if (per_run_rss_) reset_hwm();
        const double rss_before = status_mb("VmRSS");
        const double t0 = now_s();
        {
            voxmesh::Stats stats;
            const voxmesh::Mesh mesh = voxmesh::extract(view_, options_, stats);
        }
        r.setup_s = now_s() - t0;
        r.setup_rss_mb = status_mb("VmHWM") - rss_before;
        // What both engines keep between calls, and what the call freed, go back to the
        // system: the timed calls start where a fresh process with the runtime loaded would.
        voxmesh::release_scratch_memory();
        malloc_trim(0);
    } catch (const std::exception&) {
        // The timed runs report what cannot run here.
    }
}

Result Runner::finish() {
    Result r = std::move(result_);
    kept_ = voxmesh::Mesh{};
    if (r.status != "ok") return r;
    if (r.times.empty()) {
        r.status = "interrupted";
        return r;
    }
    r.median_s = median(r.times);
    r.min_s = *std::min_element(r.times.begin(), r.times.end());
    r.max_s = *std::max_element(r.times.begin(), r.times.end());
    r.classify_s = median(classify_);
    r.scan_s = median(scan_);
    r.generate_s = median(generate_);
    r.total_s = median(total_);
    r.kernel_s = median(kernel_);
    if (!cpu_share_.empty()) r.cpu_share = median(cpu_share_);
    r.transfer_s = median(transfer_);
    r.mvox_s = r.median_s > 0 ? double(r.samples()) / r.median_s / 1e6 : 0;
    return r;
}

Result measure(const Input& input, const Combo& combo, const Settings& settings) {
    Runner runner(input, combo, settings);
    runner.setup();
    for (int i = 0; i < settings.warmup && !g_interrupted; ++i)
        if (!runner.run(false)) break;
    for (int i = 0; i < std::max(1, settings.repeat) && !g_interrupted; ++i)
        if (!runner.run(true)) break;
    return runner.finish();
}

std::vector<Result> measure_interleaved(const Input& input, const std::vector<Combo>& combos,
                                        const Settings& settings) {
    std::vector<std::unique_ptr<Runner>> runners;
    for (const Combo& c : combos) runners.push_back(std::make_unique<Runner>(input, c, settings));
    const std::size_t n = runners.size();
    for (auto& runner : runners) runner->setup();
    for (int i = 0; i < settings.warmup && !g_interrupted; ++i)
        for (auto& runner : runners) runner->run(false);
    std::vector<std::vector<double>> floors(n);
    const voxmesh::VolumeView view = input.volume.view();
    for (int i = 0; i < std::max(1, settings.repeat) && !g_interrupted; ++i)
        for (std::size_t step = 0; step < n; ++step) {
            const std::size_t k = i % 2 ? n - 1 - step : step;  // forward, then backward
            runners[k]->run(true);
            if (settings.floor_in_rounds)
                floors[k].push_back(floor_reads(view, std::max(1u, combos[k].threads), 0, 1)[0]);
        }
    std::vector<Result> out;
    for (std::size_t k = 0; k < n; ++k) {
        out.push_back(runners[k]->finish());
        if (!floors[k].empty()) {
            out.back().floor_s = median(floors[k]);
            out.back().floor_in_rounds = true;
        }
    }
    return out;
}

std::string Result::size_label() const {
    if (dims[0] == dims[1] && dims[1] == dims[2]) return std::to_string(dims[0]);
    return std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]);
}

}  // namespace vmbench
