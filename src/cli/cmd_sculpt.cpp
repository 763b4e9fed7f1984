// voxmesh sculpt MODEL.stl|.ply|.obj --resolution N [--padding P] [--strokes FILE] [--fill evenodd|nonzero] -o OUT.ply
//                [--backend cpu|opencl|auto] [--device I] [--threads T] [--frames] [--largest N]
// The paper's loop: voxelize a model, apply brush dabs, re-mesh only what each dab touched.
// Without strokes, the paper's pipeline in one step: the model voxelized and meshed again.
#include "common.hpp"
#include "stdin_input.hpp"

#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxelize.hpp>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace voxmesh::cli {

namespace {

struct SculptArgs {
    std::string input, strokes, output, format;
    std::size_t resolution = 0;
    std::size_t padding = 2;  // samples of room around the model
    std::string fill = "evenodd";
    unsigned threads = 0;
    std::string backend = "cpu";
    int device = -1;  // -1: a GPU/accelerator, else the first device
    bool frames = false;
    std::size_t largest = 0;  // keep that many pieces with the most triangles; 0: all
};

int run_sculpt(const SculptArgs& a) {
    check_mesh_output(a.output, a.format);
    std::FILE* const report = report_file(a.output);
    if (a.input == "-" && a.strokes == "-") throw BadInput("the model and --strokes cannot both be standard input");
    if (a.input != "-") {  // checked before the strokes are read (load_model reads it after)
        check_input_file(a.input);
        check_model_extension(a.input, "sculpt");
    }
    std::vector<ScriptDab> dabs;
    if (!a.strokes.empty()) {
        const InputPath strokes(a.strokes, InputKind::Text);
        dabs = strokes.read([&] { return read_stroke_script(strokes.path()); });
    }

    refuse_device_on_cpu(a.backend, a.device, "it is sculpt's default: give --backend opencl or auto");
    SculptOptions options;
    options.threads = a.threads;
    options.backend = parse_backend(a.backend);
    options.device = a.device;
    options.log = print_warning;
    // A device that does not exist is named before the model is read and voxelized (minutes at
    // a high resolution), and not as the model file's fault. With no device at all the CPU
    // re-meshes, with the library's warning.
    if (options.backend != Backend::Cpu && a.device >= 0) {
        const std::size_t count = list_devices().size();
        if (count > 0 && static_cast<std::size_t>(a.device) >= count)
            throw BadInput("OpenCL device index " + std::to_string(a.device) + " does not exist (voxmesh devices lists " +
                           std::to_string(count) + (count == 1 ? " device)" : " devices)"));
    }
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh model = load_model(a.input, "sculpt");
    VoxelizeOptions voxelize_options = Sculpt::model_voxelization(a.resolution, options);
    voxelize_options.padding = a.padding;
    voxelize_options.fill = parse_fill_rule(a.fill);
    Sculpt sculpt =
        about_file(input_name(a.input), [&] { return Sculpt::from_mesh(model, voxelize_options, options); });
    const UpdateResult first = sculpt.update();
    const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    std::vector<double> update_ms;
    update_ms.reserve(dabs.size());
    run_strokes(sculpt, dabs, [&](const StrokeFrame& f) {
        update_ms.push_back(1e3 * f.update_seconds);
        if (a.frames)
            std::fprintf(report, "frame %zu: edit %.2f ms, update %.2f ms, %zu block%s re-meshed\n", f.frame,
                         1e3 * f.edit_seconds, 1e3 * f.update_seconds, f.blocks_remeshed, f.blocks_remeshed == 1 ? "" : "s");
    });
    Mesh mesh = sculpt.mesh();
    if (a.largest > 0) mesh = keep_largest_components(mesh, a.largest);  // e.g. without the crumbs a brush left
    write_mesh_output(a.output, a.format, mesh);

    const LatencySummary s = summarize_latencies(update_ms);
    const MeshTopology topo = analyze_topology(mesh);
    const auto dims = sculpt.view().dims;
    std::fprintf(report, "%s -> %s: %s volume, voxelized and meshed in %s (%zu blocks); ", input_name(a.input).c_str(),
                 output_name(a.output).c_str(),
                dims_text(dims).c_str(), format_ms(load_s).c_str(), first.remeshed);
    if (dabs.empty())
        std::fprintf(report, "no strokes; ");
    else
        std::fprintf(report, "%zu dabs re-meshed on %s, update p50 %.2f ms, p95 %.2f ms, p99 %.2f ms, max %.2f ms; ", dabs.size(),
                    sculpt.device_name().c_str(), s.p50, s.p95, s.p99, s.max);
    const std::string shape = topo.closed() ? "closed (euler " + std::to_string(topo.euler) + ")" : "open";
    std::fprintf(report, "%zu vertices, %zu triangles in %s, %s\n", mesh.vertex_count(), mesh.triangle_count(),
                pieces_text(topo.components).c_str(), shape.c_str());
    return kExitOk;
}

}  // namespace

Command add_sculpt(CLI::App& app) {
    auto a = std::make_shared<SculptArgs>();
    CLI::App* sub = app.add_subcommand(
        "sculpt", "Voxelize a closed model (STL, PLY, OBJ), apply a stroke script if given (re-meshing only what each dab changed), write the mesh");
    sub->add_option("MODEL", a->input, "closed triangle mesh (.stl, .ply or .obj; -: standard input)")->required();
    sub->add_option("--strokes", a->strokes,
                    "stroke script: one dab per line 'op x y z radius strength', op add|subtract|smooth|set, "
                    "'#' comments; coordinates in samples, or model units after a line 'units world' (-: standard input). Without it, "
                    "the model is voxelized and meshed again as it is");
    sub->add_option("-o,--output", a->output, "mesh file to write (.stl, .ply, .obj or .glb; -: standard output, with --format)")
        ->required();
    add_mesh_format_option(sub, a->format);
    sub->add_option("--resolution", a->resolution, "voxels along the longest side of the model (8..2048)")
        ->required()
        ->transform(whole_number_in(8, 2048));
    sub->add_option("--padding", a->padding,
                    "samples of room around the model (0..256, default 2): a surface built up past it is cut open at "
                    "the volume's border")
        ->transform(whole_number_in(0, 256));
    add_fill_option(sub, a->fill);
    sub->add_option("--backend", a->backend,
                    "where each update re-meshes: cpu (threads), opencl (a device; the CPU with a warning when there "
                    "is none) or auto (a GPU when there is one); default cpu")
        ->check(CLI::IsMember({"auto", "cpu", "opencl"}));
    sub->add_option("--device", a->device, "OpenCL device index (see voxmesh devices)")
        ->transform(whole_number_in(0, std::numeric_limits<int>::max()));
    sub->add_option("--threads", a->threads, "CPU threads (default: every CPU this process may use)")
        ->transform(whole_number_in(0, std::numeric_limits<unsigned>::max()));
    sub->add_flag("--frames", a->frames, "print every frame's edit and update time");
    add_largest_option(sub, a->largest, "drops what a brush cut off or left floating");
    return {sub, [a] { return run_sculpt(*a); }};
}

}  // namespace voxmesh::cli
