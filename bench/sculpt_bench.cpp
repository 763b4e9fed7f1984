// voxmesh-bench --sculpt: a built-in stroke path over a sculpted sphere, update latency
// percentiles beside the full re-mesh time (the paper re-meshed everything every frame).
#include "bench.hpp"

#include <voxmesh/sculpt.hpp>

#include <cstdio>

namespace vmbench {

int run_sculpt(const std::vector<std::size_t>& sizes, unsigned threads, std::size_t dabs, bool json, bool quiet) {
    for (std::size_t n : sizes) {
        if (g_interrupted) break;
        voxmesh::SculptBenchOptions options;
        options.resolution = n;
        options.dabs = dabs;
        options.threads = threads;
        const auto log = [&](const std::string& line) {
            if (!quiet) std::fprintf(stderr, "[sculpt %zu^3] %s\n", n, line.c_str());
        };
        const voxmesh::SculptBenchResult r = voxmesh::run_sculpt_benchmark(options, log);
        if (json) {
            std::printf("{\"bench\":\"sculpt\",\"size\":%zu,\"threads\":%u,\"dabs\":%zu,\"update_p50_ms\":%.3f,"
                        "\"update_p95_ms\":%.3f,\"update_p99_ms\":%.3f,\"update_cpu_p50_ms\":%.3f,"
                        "\"frame_p95_ms\":%.3f,\"blocks_per_dab\":%.2f,\"full_extract_ms\":%.3f,"
                        "\"mesh_assembly_ms\":%.3f,\"triangles\":%zu}\n",
                        n, r.threads, r.update.count, r.update.p50, r.update.p95, r.update.p99, r.update_cpu.p50,
                        r.frame.p95, r.mean_blocks_remeshed, r.full_extract_ms, r.mesh_assembly_ms, r.triangles);
        } else {
            std::printf("%s\n", voxmesh::format_sculpt_benchmark(r).c_str());
        }
        std::fflush(stdout);
    }
    return g_interrupted ? 130 : 0;
}

}  // namespace vmbench
