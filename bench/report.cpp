// Printing results: a readable table, CSV, JSON lines, and the paper's Table 1 beside ours.
#include "bench.hpp"

#include "core/atomic_file.hpp"

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fcntl.h>
#include <map>
#include <sstream>
#include <string>
#include <tuple>

#include <unistd.h>

namespace vmbench {

namespace {

// The series a speedup is taken within: same input, backend and device.
std::string series_key(const Result& r) {
    return r.field + "|" + r.type + "|" + r.size_label() + "|" + r.backend + "|" + r.device;
}

// The length of the well-formed UTF-8 sequence at s[i], or 0 where it is not one.
std::size_t utf8_length(const std::string& s, std::size_t i) {
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char b = byte(i);
    const std::size_t n = b < 0x80 ? 1 : (b >> 5) == 0x6 ? 2 : (b >> 4) == 0xe ? 3 : (b >> 3) == 0x1e ? 4 : 0;
    if (n == 0 || i + n > s.size()) return 0;
    for (std::size_t k = 1; k < n; ++k)
        if ((byte(i + k) >> 6) != 0x2) return 0;
    return n;
}

// A JSON string's contents. Bytes that are not UTF-8 (a file name in another encoding) become
// U+FFFD: JSON text must be UTF-8, and the line must stay parseable.
std::string json_escape(const std::string& s) {
    std::string o;
    for (std::size_t i = 0; i < s.size(); ++i) {
        const char c = s[i];
        if (static_cast<unsigned char>(c) >= 0x80) {
            const std::size_t n = utf8_length(s, i);
            if (n == 0) {
                o += "\\ufffd";
            } else {
                o.append(s, i, n);
                i += n - 1;
            }
            continue;
        }
        switch (c) {
            case '"': o += "\\\""; break;
            case '\\': o += "\\\\"; break;
            case '\n': o += "\\n"; break;
            case '\t': o += "\\t"; break;
            default:
                if (static_cast<unsigned char>(c) < 0x20) {
                    char buf[8];
                    std::snprintf(buf, sizeof buf, "\\u%04x", c);
                    o += buf;
                } else {
                    o += c;
                }
        }
    }
    return o;
}

std::string num(double v, const char* fmt = "%.6g") {
    if (!std::isfinite(v)) return "null";
    char buf[64];
    std::snprintf(buf, sizeof buf, fmt, v);
    return buf;
}

std::string pause_note(double pause_ms) {
    return pause_ms > 0 ? ", each after a " + num(pause_ms) + " ms sleep (--pause)" : "";
}

std::string csv_field(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string o = "\"";
    for (char c : s) o += (c == '"') ? std::string("\"\"") : std::string(1, c);
    return o + "\"";
}

std::string joined(const std::vector<std::string>& v, const char* sep) {
    std::string o;
    for (const auto& s : v) o += (o.empty() ? "" : sep) + s;
    return o;
}

std::string backend_label(const Result& r) {
    if (r.status == "ok" && r.backend_ran != r.backend) return r.backend + ">" + r.backend_ran;
    return r.backend;
}

}  // namespace

void compute_speedups(std::vector<Result>& results, const std::map<unsigned, ComputeRates>& compute_rates) {
    std::map<std::string, const Result*> base;
    for (const auto& r : results) {
        if (r.status != "ok") continue;
        auto& b = base[series_key(r)];
        if (!b || r.threads < b->threads) b = &r;
    }
    for (auto& r : results) {
        if (r.status != "ok") continue;
        const Result* b = base[series_key(r)];
        if (b && r.median_s > 0) {
            r.speedup = b->median_s / r.median_s;
            r.speedup_base_threads = b->threads;
            const auto at = compute_rates.find(r.threads), base_at = compute_rates.find(b->threads);
            if (at != compute_rates.end() && base_at != compute_rates.end()) {
                if (base_at->second.chain > 0) r.compute_ceiling = at->second.chain / base_at->second.chain;
                if (base_at->second.wide > 0) r.compute_ceiling_wide = at->second.wide / base_at->second.wide;
            }
            if (r.floor_s > 0 && b->floor_s > 0) r.floor_speedup = b->floor_s / r.floor_s;
        }
    }
}

void print_table(const std::vector<Result>& results) {
    std::printf("%-8s %-4s %-6s %-10s %-8s %3s %9s %9s %9s %8s %10s %9s %8s %6s %6s %6s %6s %7s %7s %6s %8s %8s %8s "
                "%8s %8s\n",
                "field", "type", "size", "backend", "device", "thr", "median_s", "min_s", "max_s", "Mvox/s",
                "triangles", "floor_s", "x_floor", "speed", "ceil", "ceil_w", "fl_sp", "rss_MB", "ext_MB", "over%", "classify",
                "scan", "generate", "kernel", "transfer");
    for (const auto& r : results) {
        if (r.status != "ok") {
            std::printf("%-8s %-4s %-6s %-10s %-8s %3u  %s: %s\n", r.field.c_str(), r.type.c_str(),
                        r.size_label().c_str(), r.backend.c_str(), r.device.c_str(), r.threads, r.status.c_str(),
                        r.error.c_str());
            continue;
        }
        std::string speed = r.speedup > 0 ? num(r.speedup, "%.2f") : "-";
        std::string ceiling = r.compute_ceiling > 0 ? num(r.compute_ceiling, "%.2f") : "-";
        std::string ceiling_wide = r.compute_ceiling_wide > 0 ? num(r.compute_ceiling_wide, "%.2f") : "-";
        std::string floor_speed = r.floor_speedup > 0 ? num(r.floor_speedup, "%.2f") : "-";
        std::string kernel = r.kernel_s > 0 ? num(r.kernel_s, "%.4f") : "-";
        std::string transfer = r.transfer_s > 0 ? num(r.transfer_s, "%.4f") : "-";
        // No floor (--no-floor, or interrupted before it was read): shown as missing, not 0.
        std::string floor_s = r.floor_s > 0 ? num(r.floor_s, "%.6f") : "-";
        std::string floor_ratio = r.floor_ratio > 0 ? num(r.floor_ratio, "%.2f") : "-";
        // Memory the extraction took beyond its mesh, in % of volume + mesh (issue 6: <= 10 %).
        const double over = 100 * (r.extract_rss_mb - r.mesh_mb) / std::max(r.volume_mb + r.mesh_mb, 1e-9);
        std::printf("%-8s %-4s %-6s %-10s %-8s %3u %9.4f %9.4f %9.4f %8.1f %10zu %9s %8s %6s %6s %6s %6s %7.0f %7.0f "
                    "%6.1f %8.4f %8.4f %8.4f %8s %8s\n",
                    r.field.c_str(), r.type.c_str(), r.size_label().c_str(), backend_label(r).c_str(),
                    r.device.c_str(), r.threads, r.median_s, r.min_s, r.max_s, r.mvox_s, r.triangles, floor_s.c_str(),
                    floor_ratio.c_str(), speed.c_str(), ceiling.c_str(), ceiling_wide.c_str(), floor_speed.c_str(), r.peak_rss_mb,
                    r.extract_rss_mb, over, r.classify_s, r.scan_s, r.generate_s, kernel.c_str(), transfer.c_str());
        if (r.setup_rss_mb >= 0)
            std::printf("    note: set-up (--setup-first, one untimed extract before the runs) took %.3f s and %.0f MB\n",
                        r.setup_s, r.setup_rss_mb);
        for (const auto& w : r.warnings) std::printf("    note: %s\n", w.c_str());
    }
    bool any = false;
    for (const auto& r : results) any = any || r.status == "ok";
    if (any) {
        const Result* first = nullptr;
        for (const auto& r : results)
            if (r.status == "ok") {
                first = &r;
                break;
            }
        std::printf("\nmedian/min/max: end-to-end %s seconds over %d runs after %d warmup%s%s; x_floor: median / "
                    "streaming floor (one threaded read of the volume%s); speed: vs the fewest threads of the same "
                    "series; ceil: the same for a compute-only loop on at most as many threads as cores (the "
                    "machine's ceiling; the CPU engine runs no more workers than cores); ceil_w: the same for a loop "
                    "that fills a core's issue width (below ceil where threads share a core, as hyperthreads); fl_sp: the same for the "
                    "streaming floor; rss_MB: process peak RSS while extracting (%s); ext_MB: that peak minus RSS "
                    "before the call; over%%: ext_MB minus the mesh, in %% of volume + mesh (a fresh process: --repeat 1 "
                    "--warmup 0); classify/scan/generate: Stats pass medians; kernel/transfer: OpenCL device time.\n\n",
                    first->reuse_mesh ? "extract_into() (one Mesh reused across runs, --reuse-mesh)" : "extract()",
                    first->repeat, first->warmup,
                    first->interleaved ? " (combinations of an input taking turns run by run, --interleave)" : "",
                    pause_note(first->pause_ms).c_str(),
                    first->floor_in_rounds ? ", median of reads after each run, in the same phases as the runs" : "",
                    first->rss_scope == "run" ? "VmHWM reset before each run"
                                              : "lifetime peak: VmHWM could not be reset on this system");
    }
}

void print_csv(const std::vector<Result>& results) {
    std::printf("field,type,size,nx,ny,nz,iso,backend,backend_ran,device,device_names,threads,normals,repeat,warmup,"
                "status,error,median_s,min_s,max_s,classify_s,scan_s,generate_s,total_s,kernel_s,transfer_s,"
                "triangles,vertices,mvox_s,floor_s,floor_ratio,speedup,speedup_base_threads,compute_ceiling,"
                "compute_ceiling_wide,floor_speedup,peak_rss_mb,extract_rss_mb,rss_scope,volume_mb,mesh_mb,warnings,reuse_mesh,interleaved,"
                "pause_ms,cpu_share,setup_s,setup_rss_mb,hybrid_modes\n");
    for (const auto& r : results) {
        std::ostringstream o;
        o << csv_field(r.field) << ',' << r.type << ',' << r.size_label() << ',' << r.dims[0] << ',' << r.dims[1]
          << ',' << r.dims[2] << ',' << num(r.iso, "%.17g") << ',' << r.backend << ',' << r.backend_ran << ','
          << csv_field(r.device) << ',' << csv_field(r.device_names) << ',' << r.threads << ','
          << (r.normals ? 1 : 0) << ',' << r.repeat << ',' << r.warmup << ',' << r.status << ','
          << csv_field(r.error) << ',' << num(r.median_s) << ',' << num(r.min_s) << ',' << num(r.max_s) << ','
          << num(r.classify_s) << ',' << num(r.scan_s) << ',' << num(r.generate_s) << ',' << num(r.total_s) << ','
          << num(r.kernel_s) << ',' << num(r.transfer_s) << ',' << r.triangles << ',' << r.vertices << ','
          << num(r.mvox_s) << ',' << (r.floor_s > 0 ? num(r.floor_s) : "") << ','
          << (r.floor_ratio > 0 ? num(r.floor_ratio) : "") << ','
          << (r.speedup > 0 ? num(r.speedup) : "") << ',' << r.speedup_base_threads << ','
          << (r.compute_ceiling > 0 ? num(r.compute_ceiling) : "") << ','
          << (r.compute_ceiling_wide > 0 ? num(r.compute_ceiling_wide) : "") << ','
          << (r.floor_speedup > 0 ? num(r.floor_speedup) : "") << ',' << num(r.peak_rss_mb)
          << ',' << num(r.extract_rss_mb) << ',' << r.rss_scope << ',' << num(r.volume_mb) << ','
          << num(r.mesh_mb) << ',' << csv_field(joined(r.warnings, "; ")) << ',' << (r.reuse_mesh ? 1 : 0) << ','
          << (r.interleaved ? 1 : 0) << ',' << num(r.pause_ms) << ',' << (r.cpu_share >= 0 ? num(r.cpu_share) : "")
          << ',' << (r.setup_s >= 0 ? num(r.setup_s) : "") << ',' << (r.setup_rss_mb >= 0 ? num(r.setup_rss_mb) : "")
          << ',' << r.hybrid_modes;
        std::printf("%s\n", o.str().c_str());
    }
}

void print_json(const std::vector<Result>& results, std::FILE* out) {
    for (const auto& r : results) {
        std::ostringstream o;
        const bool ok = r.status == "ok";
        auto opt = [&](double v) { return ok ? num(v) : std::string("null"); };
        o << "{\"field\":\"" << json_escape(r.field) << "\",\"type\":\"" << r.type << "\",\"size\":" << r.dims[0]
          << ",\"dims\":[" << r.dims[0] << ',' << r.dims[1] << ',' << r.dims[2] << "],\"iso\":" << num(r.iso, "%.17g")
          << ",\"backend\":\"" << r.backend << "\",\"backend_ran\":\"" << r.backend_ran << "\",\"device\":\""
          << json_escape(r.device) << "\",\"device_names\":\"" << json_escape(r.device_names)
          << "\",\"threads\":" << r.threads << ",\"normals\":" << (r.normals ? "true" : "false")
          << ",\"reuse_mesh\":" << (r.reuse_mesh ? "true" : "false")
          << ",\"interleaved\":" << (r.interleaved ? "true" : "false") << ",\"pause_ms\":" << num(r.pause_ms)
          << ",\"repeat\":" << r.repeat << ",\"warmup\":" << r.warmup << ",\"status\":\"" << r.status
          << "\",\"error\":\"" << json_escape(r.error) << "\",\"median_s\":" << opt(r.median_s)
          << ",\"min_s\":" << opt(r.min_s) << ",\"max_s\":" << opt(r.max_s) << ",\"times_s\":[";
        for (std::size_t i = 0; i < r.times.size(); ++i) o << (i ? "," : "") << num(r.times[i]);
        o << "],\"classify_s\":" << opt(r.classify_s) << ",\"scan_s\":" << opt(r.scan_s)
          << ",\"generate_s\":" << opt(r.generate_s) << ",\"total_s\":" << opt(r.total_s)
          << ",\"kernel_s\":" << opt(r.kernel_s) << ",\"transfer_s\":" << opt(r.transfer_s)
          << ",\"cpu_share\":" << (r.cpu_share >= 0 ? num(r.cpu_share) : "null") << ",\"hybrid_modes\":\""
          << r.hybrid_modes << '"'
          << ",\"triangles\":" << (ok ? std::to_string(r.triangles) : "null")
          << ",\"vertices\":" << (ok ? std::to_string(r.vertices) : "null") << ",\"mvox_s\":" << opt(r.mvox_s)
          << ",\"floor_s\":" << (r.floor_s > 0 ? num(r.floor_s) : "null")
          << ",\"floor_ratio\":" << (r.floor_ratio > 0 ? opt(r.floor_ratio) : "null")
          << ",\"floor_in_rounds\":" << (r.floor_in_rounds ? "true" : "false")
          << ",\"speedup\":" << (r.speedup > 0 ? num(r.speedup) : "null")
          << ",\"speedup_base_threads\":" << r.speedup_base_threads
          << ",\"compute_ceiling\":" << (r.compute_ceiling > 0 ? num(r.compute_ceiling) : "null")
          << ",\"compute_ceiling_wide\":" << (r.compute_ceiling_wide > 0 ? num(r.compute_ceiling_wide) : "null")
          << ",\"floor_speedup\":" << (r.floor_speedup > 0 ? num(r.floor_speedup) : "null")
          << ",\"peak_rss_mb\":" << opt(r.peak_rss_mb)
          << ",\"extract_rss_mb\":" << opt(r.extract_rss_mb)
          << ",\"setup_rss_mb\":" << (r.setup_rss_mb >= 0 ? num(r.setup_rss_mb) : "null")
          << ",\"setup_s\":" << (r.setup_s >= 0 ? num(r.setup_s) : "null") << ",\"rss_scope\":\"" << r.rss_scope
          << "\",\"volume_mb\":" << num(r.volume_mb) << ",\"mesh_mb\":" << opt(r.mesh_mb) << ",\"warnings\":[";
        for (std::size_t i = 0; i < r.warnings.size(); ++i) o << (i ? "," : "") << '"' << json_escape(r.warnings[i]) << '"';
        o << "]}";
        std::fprintf(out, "%s\n", o.str().c_str());
    }
}

void check_save_path(const std::string& path) {
    // What save_json's atomic write needs: a writable directory to put its temporary in.
    // Checked without creating anything, so an interrupt now cannot leave a file behind.
    const std::filesystem::path target(path);
    const std::filesystem::path dir = voxmesh::detail::target_directory(path);
    // An unnamed file in the directory (O_TMPFILE): nothing to clean up, whatever happens.
    // Filesystems without it get a named probe, removed at once.
    int fd = ::open(dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0600);
    if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
        std::string name = ".";  // built with append: gcc 12 gives a false -Wrestrict on operator+ here
        name.append(target.filename().string()).append(".probe").append(std::to_string(::getpid()));
        const std::string probe = (dir / name).string();
        fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        if (fd >= 0) ::unlink(probe.c_str());
    }
    if (fd < 0) throw voxmesh::Error("cannot write '" + path + "': " + std::strerror(errno));
    ::close(fd);
}

void save_json(const std::vector<Result>& results, const std::string& path) {
    // The library's atomic write: a failed write leaves an earlier file as it was, and a
    // signal handler's remove_partial_outputs() finds the temporary.
    voxmesh::detail::write_file_atomically(path, [&](std::FILE* f) { print_json(results, f); });
}

// ---- the paper's Table 1 ---------------------------------------------------------------------

namespace {
// Serttas, Ayar, Cit, Oz: seconds on an Intel Core Quad 2.50 GHz (see paper-notes.md).
constexpr unsigned kPaperThreads[] = {1, 2, 4, 6, 16};
constexpr std::size_t kPaperSizes[] = {64, 128, 256, 512};
constexpr double kPaperTimes[5][4] = {
    {0.122, 0.383, 1.515, 6.949},
    {0.093, 0.130, 0.651, 3.842},
    {0.041, 0.717, 0.390, 1.450},
    {0.037, 0.596, 0.287, 1.331},
    {0.034, 0.501, 0.261, 1.301},
};
}  // namespace

void print_paper(const std::vector<Result>& results, const std::string& field, const std::string& type) {
    // ours[t][s]: the CPU result for paper thread row t and size column s, if measured.
    const Result* ours[5][4] = {};
    for (const auto& r : results) {
        if (r.status != "ok" || r.backend != "cpu" || r.field != field || r.type != type) continue;
        if (r.dims[0] != r.dims[1] || r.dims[1] != r.dims[2]) continue;
        for (int t = 0; t < 5; ++t)
            for (int s = 0; s < 4; ++s)
                if (r.threads == kPaperThreads[t] && r.dims[0] == kPaperSizes[s]) ours[t][s] = &r;
    }
    auto cell_time = [](const Result* r) { return r ? num(r->median_s, "%.4f") : std::string("-"); };

    std::printf("\nTable 1, reproduced: marching cubes seconds, threads down, resolution across.\n");
    std::printf("ours = voxmesh CPU engine, %s %s, median end-to-end extract(); paper = Serttas et al., Intel Core "
                "Quad 2.50 GHz.\n",
                field.c_str(), type.c_str());
    std::printf("%-8s", "threads");
    for (std::size_t s : kPaperSizes) std::printf(" | %9s %9s %7s", (std::to_string(s) + "^3").c_str(), "paper", "p/ours");
    std::printf("\n");
    for (int t = 0; t < 5; ++t) {
        std::printf("%-8u", kPaperThreads[t]);
        for (int s = 0; s < 4; ++s) {
            const Result* r = ours[t][s];
            const std::string ratio = r && r->median_s > 0 ? num(kPaperTimes[t][s] / r->median_s, "%.1f") : "-";
            std::printf(" | %9s %9.3f %7s", cell_time(r).c_str(), kPaperTimes[t][s], ratio.c_str());
        }
        std::printf("\n");
    }

    std::printf("\nSpeedup over 1 thread (ours vs paper):\n");
    std::printf("%-8s", "threads");
    for (std::size_t s : kPaperSizes) std::printf(" | %7s %7s", (std::to_string(s) + "^3").c_str(), "paper");
    std::printf("\n");
    for (int t = 0; t < 5; ++t) {
        std::printf("%-8u", kPaperThreads[t]);
        for (int s = 0; s < 4; ++s) {
            const Result* r = ours[t][s];
            const Result* one = ours[0][s];
            const std::string sp = r && one && r->median_s > 0 ? num(one->median_s / r->median_s, "%.2f") : "-";
            std::printf(" | %7s %7.2f", sp.c_str(), kPaperTimes[0][s] / kPaperTimes[t][s]);
        }
        std::printf("\n");
    }
    std::printf("(The paper's 128^3 column for 4-16 threads is out of line with the rest as printed.)\n");
}

}  // namespace vmbench
