// voxmesh-bench --mesh-ops: what a program does with a mesh after extract, timed beside the
// extract itself: analyze_topology (on one worker and on all), keep_largest_components,
// write_mesh for each format (to a temporary directory, each file removed after its run), and
// the per-vertex and per-triangle queries in their vector forms (vertex_edges, triangle_cells,
// edge_cell_ranges over vertex_edges' edges).
// Medians over --repeat rounds, each round running every operation once, so that drift in
// the machine's speed spreads over all of them; reported as ratios to the extract.
#include "bench.hpp"

#include "core/components.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <unistd.h>
#include <vector>

namespace vmbench {

namespace {

double seconds_of(const std::function<void()>& run) {
    const double start = now_s();
    run();
    return now_s() - start;
}

// The temporary directory, removed with what is in it however the run ends.
struct TempDir {
    std::filesystem::path path;
    ~TempDir() {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
};

struct Operation {
    std::string name;
    std::function<void()> run;
    std::vector<double> times;
};

}  // namespace

int run_mesh_ops(const std::vector<voxmesh::Field>& fields, const std::vector<voxmesh::ScalarType>& types,
                 const std::vector<std::size_t>& sizes, int repeat, std::uint32_t seed, bool json, bool quiet) {
    std::string dir_template = (std::filesystem::temp_directory_path() / "voxmesh-bench-XXXXXX").string();
    if (!mkdtemp(dir_template.data()))
        throw voxmesh::Error("--mesh-ops: cannot make a temporary directory like " + dir_template);
    const TempDir temp{dir_template};
    const std::filesystem::path& dir = temp.path;
    for (voxmesh::Field field : fields)
        for (voxmesh::ScalarType type : types)
            for (std::size_t n : sizes) {
                if (g_interrupted) break;
                const voxmesh::FieldVolume fv = voxmesh::make_field(field, n, type, seed);
                voxmesh::Options options;
                options.iso = fv.iso;
                options.backend = voxmesh::Backend::Cpu;
                voxmesh::Mesh mesh = voxmesh::extract(fv.volume.view(), options);  // untimed: the pages are warm after
                const std::vector<std::uint64_t> edges = voxmesh::vertex_edges(fv.volume.view(), fv.iso);
                std::vector<Operation> ops;
                ops.push_back({"extract", [&] { mesh = voxmesh::extract(fv.volume.view(), options); }, {}});
                ops.push_back({"analyze_topology_1_worker", [&] { (void)voxmesh::detail::topology_with_workers(mesh, 1); }, {}});
                ops.push_back({"analyze_topology", [&] { (void)voxmesh::analyze_topology(mesh); }, {}});
                ops.push_back({"keep_largest_components", [&] { (void)voxmesh::keep_largest_components(mesh, 1); }, {}});
                for (const char* ext : {"stl", "ply", "obj", "glb"}) {
                    const std::string path = (dir / (std::string("mesh.") + ext)).string();
                    ops.push_back({std::string("write_") + ext, [path, &mesh] {
                                       voxmesh::write_mesh(path, mesh);
                                       std::filesystem::remove(path);
                                   }, {}});
                }
                ops.push_back({"vertex_edges", [&] { (void)voxmesh::vertex_edges(fv.volume.view(), fv.iso); }, {}});
                ops.push_back({"triangle_cells", [&] { (void)voxmesh::triangle_cells(fv.volume.view(), fv.iso); }, {}});
                ops.push_back({"edge_cell_ranges", [&] { (void)voxmesh::edge_cell_ranges(fv.volume.view(), edges, fv.iso); }, {}});
                for (int round = 0; round < repeat && !g_interrupted; ++round)
                    for (Operation& op : ops) {
                        if (g_interrupted) break;
                        op.times.push_back(seconds_of(op.run));
                    }
                // Interrupted: the complete rounds (those the last operation finished) are printed.
                const int rounds = static_cast<int>(ops.back().times.size());
                if (g_interrupted) {
                    for (Operation& op : ops) op.times.resize(static_cast<std::size_t>(rounds));
                    std::fprintf(stderr, "\ninterrupted: %d complete round(s) of %d\n", rounds, repeat);
                    if (rounds == 0) break;
                }
                const double extract_s = median(ops[0].times);
                const std::string what = std::string(voxmesh::field_name(field)) + " " + voxmesh::scalar_name(type) +
                                         " " + std::to_string(n) + "^3";
                if (!json)
                    std::printf("%s: %zu vertices, %zu triangles, %u threads, medians of %d\n", what.c_str(),
                                mesh.vertex_count(), mesh.triangle_count(), hardware_threads(), rounds);
                for (const Operation& op : ops) {
                    const double s = median(op.times), fastest = *std::min_element(op.times.begin(), op.times.end());
                    if (json)
                        std::printf("{\"bench\":\"mesh_ops\",\"field\":\"%s\",\"type\":\"%s\",\"size\":%zu,\"triangles\":%zu,"
                                    "\"threads\":%u,\"op\":\"%s\",\"median_s\":%.6f,\"min_s\":%.6f,\"vs_extract\":%.3f}\n",
                                    voxmesh::field_name(field), voxmesh::scalar_name(type), n, mesh.triangle_count(),
                                    hardware_threads(), op.name.c_str(), s, fastest, s / extract_s);
                    else
                        std::printf("  %-26s %9.4f s (min %.4f)  %6.2fx extract\n", op.name.c_str(), s, fastest,
                                    s / extract_s);
                }
                std::fflush(stdout);
                if (!quiet) std::fprintf(stderr, "[mesh-ops] %s done\n", what.c_str());
                if (g_interrupted) break;
            }
    return g_interrupted ? 130 : 0;
}

}  // namespace vmbench
