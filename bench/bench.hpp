// voxmesh-bench internals: what is measured, how results are kept and printed.
#pragma once

#include <voxmesh/fields.hpp>
#include <voxmesh/voxmesh.hpp>

#include <array>
#include <csignal>
#include <cstdio>
#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace vmbench {

// Set by SIGINT; the run loops stop between measurements and print what finished.
extern volatile std::sig_atomic_t g_interrupted;

// One volume to mesh: a built-in field at one size and type, or a file.
struct Input {
    std::string field;  // "sphere", ..., or the file name
    std::string type;   // scalar name
    std::array<std::size_t, 3> dims{0, 0, 0};
    double iso = 0;
    voxmesh::Volume volume;
};

// How to run one extraction.
struct Combo {
    voxmesh::Backend backend = voxmesh::Backend::Cpu;
    std::string device;        // "cpu", "all", "#0", "#0+1"
    std::vector<int> devices;  // Options::devices
    unsigned threads = 1;
};

struct Result {
    // What ran.
    std::string field, type;
    std::array<std::size_t, 3> dims{0, 0, 0};
    double iso = 0;
    std::string backend, backend_ran, device;
    unsigned threads = 0;
    bool normals = true;
    bool reuse_mesh = false, interleaved = false;
    int repeat = 0, warmup = 0;
    double pause_ms = 0;  // --pause: idle time before each run
    std::string status = "ok";  // "ok", "unavailable", "error"
    std::string error;
    std::vector<std::string> warnings;

    // End-to-end extract() wall time, seconds, over `repeat` runs.
    std::vector<double> times;
    double median_s = 0, min_s = 0, max_s = 0;
    // Medians of the library's own accounting (voxmesh::Stats).
    double classify_s = 0, scan_s = 0, generate_s = 0, total_s = 0;
    double kernel_s = 0, transfer_s = 0;  // summed over devices (OpenCL)
    std::string device_names;             // Stats::devices names, '+'-joined
    double cpu_share = -1;                // Hybrid: median share of the samples the CPU engine meshed (-1: not Hybrid)
    // Hybrid with one device: what each call ran, in order: S the split, C the CPU engine alone,
    // D the device alone; lower case for warm-up calls.
    std::string hybrid_modes;

    std::size_t triangles = 0, vertices = 0;
    double mvox_s = 0;
    double floor_s = 0, floor_ratio = 0;  // streaming floor on the same threads
    bool floor_in_rounds = false;         // floor_s: median of reads between the runs (--interleave)
    double speedup = -1;                  // vs the fewest threads of the same series; -1: none
    unsigned speedup_base_threads = 0;
    // What the machine allows that speed-up, against the same base thread count (-1: not
    // measured): a compute-only loop's speed-up (compute_ceiling: one dependent chain a thread;
    // compute_ceiling_wide: a core's full issue width, below 2 where two threads share a core)
    // and the streaming floor's.
    double compute_ceiling = -1, compute_ceiling_wide = -1, floor_speedup = -1;

    double peak_rss_mb = 0;     // process peak while extracting (VmHWM after a reset)
    double extract_rss_mb = 0;  // that peak minus the RSS just before extract()
    double setup_rss_mb = -1;   // --setup-first: that call's peak minus the RSS before it (-1: not done)
    double setup_s = -1;        // --setup-first: that call's seconds
    std::string rss_scope;      // "run" (VmHWM reset per run) or "process" (lifetime peak)
    double volume_mb = 0, mesh_mb = 0;

    std::size_t samples() const { return dims[0] * dims[1] * dims[2]; }
    std::string size_label() const;  // "256" for cubes, else "NXxNYxNZ"
};

struct Settings {
    int repeat = 3, warmup = 1;
    bool normals = true;
    bool quiet = false;
    bool reuse_mesh = false;  // extract_into() one Mesh kept across runs, instead of extract()
    bool interleave = false;  // an input's combinations take turns run by run (measure_interleaved)
    // Milliseconds the process sleeps before each run, as a program that meshes once a frame
    // does between frames: the library's idle worker threads are then woken from a sleep.
    double pause_ms = 0;
    // --interleave: one read of the volume (the streaming floor) on each combination's threads
    // after each of its timed runs, so the floor is measured in the same phases as the runs.
    bool floor_in_rounds = false;
    // Before its runs, each combination meshes the volume's first 3 z-planes once: set-up (the
    // OpenCL runtime, program builds) is paid there, so a first run's memory is extraction's.
    bool setup_first = false;
};

// ---- measure.cpp ----
double now_s();
double median(std::vector<double> v);
// Time to read every sample once with `threads` threads (median over repeats, after warmup).
double streaming_floor(const voxmesh::VolumeView& view, unsigned threads, int repeat, int warmup);
// Rounds per second in which `threads` threads, started together, finish a fixed amount of
// arithmetic (no memory traffic), median of 7 rounds: the ratio of two thread counts' rates is
// the machine's own ceiling for a speed-up (cores, SMT, a VM's share of them). `chain`: one
// dependent integer chain per thread, which hyperthreads of one core hide; `wide`: six
// independent chains, a core's full issue width, which they share.
struct ComputeRates {
    double chain = 0, wide = 0;
};
ComputeRates compute_rates(unsigned threads);
// Runs one combination on one input: warmup, then `repeat` timed extract() calls.
Result measure(const Input& input, const Combo& combo, const Settings& settings);
// All combinations of one input, taking turns run by run (forward, then backward): on a
// machine whose speed drifts over seconds, their ratios (threads, engines) then compare runs
// made in the same phases instead of one combination's phase against another's.
std::vector<Result> measure_interleaved(const Input& input, const std::vector<Combo>& combos,
                                        const Settings& settings);

// One combination's runs, one call at a time (what both of the above drive).
class Runner {
public:
    Runner(const Input& input, const Combo& combo, const Settings& settings);
    bool run(bool timed);  // false once the combination failed (status and error set)
    void setup();          // --setup-first: the whole volume meshed once, untimed, then the heap trimmed
    Result finish();       // medians of the timed runs

private:
    void record(const voxmesh::Stats& stats);

    const Settings& settings_;
    voxmesh::VolumeView view_;
    voxmesh::Options options_;
    bool per_run_rss_;
    Result result_;
    voxmesh::Mesh kept_;  // --reuse-mesh
    std::vector<double> classify_, scan_, generate_, total_, kernel_, transfer_, cpu_share_;
};
// Whether /proc/self/clear_refs can reset VmHWM (per-run peaks) on this system.
bool rss_reset_works();
// The CPUs this process may use (its affinity and CPU quota): what threads = 0 gives.
unsigned hardware_threads();

// ---- report.cpp ----
// Speed-ups within each series (same input, backend, device), with the ceilings beside them
// when `compute_rates` (compute_rates() per thread count) has the counts.
void compute_speedups(std::vector<Result>& results, const std::map<unsigned, ComputeRates>& compute_rates = {});
void print_table(const std::vector<Result>& results);
void print_csv(const std::vector<Result>& results);
void print_json(const std::vector<Result>& results, std::FILE* out = stdout);
// print_json into `path` (--save), through a temporary renamed into place; check_save_path
// checks before any run that the temporary could be made there (an unnamed file in the
// directory), so that a bad path fails at once, not after them.
void check_save_path(const std::string& path);
void save_json(const std::vector<Result>& results, const std::string& path);
// Table 1 of the paper beside ours: threads down, resolution across.
void print_paper(const std::vector<Result>& results, const std::string& field, const std::string& type);

// ---- sculpt_bench.cpp ----
// --sculpt: stroke-path latency per size and backend (cpu, opencl, auto: --backends); 0 threads =
// all cores; pause_ms: a sleep before each dab (--pause). Returns the exit code.
int run_sculpt(const std::vector<std::size_t>& sizes, unsigned threads, std::size_t dabs, double pause_ms,
               const std::vector<std::string>& backends, bool json, bool quiet);

// ---- mesh_ops_bench.cpp ----
// --mesh-ops: analyze_topology, keep_largest_components and write_mesh per format, beside the
// extract of the same built-in volume (CPU engine, all cores). Returns the exit code.
int run_mesh_ops(const std::vector<voxmesh::Field>& fields, const std::vector<voxmesh::ScalarType>& types,
                 const std::vector<std::size_t>& sizes, int repeat, std::uint32_t seed, bool json, bool quiet);

// ---- volume_files.cpp ----
// NRRD with the iso and field as key/value pairs (voxmesh_iso:=..., read back by voxmesh::recorded_iso).
void write_volume_nrrd(const std::string& path, const Input& input);

}  // namespace vmbench
