// voxmesh-bench: how fast is marching cubes here, on CPU threads and OpenCL devices?
//
//   voxmesh-bench --field sphere,gyroid --sizes 128,256 --threads 1,2 --backends cpu,opencl
//   voxmesh-bench --paper --repeat 5          # the paper's Table 1 grid, beside the paper
//   voxmesh-bench --input head.nrrd --iso 400.5 --json
//   voxmesh-bench --field gyroid --sizes 512 --write-volume gyroid512.nrrd   # for bench/peers
//   voxmesh-bench --sculpt                    # stroke latency p50/p95/p99 at 256^3 and 512^3
#include "bench.hpp"

#include "cli/option_checks.hpp"
#include "core/exit_signals.hpp"
#include "io/input_file.hpp"

#include <voxmesh/fields.hpp>
#include <voxmesh/io.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

using namespace vmbench;

namespace {

using voxmesh::detail::handle_signal_unless_ignored;
using voxmesh::detail::kExitSignals;
using voxmesh::detail::remove_partial_outputs_and_die;

// SIGINT during the runs: the first asks the loops to stop and print what finished; a second
// ends the process at once. (SIGTERM, SIGHUP, and SIGINT outside the timed runs remove the
// temporary of a --save or --write-volume in progress and die.)
void on_sigint(int sig) {
    if (g_interrupted) remove_partial_outputs_and_die(sig);
    g_interrupted = 1;
}

voxmesh::ScalarType parse_type(const std::string& s) {
    using voxmesh::ScalarType;
    for (auto t : {ScalarType::U8, ScalarType::I8, ScalarType::U16, ScalarType::I16, ScalarType::U32, ScalarType::I32,
                   ScalarType::F32, ScalarType::F64})
        if (s == voxmesh::scalar_name(t)) return t;
    throw voxmesh::Error("unknown type '" + s + "' (expected u8, i8, u16, i16, u32, i32, f32 or f64)");
}

voxmesh::Backend parse_backend(const std::string& s) {
    using voxmesh::Backend;
    for (auto b : {Backend::Cpu, Backend::OpenCL, Backend::Hybrid, Backend::Auto})
        if (s == voxmesh::backend_name(b)) return b;
    throw voxmesh::Error("unknown backend '" + s + "' (expected cpu, opencl, hybrid or auto)");
}

// "all": one run on every device; "0,2": device 0 alone, then device 2 alone; "0+2": both together.
std::vector<Combo> parse_devices(const std::string& spec) {
    std::vector<Combo> out;
    if (spec == "all" || spec.empty()) {
        Combo c;
        c.device = "all";
        out.push_back(c);
        return out;
    }
    std::istringstream list(spec);
    std::string item;
    while (std::getline(list, item, ',')) {
        if (item.empty()) throw voxmesh::Error("bad --devices '" + spec + "': an empty entry (expected all, I,J or I+J)");
        Combo c;
        c.device = "#" + item;
        std::istringstream parts(item);
        std::string p;
        while (std::getline(parts, p, '+')) {
            try {
                std::size_t used = 0;
                const int i = std::stoi(p, &used);
                if (used != p.size() || i < 0) throw std::invalid_argument(p);
                if (std::find(c.devices.begin(), c.devices.end(), i) != c.devices.end())
                    throw std::invalid_argument(p);  // a device twice in one group
                c.devices.push_back(i);
            } catch (const std::exception&) {
                throw voxmesh::Error("bad --devices entry '" + item + "' (expected all, I,J or I+J, each device once)");
            }
        }
        for (const Combo& earlier : out)
            if (earlier.device == c.device) throw voxmesh::Error("--devices lists '" + item + "' twice");
        out.push_back(c);
    }
    return out;
}

// Each value once, in the order given: a repeated size or thread count made a second series
// under the same key, whose speed-ups were taken against the first copy's runs.
template <class T>
void drop_repeats(std::vector<T>& values) {
    std::vector<T> kept;
    for (const T& v : values)
        if (std::find(kept.begin(), kept.end(), v) == kept.end()) kept.push_back(v);
    values = std::move(kept);
}

// The options a mode (--sculpt, --mesh-ops, --paper) would accept and ignore: refused instead.
void refuse_options(CLI::App& app, const char* mode, std::initializer_list<const char*> names) {
    for (const char* name : names)
        if (app.get_option(name)->count() > 0)
            throw voxmesh::Error(std::string(name) + " does not apply to " + mode);
}

}  // namespace

int main(int argc, char** argv) {
    for (const int sig : kExitSignals) handle_signal_unless_ignored(sig, remove_partial_outputs_and_die);
    CLI::App app{"voxmesh-bench: marching-cubes timings on CPU threads and OpenCL devices"};
    std::vector<std::string> fields, inputs, types{"f32"}, backends{"cpu"};
    std::vector<std::size_t> sizes{64, 128, 256};
    std::vector<unsigned> threads;
    std::string devices = "all", write_path;
    double iso = NAN;
    std::uint32_t seed = 1;
    Settings settings;
    bool paper = false, csv = false, json = false, no_normals = false, list = false, no_floor = false;
    bool sculpt = false, mesh_ops = false;
    std::size_t dabs = 300;

    app.add_option("--field", fields, "built-in fields: sphere, gyroid, blobs, ct (comma list; default sphere)")
        ->delimiter(',');
    // No comma list: a file's name may hold a comma. Several files: --input a.nrrd b.nrrd.
    app.add_option("--input", inputs, "volume files (NRRD, MetaImage, NIfTI, legacy VTK, NumPy .npy; not raw; names taken whole, commas and all); loading is not timed");
    app.add_option("--iso", iso, "iso value (default: the field's, or voxmesh_iso in a file written by --write-volume)")
        ->transform(voxmesh::cli::decimal_number())
        ->check([](const std::string& text) {  // NaN stands for "not given" below: refuse it here
            const double value = std::strtod(text.c_str(), nullptr);
            return std::isfinite(value) ? std::string() : "--iso must be a finite number, not '" + text + "'";
        });
    app.add_option("--type", types, "scalar types of built-in fields: f32, u8, u16, i16, i8, u32, i32, f64")
        ->delimiter(',');
    auto* sizes_opt = app.add_option("--sizes", sizes, "cube sizes of built-in fields (default 64,128,256)")
                          ->delimiter(',')
                          ->transform(voxmesh::cli::whole_number_in(1, 65536));
    auto* threads_opt =
        app.add_option("--threads", threads, "CPU thread counts (default 1 and all cores; 0 = all cores)")
            ->delimiter(',')
            ->transform(voxmesh::cli::whole_number_in(0, 65536));
    app.add_option("--backends", backends, "cpu, opencl, hybrid, auto (comma list)")->delimiter(',');
    app.add_option("--devices", devices, "OpenCL devices: all (together), I,J (each alone) or I+J (together)");
    app.add_option("--repeat", settings.repeat, "timed runs per combination (median/min/max)")->transform(voxmesh::cli::whole_number_in(1, 1000));
    app.add_option("--warmup", settings.warmup, "untimed runs first")->transform(voxmesh::cli::whole_number_in(0, 100));
    app.add_option("--seed", seed, "seed of the blobs and ct fields")
        ->transform(voxmesh::cli::whole_number_in(0, std::numeric_limits<std::uint32_t>::max()));
    app.add_flag("--no-normals", no_normals, "mesh without normals (default: normals on)");
    app.add_flag("--reuse-mesh", settings.reuse_mesh,
                 "mesh every run into one kept Mesh with extract_into() (no fresh output pages), not extract()");
    app.add_flag("--interleave", settings.interleave,
                 "an input's combinations take turns run by run (robust ratios on a machine whose speed drifts); the "
                 "floor is read after each run");
    app.add_option("--pause", settings.pause_ms,
                   "milliseconds to sleep before each run (each dab with --sculpt), as a program meshing once a frame "
                   "(its worker threads then wake from a sleep)")
        ->transform(voxmesh::cli::decimal_number())
        ->check(CLI::Range(0.0, 10000.0))
        ->check([](const std::string& text) {  // CLI::Range lets NaN through
            return std::isnan(std::strtod(text.c_str(), nullptr)) ? "--pause must be a number, not '" + text + "'"
                                                                   : std::string();
        });
    app.add_flag("--setup-first", settings.setup_first,
                 "before its runs, each combination meshes the volume once, untimed, and trims the heap (OpenCL "
                 "runtime, program builds and PoCL's per-launch kernel compiles paid there; its time and memory are "
                 "printed as a note)");
    app.add_flag("--paper", paper, "the paper's Table 1 grid: sizes 64..512 x threads 1,2,4,6,16 on the CPU");
    app.add_flag("--sculpt", sculpt,
                 "sculpting: a built-in stroke path over a sphere, update latency p50/p95/p99 beside a full re-mesh "
                 "(sizes default 256,512)");
    app.add_flag("--mesh-ops", mesh_ops,
                 "time analyze_topology (1 worker, all), keep_largest_components, write_mesh (stl, ply, obj), "
                 "vertex_edges, triangle_cells and edge_cell_ranges beside the extract of each "
                 "--field/--type/--sizes volume (default sizes 256,512)");
    app.add_option("--dabs", dabs, "brush dabs of the --sculpt stroke path")->transform(voxmesh::cli::whole_number_in(1, 100000));
    app.add_flag("--csv", csv, "CSV output");
    app.add_flag("--json", json, "one JSON object per line");
    std::string save_path;
    app.add_option("--save", save_path, "also write the JSON lines to this file (for bench/plot.py)");
    app.add_flag("--no-floor", no_floor, "skip the streaming-floor measurement");
    app.add_flag("--quiet,-q", settings.quiet, "no progress on stderr");
    app.add_flag("--list-devices", list, "list OpenCL devices and exit");
    app.add_option("--write-volume", write_path,
                   "write the (one) built-in field as a raw NRRD for bench/peers, with its iso, and exit");
    voxmesh::cli::refuse_empty_values(app);
    CLI11_PARSE(app, argc, argv);
    settings.normals = !no_normals;
    settings.floor_in_rounds = settings.interleave && !no_floor;
    if (csv && json) {
        std::fprintf(stderr, "voxmesh-bench: choose one of --csv and --json\n");
        return 2;
    }

    try {
        if (!save_path.empty()) check_save_path(save_path);
        if (list) {
            const auto devs = voxmesh::list_devices();
            if (devs.empty()) std::printf("no usable OpenCL device\n");
            for (const auto& d : devs)
                std::printf("#%d  %s / %s (%s), %u compute units, %.0f MiB, max alloc %.0f MiB\n", d.index,
                            d.platform.c_str(), d.name.c_str(), d.version.c_str(), d.compute_units,
                            double(d.global_memory) / 1048576.0, double(d.max_allocation) / 1048576.0);
            return 0;
        }
        if (sculpt)
            refuse_options(app, "--sculpt",
                           {"--field", "--input", "--iso", "--type", "--devices", "--repeat", "--warmup", "--seed",
                            "--no-normals", "--reuse-mesh", "--interleave", "--setup-first", "--paper", "--mesh-ops",
                            "--csv", "--save", "--no-floor", "--write-volume"});
        if (mesh_ops)
            refuse_options(app, "--mesh-ops",
                           {"--input", "--iso", "--threads", "--backends", "--devices", "--warmup", "--no-normals",
                            "--reuse-mesh", "--interleave", "--pause", "--setup-first", "--paper", "--dabs", "--csv",
                            "--save", "--no-floor", "--write-volume"});
        if (paper) refuse_options(app, "--paper (the CPU engine's table)", {"--backends", "--devices"});
        if (!write_path.empty() && !voxmesh::io::ends_with_nocase(write_path, ".nrrd"))
            throw voxmesh::Error("--write-volume writes NRRD: give a name ending in .nrrd, not '" + write_path + "'");
        drop_repeats(fields);
        drop_repeats(inputs);
        drop_repeats(types);
        drop_repeats(sizes);
        drop_repeats(backends);
        if (sculpt) {
            handle_signal_unless_ignored(SIGINT, on_sigint);
            return run_sculpt(sizes_opt->count() ? sizes : std::vector<std::size_t>{256, 512},
                              threads_opt->count() && !threads.empty() ? threads[0] : 0, dabs, settings.pause_ms,
                              backends, json, settings.quiet);
        }
        if (paper) {
            if (!sizes_opt->count()) sizes = {64, 128, 256, 512};
            if (!threads_opt->count()) threads = {1, 2, 4, 6, 16};
        }
        if (threads.empty()) threads = {1u, hardware_threads()};
        for (auto& t : threads)
            if (t == 0) t = hardware_threads();
        drop_repeats(threads);
        if (fields.empty() && inputs.empty()) fields = {"sphere"};
        std::vector<voxmesh::Field> field_ids;
        for (const auto& f : fields) field_ids.push_back(voxmesh::parse_field(f));
        std::vector<voxmesh::ScalarType> type_ids;
        for (const auto& t : types) type_ids.push_back(parse_type(t));
        if (mesh_ops) {
            handle_signal_unless_ignored(SIGINT, on_sigint);
            return run_mesh_ops(field_ids, type_ids, sizes_opt->count() ? sizes : std::vector<std::size_t>{256, 512},
                                settings.repeat, seed, json, settings.quiet);
        }
        std::vector<voxmesh::Backend> backend_ids;
        for (const auto& b : backends) backend_ids.push_back(parse_backend(b));
        const std::vector<Combo> device_sel = parse_devices(devices);

        // The inputs, as recipes: built-in ones are generated one at a time (512^3 f32 is 512 MiB).
        struct Recipe {
            bool file = false;
            std::string path;
            voxmesh::Field field{};
            voxmesh::ScalarType type{};
            std::size_t size = 0;
            double iso = NAN;  // a file's: --iso, else its voxmesh_iso
        };
        std::vector<Recipe> recipes;
        for (auto f : field_ids)
            for (auto t : type_ids)
                for (auto n : sizes) recipes.push_back({false, "", f, t, n});
        // Files, and the iso each needs, checked before any run: a bad one found after hours of
        // runs threw those results away.
        for (const auto& p : inputs) {
            Recipe rc{true, p, {}, {}, 0, iso};
            const voxmesh::VolumeInfo info = voxmesh::read_volume_info(p);  // a bad file fails here
            if (std::isnan(iso)) {
                std::optional<double> recorded;
                try {
                    recorded = voxmesh::recorded_iso(info, p);
                } catch (const voxmesh::Error& e) {
                    throw voxmesh::Error(std::string(e.what()) + ": give --iso");
                }
                if (!recorded) throw voxmesh::Error("'" + p + "' has no " + voxmesh::kRecordedIsoKey + ": give --iso");
                rc.iso = *recorded;
            }
            recipes.push_back(rc);
        }

        if (!write_path.empty()) {
            if (recipes.size() != 1 || recipes[0].file)
                throw voxmesh::Error("--write-volume needs exactly one built-in field, type and size");
            const Recipe& rc = recipes[0];
            voxmesh::FieldVolume fv = voxmesh::make_field(rc.field, rc.size, rc.type, seed);
            Input in;
            in.field = voxmesh::field_name(rc.field);
            in.type = voxmesh::scalar_name(rc.type);
            in.dims = fv.volume.dims;
            in.iso = std::isnan(iso) ? fv.iso : iso;
            in.volume = std::move(fv.volume);
            write_volume_nrrd(write_path, in);
            std::fprintf(stderr, "wrote %s: %s %s %zu^3, iso %.17g\n", write_path.c_str(), in.field.c_str(),
                         in.type.c_str(), rc.size, in.iso);
            return 0;
        }

        // Every combination for one input.
        auto combos_for = [&]() {
            std::vector<Combo> out;
            for (auto b : backend_ids) {
                if (b == voxmesh::Backend::Cpu || b == voxmesh::Backend::Auto) {
                    for (unsigned t : threads) {
                        Combo c;
                        c.backend = b;
                        c.device = b == voxmesh::Backend::Cpu ? "cpu" : "auto";
                        c.threads = t;
                        out.push_back(c);
                    }
                } else {
                    for (const Combo& d : device_sel) {
                        if (b == voxmesh::Backend::OpenCL) {
                            // Device-only: CPU thread counts do not apply; the host side uses all cores.
                            Combo c = d;
                            c.backend = b;
                            c.threads = hardware_threads();
                            out.push_back(c);
                        } else {
                            for (unsigned t : threads) {
                                Combo c = d;
                                c.backend = b;
                                c.threads = t;
                                out.push_back(c);
                            }
                        }
                    }
                }
            }
            return out;
        };
        const std::size_t total = recipes.size() * combos_for().size();

        handle_signal_unless_ignored(SIGINT, on_sigint);

        std::vector<Result> results;
        std::string failure;  // an input that could not be made or read: reported after the results
        std::size_t done = 0;
        for (const Recipe& rc : recipes) {
            if (g_interrupted) break;
            Input in;
            const double g0 = now_s();
            try {
                if (rc.file) {
                    in.field = rc.path;
                    in.volume = voxmesh::read_volume(rc.path);
                    in.iso = rc.iso;
                } else {
                    voxmesh::FieldVolume fv = voxmesh::make_field(rc.field, rc.size, rc.type, seed);
                    in.field = voxmesh::field_name(rc.field);
                    in.iso = std::isnan(iso) ? fv.iso : iso;
                    in.volume = std::move(fv.volume);
                }
            } catch (const std::exception& e) {
                failure = e.what();
                break;
            }
            in.type = voxmesh::scalar_name(in.volume.type);
            in.dims = in.volume.dims;
            if (!settings.quiet)
                std::fprintf(stderr, "input %s %s %zux%zux%zu iso %g (%s in %.2f s)\n", in.field.c_str(),
                             in.type.c_str(), in.dims[0], in.dims[1], in.dims[2], in.iso,
                             rc.file ? "loaded" : "generated", now_s() - g0);

            std::map<unsigned, double> floors;
            const std::vector<Combo> combos = combos_for();
            std::vector<Result> interleaved;
            if (settings.interleave) {
                if (!settings.quiet)
                    std::fprintf(stderr, "%zu combinations taking turns, %d runs each ...\n", combos.size(),
                                 settings.repeat);
                interleaved = measure_interleaved(in, combos, settings);
            }
            for (std::size_t ci = 0; ci < combos.size(); ++ci) {
                const Combo& c = combos[ci];
                // Interleaved, every combination has run its rounds: keep those that finished any.
                if (g_interrupted && !settings.interleave) break;
                ++done;
                if (!settings.quiet)
                    std::fprintf(stderr, "[%zu/%zu] %s %s %s %s %s t=%u ...", done, total, in.field.c_str(),
                                 in.type.c_str(), std::to_string(in.dims[0]).c_str(), voxmesh::backend_name(c.backend),
                                 c.device.c_str(), c.threads);
                std::fflush(stderr);
                Result r = settings.interleave ? std::move(interleaved[ci]) : measure(in, c, settings);
                if (r.status == "interrupted") {
                    if (settings.interleave) continue;
                    break;
                }
                if (!r.floor_in_rounds && !no_floor && !g_interrupted) {  // else read between the runs
                    auto it = floors.find(c.threads);
                    if (it == floors.end())
                        it = floors.emplace(c.threads, streaming_floor(in.volume.view(), c.threads, settings.repeat,
                                                                       1)).first;
                    r.floor_s = it->second;
                }
                if (r.status == "ok" && r.floor_s > 0) r.floor_ratio = r.median_s / r.floor_s;
                if (!settings.quiet) {
                    if (r.status == "ok")
                        std::fprintf(stderr, " %.4f s median, %zu triangles, %.2fx floor\n", r.median_s, r.triangles,
                                     r.floor_ratio);
                    else
                        std::fprintf(stderr, " %s: %s\n", r.status.c_str(), r.error.c_str());
                }
                results.push_back(std::move(r));
            }
        }
        if (g_interrupted) {
            // The run in progress keeps the runs it finished: say so where they are fewer.
            const std::size_t last_runs = results.empty() ? 0 : results.back().times.size();
            if (last_runs > 0 && last_runs < std::size_t(std::max(1, settings.repeat)))
                std::fprintf(stderr, "\ninterrupted: printing %zu result(s), the last from %zu of %d runs\n",
                             results.size(), last_runs, settings.repeat);
            else
                std::fprintf(stderr, "\ninterrupted: printing the %zu finished result(s)\n", results.size());
        }

        // The machine's own speed-up per thread count, beside the measured ones (when there are two
        // or more counts to compare). Counts above the cores get the ceiling of all cores: the CPU
        // engine starts no more workers than cores, whatever Options::threads asks for.
        std::map<unsigned, ComputeRates> rates;
        for (const auto& r : results) rates.emplace(r.threads, ComputeRates{});
        if (rates.size() > 1 && !g_interrupted) {
            std::map<unsigned, ComputeRates> measured;
            for (auto& [count, rate] : rates) {
                const unsigned running = std::clamp(count, 1u, hardware_threads());
                auto it = measured.find(running);
                if (it == measured.end()) it = measured.emplace(running, compute_rates(running)).first;
                rate = it->second;
            }
        } else {
            rates.clear();
        }
        compute_speedups(results, rates);
        if (!save_path.empty()) save_json(results, save_path);
        if (json) print_json(results);
        else if (csv) print_csv(results);
        else {
            print_table(results);
            if (paper) {
                const std::string f = fields.empty() ? "sphere" : fields[0];
                print_paper(results, f, types[0]);
            }
        }
        std::fflush(stdout);
        if (!failure.empty()) {
            std::fprintf(stderr, "voxmesh-bench: %s\n", failure.c_str());
            return 1;
        }
        if (g_interrupted) return 130;
        // Nothing could run (no such device, an engine not built): a failure, not a result.
        if (std::none_of(results.begin(), results.end(), [](const Result& r) { return r.status == "ok"; })) {
            std::fprintf(stderr, "voxmesh-bench: no combination could run here\n");
            return 1;
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "voxmesh-bench: %s\n", e.what());
        return 1;
    }
}
