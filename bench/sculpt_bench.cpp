// voxmesh-bench --sculpt: a built-in stroke path over a sculpted sphere, update latency
// percentiles beside the full re-mesh time (the paper re-meshed everything every frame), for
// each --backends entry (cpu, opencl, auto; default cpu).
#include "bench.hpp"

#include <voxmesh/sculpt.hpp>

#include <cstdio>

namespace vmbench {

namespace {

voxmesh::Backend sculpt_backend(const std::string& name) {
    for (auto b : {voxmesh::Backend::Cpu, voxmesh::Backend::OpenCL, voxmesh::Backend::Auto})
        if (name == voxmesh::backend_name(b)) return b;
    throw voxmesh::Error("--sculpt runs on cpu, opencl or auto, not '" + name + "'");
}

}  // namespace

int run_sculpt(const std::vector<std::size_t>& sizes, unsigned threads, std::size_t dabs, double pause_ms,
               const std::vector<std::string>& backends, bool json, bool quiet) {
    std::vector<voxmesh::Backend> chosen;
    for (const std::string& b : backends) chosen.push_back(sculpt_backend(b));
    for (std::size_t n : sizes) {
        for (voxmesh::Backend backend : chosen) {
            if (g_interrupted) break;
            voxmesh::SculptBenchOptions options;
            options.resolution = n;
            options.dabs = dabs;
            options.threads = threads;
            options.pause_ms = pause_ms;
            options.backend = backend;
            options.stop = [] { return g_interrupted != 0; };  // Ctrl-C: the dabs so far are printed
            const auto log = [&](const std::string& line) {
                if (!quiet) std::fprintf(stderr, "[sculpt %zu^3 %s] %s\n", n, voxmesh::backend_name(backend), line.c_str());
            };
            const voxmesh::SculptBenchResult r = voxmesh::run_sculpt_benchmark(options, log);
            if (json) {
                std::printf("{\"bench\":\"sculpt\",\"size\":%zu,\"backend\":\"%s\",\"device\":\"%s\",\"threads\":%u,"
                            "\"workers\":%u,\"dabs\":%zu,\"pause_ms\":%g,\"update_p50_ms\":%.3f,\"update_p95_ms\":%.3f,"
                            "\"update_p99_ms\":%.3f,\"update_cpu_p50_ms\":%.3f,\"frame_p95_ms\":%.3f,\"blocks_per_dab\":%.2f,"
                            "\"full_extract_ms\":%.3f,\"mesh_assembly_ms\":%.3f,\"triangles\":%zu}\n",
                            n, voxmesh::backend_name(r.backend), r.device.c_str(), r.threads, r.workers, r.update.count, pause_ms,
                            r.update.p50, r.update.p95, r.update.p99, r.update_cpu.p50, r.frame.p95, r.mean_blocks_remeshed,
                            r.full_extract_ms, r.mesh_assembly_ms, r.triangles);
            } else {
                std::printf("%s\n", voxmesh::format_sculpt_benchmark(r).c_str());
            }
            std::fflush(stdout);
        }
    }
    return g_interrupted ? 130 : 0;
}

}  // namespace vmbench
