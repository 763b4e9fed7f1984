// voxmesh mesh INPUT -o OUTPUT [--iso V] [--backend ...] [--threads N] [--device I]
//   [--no-normals] [--inside-below] [--largest N] [--world] [--json] [raw flags]
#include "common.hpp"
#include "stdin_input.hpp"

#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

namespace voxmesh::cli {

namespace {

struct MeshArgs {
    std::string input, output, format;
    double iso = 0;
    std::string backend = "auto";
    unsigned threads = 0;
    int device = -1;  // -1: every device of the backend
    std::size_t largest = 0;  // keep that many pieces with the most triangles; 0: all
    bool no_normals = false, inside_below = false, world = false, json = false;
    RawFlags raw;
    CLI::Option* iso_option = nullptr;
};

// The iso the file records for meshing (recorded_iso); a bad one is refused with the way on.
std::optional<double> file_iso(const VolumeInfo& info, const std::string& name) {
    try {
        return recorded_iso(info, name);
    } catch (const Error& e) {
        throw BadInput(std::string(e.what()) + "; give --iso to mesh it at another value");
    }
}

// "2 threads", or "16 threads asked for, run on 2 CPUs" where the process may use fewer.
std::string threads_text(const Stats& stats) {
    const auto count = [](unsigned n) { return std::to_string(n) + (n == 1 ? " thread" : " threads"); };
    if (stats.workers == 0 || stats.workers >= stats.threads) return count(stats.threads);
    return count(stats.threads) + " asked for, run on " + std::to_string(stats.workers) +
           (stats.workers == 1 ? " CPU" : " CPUs");
}

std::string devices_text(const Stats& stats) {
    if (stats.devices.empty()) return "cpu";
    std::string s;
    for (const DeviceStats& d : stats.devices) {
        if (!s.empty()) s += ", ";
        s += d.name;
        if (d.chunks) s += " (" + std::to_string(d.chunks) + (d.chunks == 1 ? " chunk)" : " chunks)");
    }
    return s;
}

void print_json(const MeshArgs& a, double iso, const std::string& iso_source, const Mesh& mesh,
                const MeshTopology& topo, std::size_t extracted_triangles, const Stats& stats) {
    std::ostringstream o;
    o << "{\"input\": " << json_string(a.input) << ", \"output\": " << json_string(a.output)
      << ", \"iso\": " << format_double(iso) << ", \"iso_source\": " << json_string(iso_source)
      << ", \"vertices\": " << mesh.vertex_count() << ", \"triangles\": " << mesh.triangle_count()
      << ", \"closed\": " << (topo.closed() ? "true" : "false") << ", \"boundary_edges\": " << topo.boundary_edges
      << ", \"nonmanifold_edges\": " << topo.nonmanifold_edges << ", \"euler\": " << topo.euler
      << ", \"components\": " << topo.components << ", \"extracted_triangles\": " << extracted_triangles
      << ", \"normals\": " << (mesh.normals.empty() ? "false" : "true") << ", \"times_s\": {\"classify\": "
      << format_double(stats.times.classify) << ", \"scan\": " << format_double(stats.times.scan)
      << ", \"generate\": " << format_double(stats.times.generate) << ", \"total\": "
      << format_double(stats.times.total) << "}, \"backend\": " << json_string(backend_name(stats.backend))
      << ", \"threads\": " << stats.threads << ", \"workers\": " << stats.workers << ", \"devices\": [";
    for (std::size_t i = 0; i < stats.devices.size(); ++i) {
        const DeviceStats& d = stats.devices[i];
        o << (i ? ", " : "") << "{\"name\": " << json_string(d.name) << ", \"chunks\": " << d.chunks
          << ", \"voxels\": " << d.voxels << ", \"kernel_s\": " << format_double(d.kernel_s)
          << ", \"setup_s\": " << format_double(d.setup_s) << ", \"programs_built\": " << d.programs_built
          << ", \"transfer_s\": " << format_double(d.transfer_s) << ", \"wall_s\": " << format_double(d.wall_s) << "}";
    }
    o << "], \"warnings\": [";
    for (std::size_t i = 0; i < stats.warnings.size(); ++i) o << (i ? ", " : "") << json_string(in_cli_words(stats.warnings[i]));
    o << "]}";
    report_stream(a.output) << o.str() << "\n";
}

int run_mesh(const MeshArgs& a) {
    check_mesh_output(a.output, a.format);
    if (is_model_path(a.input)) {  // the paper's pipeline in two steps: say which
        check_input_file(a.input);
        throw BadInput("'" + a.input + "': a model, not a volume: voxelize it first (voxmesh voxelize " + a.input +
                       " --resolution N -o model.nrrd), then mesh that; or voxelize and re-mesh it in one step with voxmesh sculpt");
    }
    if (a.iso_option->count() && !std::isfinite(a.iso))
        throw BadInput("--iso is " + format_double(a.iso) + "; give a finite value");
    refuse_device_on_cpu(a.backend, a.device, "give --backend opencl, hybrid or auto");
    VolumeInfo info;
    const Volume volume = load_volume(a.input, a.raw, a.threads, &info, a.world);
    // Named here: extract() would say the same without the file.
    for (int d = 0; d < 3; ++d)
        if (volume.dims[d] < 2)
            throw BadInput("'" + input_name(a.input) + "': volume dimension " + std::string(1, "xyz"[d]) + " is " +
                           std::to_string(volume.dims[d]) + "; marching cubes needs at least 2 samples along every axis");

    double iso = a.iso;
    std::string iso_source = "given";
    std::optional<double> recorded;
    if (a.iso_option->count() == 0) recorded = file_iso(info, input_name(a.input));
    if (recorded) {
        iso = *recorded;
        iso_source = std::string("default: the file's ") + kRecordedIsoKey;
    } else if (a.iso_option->count() == 0) {
        const ValueRange r = value_range(volume.view(), std::nullopt, a.threads);
        iso = 0.5 * r.min + 0.5 * r.max;  // not 0.5 * (min + max): that overflows to inf near DBL_MAX
        iso_source = "default: midpoint of value range " + format_double(r.min) + ".." + format_double(r.max);
    }

    Options options;
    options.iso = iso;
    options.backend = parse_backend(a.backend);
    options.threads = a.threads;
    options.normals = !a.no_normals;
    options.inside_below = a.inside_below;
    if (a.device >= 0) options.devices = {a.device};
    options.log = print_warning;

    Stats stats;
    Mesh mesh = extract(volume.view(), options, stats);  // errors here are not about the file
    const std::size_t extracted_triangles = mesh.triangle_count();
    if (a.largest > 0) mesh = keep_largest_components(mesh, a.largest);
    if (a.world)  // after extract and the pieces: they work in index axes
        about_file(input_name(a.input), [&] { to_world(mesh, info); });  // errors name the file
    const MeshTopology topo = analyze_topology(mesh);
    if (mesh.triangle_count() == 0) {
        // Nearly always an iso outside the data (a typo, stored vs scaled values): say which side.
        const ValueRange r = value_range(volume.view(), std::nullopt, a.threads);
        const char* side = iso > r.max ? ", all below the iso" : iso <= r.min ? ", all at or above the iso" : "";
        std::cerr << "voxmesh: warning: no surface at iso " << format_double(iso) << " in '" << input_name(a.input)
                  << "' (its samples range " << format_double(r.min) << " .. " << format_double(r.max) << side
                  << "); writing an empty mesh\n";
    }
    write_mesh_output(a.output, a.format, mesh);

    if (a.json) {
        print_json(a, iso, iso_source, mesh, topo, extracted_triangles, stats);
        return kExitOk;
    }
    std::ostringstream o;
    o << input_name(a.input) << " -> " << output_name(a.output) << ": " << mesh.vertex_count() << " vertices, " << mesh.triangle_count()
      << " triangles in " << pieces_text(topo.components);
    if (a.largest > 0)
        o << " (the " << (a.largest == 1 ? "largest" : std::to_string(a.largest) + " largest") << "; "
          << extracted_triangles << " triangles extracted)";
    o << ", ";
    if (topo.closed()) o << "closed (euler " << topo.euler << ")";
    else o << "open (" << topo.boundary_edges << " boundary, " << topo.nonmanifold_edges << " non-manifold edges)";
    o << "; iso " << format_double(iso);
    if (a.iso_option->count() == 0) o << " (" << iso_source << ")";
    o << "; classify " << format_ms(stats.times.classify) << ", scan " << format_ms(stats.times.scan) << ", generate "
      << format_ms(stats.times.generate) << ", total " << format_ms(stats.times.total) << "; backend "
      << backend_name(stats.backend);
    if (stats.threads) o << " (" << threads_text(stats) << ")";
    o << "; devices: " << devices_text(stats);
    report_stream(a.output) << o.str() << "\n";
    return kExitOk;
}

}  // namespace

Command add_mesh(CLI::App& app) {
    auto a = std::make_shared<MeshArgs>();
    CLI::App* sub = app.add_subcommand("mesh", "Extract the iso-surface of a volume file into a mesh file");
    sub->add_option("INPUT", a->input, "volume: .nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz, .vtk, .npy, or .raw with --dims --type (-: standard input, a format told from its content, or raw samples with --dims --type)")
        ->required();
    sub->add_option("-o,--output", a->output, "mesh file: .stl (binary), .ply (binary), .obj or .glb (binary glTF 2.0); -: standard output (with --format)")
        ->required();
    add_mesh_format_option(sub, a->format);
    a->iso_option = sub->add_option("--iso", a->iso,
                                    "iso value (default: the iso the file records as voxmesh_iso, as voxelize writes "
                                    "it, else the midpoint of the value range)")
                        ->transform(decimal_number());
    sub->add_option("--backend", a->backend, "auto, cpu, opencl or hybrid (default auto)")
        ->check(CLI::IsMember({"auto", "cpu", "opencl", "hybrid"}));
    sub->add_option("--threads", a->threads, "CPU worker threads (default: every CPU this process may use)")
        ->transform(whole_number_in(0, std::numeric_limits<unsigned>::max()));
    sub->add_option("--device", a->device, "OpenCL device index (see voxmesh devices)")
        ->transform(whole_number_in(0, std::numeric_limits<int>::max()));
    sub->add_flag("--no-normals", a->no_normals, "do not compute vertex normals");
    sub->add_flag("--inside-below", a->inside_below, "values below iso are inside (SDFs): flips winding and normals");
    add_largest_option(sub, a->largest, "drops the specks of noise around a CT's surface");
    sub->add_flag("--world", a->world,
                  "place the mesh in the file's world frame, rotation included (NRRD space directions, MetaImage "
                  "TransformMatrix, NIfTI sform/qform); without it the mesh is in the volume's index axes");
    sub->add_flag("--json", a->json, "print the summary as JSON (on standard error with -o -)");
    add_raw_flags(sub, a->raw);
    return {sub, [a] { return run_mesh(*a); }};
}

}  // namespace voxmesh::cli
