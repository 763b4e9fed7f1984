// Stroke scripts, the built-in stroke path and model, and the sculpt latency benchmark that
// the CLI (`voxmesh sculpt`) and voxmesh-bench (`--sculpt`) call.
#include <voxmesh/sculpt.hpp>

#include "core/out_of_memory.hpp"
#include "core/dims_text.hpp"
#include "core/parallel.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <locale>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace voxmesh {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

[[noreturn]] void script_error(const std::string& name, std::size_t line, const std::string& what) {
    throw Error(name + ":" + std::to_string(line) + ": " + what);
}

double parse_number(const std::string& token, const std::string& name, std::size_t line, const char* what) {
    double v = 0;
    const char* begin = token.data();
    const char* end = begin + token.size();
    if (!token.empty() && *begin == '+') ++begin;
    // from_chars takes a '-' itself: one after the '+' ("+-3") is no number.
    const bool signed_twice = begin != token.data() && begin != end && *begin == '-';
    const auto [ptr, ec] = std::from_chars(begin, end, v);
    if (ec == std::errc::result_out_of_range && ptr == end && !signed_twice)
        script_error(name, line, std::string(what) + " '" + token + "' is out of range (too large or too small for a double)");
    if (ec != std::errc() || ptr != end || signed_twice)
        script_error(name, line, std::string(what) + " '" + token + "' is not a number");
    if (!std::isfinite(v)) script_error(name, line, std::string(what) + " '" + token + "' is not finite");
    return v;
}

}  // namespace

// ---------------------------------------------------------------- scripts

namespace {

std::vector<ScriptDab> parse_script_lines(std::istream& in, const std::string& name) {
    std::vector<ScriptDab> dabs;
    Units units = Units::Samples;
    std::string text;
    std::size_t line = 0;
    while (std::getline(in, text)) {
        ++line;
        // A UTF-8 byte order mark, as some editors write: invisible, it made the first op
        // 'unknown' in a message that showed it as it should be.
        if (line == 1 && text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);
        // A control byte (a NUL above all) would end or garble the error messages that quote
        // the line's words; a stroke script is text, so such a byte means the wrong file.
        for (const char c : text) {
            const auto byte = static_cast<unsigned char>(c);
            if ((byte < 0x20 && !std::isspace(byte)) || byte == 0x7f) {
                char hex[8];
                std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned>(byte));
                script_error(name, line, std::string("control byte ") + hex + " in the script (not a text file?)");
            }
        }
        const std::size_t hash = text.find('#');
        if (hash != std::string::npos) text.resize(hash);
        std::istringstream fields(text);
        std::vector<std::string> tokens;
        for (std::string t; fields >> t;) tokens.push_back(t);
        if (tokens.empty()) continue;
        if (tokens[0] == "units") {
            if (tokens.size() != 2 || (tokens[1] != "world" && tokens[1] != "samples"))
                script_error(name, line, "expected 'units world' or 'units samples'");
            units = tokens[1] == "world" ? Units::World : Units::Samples;
            continue;
        }
        ScriptDab d;
        d.line = line;
        d.units = units;
        try {
            d.dab.op = parse_brush_op(tokens[0]);
        } catch (const Error&) {
            script_error(name, line,
                         "unknown op '" + tokens[0] + "' (expected add, subtract, smooth, set or units)");
        }
        if (tokens.size() != 6)
            script_error(name, line,
                         "expected 'op x y z radius strength', got " + std::to_string(tokens.size()) + " fields");
        for (int k = 0; k < 3; ++k) d.dab.center[k] = parse_number(tokens[1 + k], name, line, "coordinate");
        d.dab.radius = parse_number(tokens[4], name, line, "radius");
        d.dab.strength = parse_number(tokens[5], name, line, "strength");
        if (!(d.dab.radius > 0)) script_error(name, line, "radius must be positive, got " + tokens[4]);
        dabs.push_back(d);
    }
    if (in.bad()) throw Error(name + ": read error");
    return dabs;
}

}  // namespace

std::vector<ScriptDab> parse_stroke_script(std::istream& in, const std::string& name) {
    // A script of millions of dabs, or one endless line, can outgrow memory.
    return detail::out_of_memory_as_error([&] { return "'" + name + "': out of memory reading the stroke script"; },
                                          [&] { return parse_script_lines(in, name); });
}

std::vector<ScriptDab> read_stroke_script(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw Error("'" + path + "': is a directory, not a stroke script");
    std::ifstream in(path);
    if (!in) throw Error("'" + path + "': cannot open the stroke script");
    return parse_stroke_script(in, path);
}

void run_strokes(Sculpt& sculpt, const std::vector<ScriptDab>& dabs,
                 const std::function<void(const StrokeFrame&)>& on_frame) {
    for (std::size_t i = 0; i < dabs.size(); ++i) {
        StrokeFrame frame;
        frame.frame = i;
        frame.dab = dabs[i];
        const auto t0 = Clock::now();
        sculpt.apply(dabs[i].dab, dabs[i].units);
        frame.edit_seconds = ms_since(t0) / 1000;
        const UpdateResult r = sculpt.update();
        frame.update_seconds = r.seconds;
        frame.blocks_changed = r.changed.size();
        frame.blocks_remeshed = r.remeshed;
        if (on_frame) on_frame(frame);
    }
}

void run_stroke_script(Sculpt& sculpt, const std::string& path,
                       const std::function<void(const StrokeFrame&)>& on_frame) {
    run_strokes(sculpt, read_stroke_script(path), on_frame);
}

// ---------------------------------------------------------------- built-in model and path

namespace {
struct SphereModel {
    std::array<double, 3> centre;
    double radius;
};
SphereModel sphere_model(std::array<std::size_t, 3> dims) {
    const double n = static_cast<double>(std::min({dims[0], dims[1], dims[2]}));
    return {{0.5 * static_cast<double>(dims[0] - 1), 0.5 * static_cast<double>(dims[1] - 1),
             0.5 * static_cast<double>(dims[2] - 1)},
            0.35 * n};
}
}  // namespace

Sculpt make_sculpt_sphere(std::size_t n, const SculptOptions& options) {
    if (n < 8) throw Error("sculpt: the sphere model needs n >= 8, got " + std::to_string(n));
    // Before the table of n sines: an n whose volume cannot exist is that Error, not the
    // table's std::length_error or std::bad_alloc.
    checked_volume_bytes({n, n, n}, ScalarType::F32);
    const SphereModel m = sphere_model({n, n, n});
    const double k = 5 / m.radius, bump = 0.03 * m.radius;
    // The bumps are separable: sin(k dx) sin(k dy) sin(k dz) from one table per axis.
    auto table = std::make_shared<std::vector<double>>(n);
    for (std::size_t i = 0; i < n; ++i) (*table)[i] = std::sin(k * (static_cast<double>(i) - m.centre[0]));
    SculptOptions o = options;
    o.iso = 0;
    return Sculpt::from_function(
        {n, n, n}, ScalarType::F32,
        [m, bump, table](double x, double y, double z) {
            const double dx = x - m.centre[0], dy = y - m.centre[1], dz = z - m.centre[2];
            const std::vector<double>& s = *table;
            return m.radius - std::sqrt(dx * dx + dy * dy + dz * dz) +
                   bump * s[static_cast<std::size_t>(x)] * s[static_cast<std::size_t>(y)] * s[static_cast<std::size_t>(z)];
        },
        o);
}

std::vector<ScriptDab> builtin_stroke_path(std::size_t n_dabs, std::array<std::size_t, 3> dims, double radius_min,
                                           double radius_max) {
    if (n_dabs == 0) throw Error("sculpt: the stroke path needs at least one dab");
    if (!(radius_min > 0) || !(radius_max >= radius_min) || !std::isfinite(radius_max))
        throw Error("sculpt: stroke radii must satisfy 0 < min <= max");
    // sphere_model takes dims - 1: a 0 would wrap; fewer than 2 samples is no volume to sculpt.
    if (std::min({dims[0], dims[1], dims[2]}) < 2)
        throw Error("sculpt: the stroke path needs a volume of at least 2 samples per axis, got " +
                    detail::dims_text(dims));
    const SphereModel m = sphere_model(dims);
    const double pi = std::numbers::pi;
    // A count no vector can hold is an Error too (it let std::length_error out).
    if (n_dabs > std::vector<ScriptDab>().max_size())
        throw OutOfMemoryError("sculpt: " + std::to_string(n_dabs) + " dabs are more than memory can hold");
    auto dabs = detail::out_of_memory_as_error(
        [&] { return "sculpt: out of memory for a stroke path of " + std::to_string(n_dabs) + " dabs"; },
        [&] { return std::vector<ScriptDab>(n_dabs); });
    for (std::size_t i = 0; i < n_dabs; ++i) {
        const double t = n_dabs > 1 ? static_cast<double>(i) / static_cast<double>(n_dabs - 1) : 0.0;
        // Three turns of a spiral from near one pole to near the other, on the surface.
        const double theta = pi * (0.2 + 0.6 * t), phi = 2 * pi * 3 * t;
        ScriptDab& d = dabs[i];
        d.line = i + 1;
        d.dab.center = {m.centre[0] + m.radius * std::sin(theta) * std::cos(phi),
                        m.centre[1] + m.radius * std::sin(theta) * std::sin(phi),
                        m.centre[2] + m.radius * std::cos(theta)};
        d.dab.radius = radius_min + (radius_max - radius_min) * (0.5 + 0.5 * std::sin(2 * pi * 4 * t));
        if (i % 5 == 4) {
            d.dab.op = BrushOp::Smooth;
            d.dab.strength = 0.5;
        } else {
            d.dab.op = (i / 25) % 2 ? BrushOp::Subtract : BrushOp::Add;  // strokes of 25 dabs
            d.dab.strength = 0.75;
        }
    }
    return dabs;
}

// ---------------------------------------------------------------- benchmark

LatencySummary summarize_latencies(std::vector<double> ms) {
    LatencySummary s;
    s.count = ms.size();
    if (ms.empty()) return s;
    std::sort(ms.begin(), ms.end());
    auto rank = [&](double p) {
        const double r = std::ceil(p / 100 * static_cast<double>(ms.size()));
        const std::size_t i = r < 1 ? 0 : static_cast<std::size_t>(r) - 1;
        return ms[std::min(i, ms.size() - 1)];
    };
    s.p50 = rank(50);
    s.p95 = rank(95);
    s.p99 = rank(99);
    s.max = ms.back();
    double sum = 0;
    for (double v : ms) sum += v;
    s.mean = sum / static_cast<double>(ms.size());
    return s;
}

SculptBenchResult run_sculpt_benchmark(const SculptBenchOptions& options,
                                       const std::function<void(const std::string&)>& log) {
    SculptBenchResult r;
    r.options = options;
    const std::size_t n = options.resolution;
    auto say = [&](const std::string& s) {
        if (log) log(s);
    };
    SculptOptions so;
    so.threads = options.threads;
    so.block_size = options.block_size;
    so.backend = options.backend;
    so.device = options.device;
    so.log = [&](const std::string& w) {
        r.warnings.push_back(w);
        say(w);
    };
    auto t = Clock::now();
    Sculpt sculpt = make_sculpt_sphere(n, so);
    r.build_model_ms = ms_since(t);
    r.backend = sculpt.backend();
    r.device = sculpt.device_name();
    say("sculpt " + std::to_string(n) + "^3: model built in " + std::to_string(r.build_model_ms) + " ms");

    t = Clock::now();
    sculpt.update();
    r.initial_update_ms = ms_since(t);

    const auto path = builtin_stroke_path(options.dabs, {n, n, n}, options.radius_min, options.radius_max);
    std::vector<double> update_ms, frame_ms, cpu_ms;
    update_ms.reserve(path.size());
    frame_ms.reserve(path.size());
    cpu_ms.reserve(path.size());
    std::size_t remeshed = 0;
    for (const ScriptDab& d : path) {
        if (options.stop && options.stop()) break;
        if (options.pause_ms > 0)
            std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(options.pause_ms));
        const auto t0 = Clock::now();
        sculpt.apply(d.dab, d.units);
        const auto t1 = Clock::now();
        const std::clock_t c1 = std::clock();
        const UpdateResult u = sculpt.update();
        const std::clock_t c2 = std::clock();
        const auto t2 = Clock::now();
        update_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
        frame_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t0).count());
        cpu_ms.push_back(1000.0 * static_cast<double>(c2 - c1) / CLOCKS_PER_SEC);
        remeshed += u.remeshed;
    }
    r.update = summarize_latencies(update_ms);
    r.frame = summarize_latencies(frame_ms);
    r.update_cpu = summarize_latencies(cpu_ms);
    r.mean_blocks_remeshed = update_ms.empty() ? 0 : static_cast<double>(remeshed) / static_cast<double>(update_ms.size());
    say("sculpt " + std::to_string(n) + "^3: " + std::to_string(update_ms.size()) + " dabs replayed");

    t = Clock::now();
    const Mesh assembled = sculpt.mesh();
    r.mesh_assembly_ms = ms_since(t);
    r.vertices = assembled.vertex_count();
    r.triangles = assembled.triangle_count();
    r.full_mesh_bytes = 4 * (assembled.positions.size() + assembled.normals.size() + assembled.indices.size());
    r.memory = sculpt.memory();

    if (options.extract_repeats > 0) {
        Options eo;
        eo.iso = sculpt.options().iso;
        eo.backend = Backend::Cpu;
        eo.threads = options.threads;
        // The baseline a sculpting loop without blocks would run every frame: the whole volume
        // re-meshed into the same Mesh (extract_into keeps its storage, no fresh pages).
        std::vector<double> times;
        Mesh full;
        for (std::size_t i = 0; i < options.extract_repeats; ++i) {
            Stats stats;
            t = Clock::now();
            extract_into(sculpt.view(), eo, full, stats);
            times.push_back(ms_since(t));
        }
        r.full_extract_ms = summarize_latencies(times).p50;
    }
    r.threads = options.threads;
    if (r.threads == 0) r.threads = detail::resolve_threads(0);
    r.workers = detail::running_threads(options.threads);  // as the Sculpt resolves them
    return r;
}

std::string format_sculpt_benchmark(const SculptBenchResult& r) {
    std::ostringstream o;
    o.imbue(std::locale::classic());  // "1.50", not the program's global locale's "1,50"
    o << std::fixed << std::setprecision(2);
    const std::size_t n = r.options.resolution;
    o << "sculpt " << n << "^3, block " << r.options.block_size << ", ";
    if (r.backend == Backend::OpenCL) o << "OpenCL '" << r.device << "', ";
    else if (r.workers < r.threads) o << r.threads << " threads asked for, run on " << r.workers << ", ";
    else o << r.threads << " threads, ";
    o << r.update.count << " dabs (radius " << r.options.radius_min << ".." << r.options.radius_max << ")";
    if (r.options.pause_ms > 0) o << ", each after a " << r.options.pause_ms << " ms sleep";
    o << "\n";
    o << "  update latency ms: p50 " << r.update.p50 << "  p95 " << r.update.p95 << "  p99 " << r.update.p99
      << "  max " << r.update.max << "  mean " << r.update.mean << "\n";
    o << "  edit+update ms:    p50 " << r.frame.p50 << "  p95 " << r.frame.p95 << "  p99 " << r.frame.p99
      << "  max " << r.frame.max << "\n";
    o << "  update CPU ms (all workers): p50 " << r.update_cpu.p50 << "  p95 " << r.update_cpu.p95 << "  p99 "
      << r.update_cpu.p99 << "\n";
    o << "  blocks re-meshed per update: " << r.mean_blocks_remeshed << "\n";
    o << "  full extract ms (median): " << r.full_extract_ms << "   initial update (all blocks) ms: "
      << r.initial_update_ms << "   mesh() assembly ms: " << r.mesh_assembly_ms << "\n";
    o << "  mesh: " << r.vertices << " vertices, " << r.triangles << " triangles, " << r.full_mesh_bytes
      << " bytes; block meshes " << r.memory.block_meshes << " bytes + table " << r.memory.block_table << " ("
      << std::setprecision(1)
      << (r.full_mesh_bytes ? 100.0 * (double(r.memory.block_meshes + r.memory.block_table) / double(r.full_mesh_bytes) - 1)
                            : 0.0)
      << " % over the full mesh)\n";
    return o.str();
}

}  // namespace voxmesh
