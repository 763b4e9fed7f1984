// voxmesh-ab: times extract() of two or more builds of voxmesh in one process, call by call
// in alternating order, on one built-in volume. On a VM whose speed drifts by ±30 % over
// seconds, alternating processes (one binary, then the other) mixes that drift into the
// comparison; alternating calls in one process lets every build see the same phases, the
// same volume in the same pages and the same allocator state. Builds come as shared objects
// (bench/ab/ab.sh makes them from git commits). For development, not a measurement to quote.
#include <voxmesh/fields.hpp>
#include <voxmesh/voxmesh.hpp>

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {

using Extract = voxmesh::Mesh (*)(const voxmesh::VolumeView&, const voxmesh::Options&, voxmesh::Stats&);
using ExtractInto = void (*)(const voxmesh::VolumeView&, const voxmesh::Options&, voxmesh::Mesh&, voxmesh::Stats&);
using MakeField = voxmesh::FieldVolume (*)(voxmesh::Field, std::size_t, voxmesh::ScalarType, std::uint32_t);

// Mangled names of voxmesh::extract(view, options, stats), extract_into(view, options, mesh,
// stats) and voxmesh::make_field.
constexpr const char* kExtract = "_ZN7voxmesh7extractERKNS_10VolumeViewERKNS_7OptionsERNS_5StatsE";
constexpr const char* kExtractInto =
    "_ZN7voxmesh12extract_intoERKNS_10VolumeViewERKNS_7OptionsERNS_4MeshERNS_5StatsE";
constexpr const char* kMakeField = "_ZN7voxmesh10make_fieldENS_5FieldEmNS_10ScalarTypeEj";

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// Parsed here: the program links no voxmesh, so every voxmesh call goes to a loaded build.
voxmesh::ScalarType parse_type(const std::string& name) {
    const std::pair<const char*, voxmesh::ScalarType> types[] = {
        {"u8", voxmesh::ScalarType::U8},   {"i8", voxmesh::ScalarType::I8},   {"u16", voxmesh::ScalarType::U16},
        {"i16", voxmesh::ScalarType::I16}, {"u32", voxmesh::ScalarType::U32}, {"i32", voxmesh::ScalarType::I32},
        {"f32", voxmesh::ScalarType::F32}, {"f64", voxmesh::ScalarType::F64}};
    for (const auto& [text, type] : types)
        if (name == text) return type;
    throw voxmesh::Error("unknown scalar type " + name + " (u8, i8, u16, i16, u32, i32, f32, f64)");
}

voxmesh::Field parse_field(const std::string& name) {
    if (name == "sphere") return voxmesh::Field::Sphere;
    if (name == "gyroid") return voxmesh::Field::Gyroid;
    if (name == "blobs") return voxmesh::Field::Blobs;
    if (name == "ct") return voxmesh::Field::Ct;
    throw voxmesh::Error("unknown field " + name + " (sphere, gyroid, blobs, ct)");
}

void* symbol(void* library, const char* name, const char* path) {
    void* s = dlsym(library, name);
    if (!s) throw voxmesh::Error(std::string(path) + " has no " + name + " (not a voxmesh build?)");
    return s;
}

}  // namespace

int main(int argc, char** argv) try {
    if (argc < 7) {
        std::fprintf(stderr,
                     "usage: voxmesh-ab FIELD TYPE SIZE THREADS ROUNDS LIB.so...\n"
                     "  e.g. voxmesh-ab sphere u8 512 2 30 /tmp/a.so /tmp/b.so\n"
                     "  AB_BACKEND=cpu (default), opencl or cpu,opencl: the engines each build runs\n"
                     "  AB_PAUSE_MS=N: sleep N ms after every call (default 2; 0: back to back)\n"
                     "  AB_REUSE=1: extract_into() one kept Mesh per build, not extract()\n"
                     "  AB_NORMALS=0: no normals\n");
        return 2;
    }
    const voxmesh::Field field = parse_field(argv[1]);
    const voxmesh::ScalarType type = parse_type(argv[2]);
    const std::size_t size = std::stoul(argv[3]);
    const unsigned threads = static_cast<unsigned>(std::stoul(argv[4]));
    const unsigned rounds = static_cast<unsigned>(std::stoul(argv[5]));
    if (size < 2 || rounds < 1) throw voxmesh::Error("SIZE must be at least 2 and ROUNDS at least 1");

    // AB_BACKEND: the engines every build runs, alternated like the builds (cpu,opencl
    // compares the two engines in one process; each build gets its own OpenCL context).
    // AB_PAUSE_MS: a sleep after every call, so that one build's idle worker threads, which
    // spin for a moment before they sleep (src/core/parallel.cpp), do not take a core from
    // the next build's call.
    const char* pause_text = std::getenv("AB_PAUSE_MS");
    const double pause_ms = pause_text ? std::stod(pause_text) : 2.0;
    // AB_REUSE=1: each build meshes into its own kept Mesh (extract_into), as a program
    // meshing repeatedly would; the default, extract(), pays fresh output pages every call.
    const char* reuse_text = std::getenv("AB_REUSE");
    const bool reuse = reuse_text && std::string(reuse_text) == "1";
    // AB_NORMALS=0: meshes without normals (two output arrays instead of three).
    const char* normals_text = std::getenv("AB_NORMALS");
    const bool normals = !(normals_text && std::string(normals_text) == "0");

    std::vector<voxmesh::Backend> backends;
    const char* backend_list = std::getenv("AB_BACKEND");
    std::string list = backend_list ? backend_list : "cpu";
    for (std::size_t at = 0; at <= list.size();) {
        const std::size_t comma = std::min(list.find(',', at), list.size());
        const std::string name = list.substr(at, comma - at);
        if (name == "cpu") backends.push_back(voxmesh::Backend::Cpu);
        else if (name == "opencl") backends.push_back(voxmesh::Backend::OpenCL);
        else throw voxmesh::Error("AB_BACKEND: unknown engine '" + name + "' (cpu, opencl)");
        at = comma + 1;
    }

    struct Entry {
        Extract extract;
        ExtractInto extract_into;
        voxmesh::Backend backend;
        std::string label;
        voxmesh::Mesh kept;  // AB_REUSE's mesh

        voxmesh::Mesh& run(const voxmesh::VolumeView& view, const voxmesh::Options& options, voxmesh::Stats& stats,
                           bool reuse_mesh) {
            if (reuse_mesh) extract_into(view, options, kept, stats);
            else kept = extract(view, options, stats);
            return kept;
        }
    };
    std::vector<Entry> builds;
    MakeField make_field = nullptr;
    for (int i = 6; i < argc; ++i) {
        // Local and deep-bound: each build keeps its own copy of every voxmesh symbol.
        void* library = dlopen(argv[i], RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
        if (!library) throw voxmesh::Error(dlerror());
        const auto extract = reinterpret_cast<Extract>(symbol(library, kExtract, argv[i]));
        const auto extract_into = reinterpret_cast<ExtractInto>(symbol(library, kExtractInto, argv[i]));
        for (const voxmesh::Backend backend : backends)
            builds.push_back({extract, extract_into, backend,
                              std::string(argv[i]) + " " + (backend == voxmesh::Backend::Cpu ? "cpu" : "opencl"), {}});
        if (!make_field) make_field = reinterpret_cast<MakeField>(symbol(library, kMakeField, argv[i]));
    }
    if (builds.size() < 2) throw voxmesh::Error("nothing to compare: give two builds or two engines");
    const voxmesh::FieldVolume input = make_field(field, size, type, 1);
    voxmesh::VolumeView view;  // built here: Volume::view() is the library's, not ours
    view.data = input.volume.data;
    view.type = input.volume.type;
    view.dims = input.volume.dims;
    voxmesh::Options options;
    options.iso = input.iso;
    options.threads = threads;
    options.normals = normals;

    const std::size_t n = builds.size();
    std::vector<std::vector<double>> classify(n), generate(n), total(n), ratio(n), total_ratio(n);
    std::vector<std::size_t> triangles(n);
    for (std::size_t b = 0; b < n; ++b) {  // warm-up: page faults, thread start, caches
        voxmesh::Stats stats;
        options.backend = builds[b].backend;
        triangles[b] = builds[b].run(view, options, stats, reuse).triangle_count();
        if (!reuse) builds[b].kept = {};
    }
    for (unsigned r = 0; r < rounds; ++r) {
        std::vector<double> g(n), t(n);
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t b = r % 2 ? n - 1 - k : k;  // forward, then backward
            voxmesh::Stats stats;
            options.backend = builds[b].backend;
            builds[b].run(view, options, stats, reuse);
            if (!reuse) builds[b].kept = {};  // freed before the next call, as before
            classify[b].push_back(stats.times.classify);
            generate[b].push_back(stats.times.generate);
            total[b].push_back(stats.times.total);
            g[b] = stats.times.generate;
            t[b] = stats.times.total;
            if (pause_ms > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(pause_ms));
        }
        for (std::size_t b = 0; b < n; ++b) {
            ratio[b].push_back(g[b] / g[0]);
            total_ratio[b].push_back(t[b] / t[0]);
        }
    }
    std::printf("%s %s %zu^3, %u threads, %u rounds, %s%s; medians in seconds, generate and total / first build's per round\n",
                argv[1], argv[2], size, threads, rounds, reuse ? "extract_into()" : "extract()",
                normals ? "" : ", no normals");
    for (std::size_t b = 0; b < n; ++b)
        std::printf("%-39s triangles %zu classify %.4f generate %.4f total %.4f generate/first %.3f total/first %.3f\n",
                    builds[b].label.c_str(), triangles[b], median(classify[b]), median(generate[b]), median(total[b]),
                    median(ratio[b]), median(total_ratio[b]));
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "voxmesh-ab: %s\n", e.what());
    return 1;
}
