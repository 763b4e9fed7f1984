// voxmesh voxelize MODEL.stl|.ply|.obj -o VOLUME.nrrd --resolution N [--padding P] [--field occupancy|distance]
//                 [--fill evenodd|nonzero]
#include "common.hpp"
#include "stdin_input.hpp"

#include <voxmesh/voxelize.hpp>

#include <chrono>
#include <iostream>
#include <memory>

namespace voxmesh::cli {

namespace {

struct VoxelizeArgs {
    std::string input, output;
    std::size_t resolution = 0;
    std::size_t padding = 2;
    std::string field = "distance";
    std::string fill = "evenodd";
};

int run_voxelize(const VoxelizeArgs& a) {
    check_output_path(a.output, {".nrrd"});
    const Mesh model = load_model(a.input, "voxelize");

    VoxelizeOptions options;
    options.resolution = a.resolution;
    options.padding = a.padding;
    options.field = a.field == "occupancy" ? VoxelField::Occupancy : VoxelField::Distance;
    options.fill = parse_fill_rule(a.fill);
    const auto t0 = std::chrono::steady_clock::now();
    const Volume volume = about_file(input_name(a.input), [&] { return voxelize(model, options); });
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool distance = options.field == VoxelField::Distance;
    write_volume_output(a.output, volume.view(), {{kRecordedIsoKey, distance ? "0" : "127.5"}});

    report_stream(a.output) << input_name(a.input) << " -> " << output_name(a.output) << ": " << model.triangle_count() << " triangles, "
              << dims_text(volume.dims) << " " << scalar_name(volume.type) << " "
              << (distance ? "signed distance (positive inside)" : "occupancy (255 inside)") << ", spacing "
              << format_double(volume.spacing[0]) << ", origin " << triple_text(volume.origin) << ", "
              << format_ms(seconds) << "; mesh it back with: voxmesh mesh " << (is_stdout(a.output) ? "VOLUME.nrrd" : a.output) << " -o OUT.stl --iso "
              << (distance ? "0" : "127.5") << "\n";
    return kExitOk;
}

}  // namespace

Command add_voxelize(CLI::App& app) {
    auto a = std::make_shared<VoxelizeArgs>();
    CLI::App* sub = app.add_subcommand("voxelize", "Turn a closed model (STL, PLY, OBJ) into a volume (surface and interior)");
    sub->add_option("MODEL", a->input, "closed triangle mesh (.stl binary or ASCII, .ply, .obj; -: standard input)")->required();
    sub->add_option("-o,--output", a->output, "volume file to write (.nrrd; -: standard output)")->required();
    sub->add_option("--resolution", a->resolution, "voxels along the longest side of the model (2..4096)")
        ->required()
        ->transform(whole_number_in(2, 4096));
    sub->add_option("--padding", a->padding, "extra samples around the model on every side (default 2)")
        ->transform(whole_number_in(0, 256));
    sub->add_option("--field", a->field,
                    "distance: f32 signed distance, positive inside, mesh at iso 0 (default); "
                    "occupancy: u8 255 inside / 0 outside, mesh at iso 127.5")
        ->check(CLI::IsMember({"occupancy", "distance"}));
    add_fill_option(sub, a->fill);
    return {sub, [a] { return run_voxelize(*a); }};
}

}  // namespace voxmesh::cli
