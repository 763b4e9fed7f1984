// voxmesh info FILE [raw flags]: the header first (no samples loaded), then the value range.
#include "common.hpp"

#include <array>
#include <iostream>
#include <memory>

namespace voxmesh::cli {

namespace {

struct InfoArgs {
    std::string input;
    RawFlags raw;
};

// "x z" for flips of the first and last axes; empty for none.
std::string flipped_axes(const std::array<bool, 3>& flipped) {
    std::string out;
    for (std::size_t a = 0; a < 3; ++a)
        if (flipped[a]) out += std::string(out.empty() ? "" : " ") + "xyz"[a];
    return out;
}

int run_info(const InfoArgs& a) {
    check_input_file(a.input);
    const bool is_raw = is_raw_path(a.input);
    if (!is_raw && a.raw.any_given())
        throw BadInput("'" + a.input + "': --dims/--type/--offset/--spacing/--origin apply only to .raw input");
    const RawLayout layout = is_raw ? raw_layout(a.input, a.raw) : RawLayout{};
    const VolumeInfo info =
        about_file(a.input, [&] { return is_raw ? read_raw_info(a.input, layout) : read_volume_info(a.input); });

    const std::size_t samples = info.dims[0] * info.dims[1] * info.dims[2];
    std::cout << "file:      " << a.input << "\n"
              << "format:    " << info.format << " (" << info.encoding << ", "
              << (info.big_endian ? "big" : "little") << " endian)\n"
              << "dims:      " << dims_text(info.dims) << " (" << samples << " samples)\n"
              << "type:      " << scalar_name(info.type) << "\n"
              << "spacing:   " << triple_text(info.spacing) << "\n"
              << "origin:    " << triple_text(info.origin) << "\n"
              << "size:      " << format_bytes(std::uint64_t(samples) * scalar_size(info.type)) << " of samples; file "
              << format_bytes(info.file_bytes) << "\n";
    if (const std::string axes = flipped_axes(info.flipped); !axes.empty())
        std::cout << "flipped:   " << axes
                  << " (stored in the negative direction; reversed on load, origin is the minimum corner)\n";
    if (info.rotation_dropped)
        std::cout << "rotation:  dropped (the direction matrix is not axis-aligned; spacing and origin as above)\n";
    if (!info.data_file.empty() && info.data_file != a.input) std::cout << "data file: " << info.data_file << "\n";
    if (info.value_scale != 1 || info.value_offset != 0)
        std::cout << "scaling:   physical = stored * " << format_double(info.value_scale) << " + "
                  << format_double(info.value_offset) << " (not applied; values below are stored values)\n";
    std::cout.flush();

    // The value range needs the samples (memory-mapped where the reader can).
    const Volume v = about_file(a.input, [&] { return is_raw ? read_raw(a.input, layout) : read_volume(a.input); });
    const ValueRange r = value_range(v.view());
    std::cout << "range:     " << format_double(r.min) << " .. " << format_double(r.max);
    if (r.nonfinite) std::cout << " (" << r.nonfinite << " NaN or infinite samples)";
    std::cout << "\n";
    return kExitOk;
}

}  // namespace

Command add_info(CLI::App& app) {
    auto a = std::make_shared<InfoArgs>();
    CLI::App* sub = app.add_subcommand("info", "Print a volume file's dims, type, spacing, origin, value range, size");
    sub->add_option("FILE", a->input, "volume: .nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz, or .raw with --dims --type")
        ->required();
    add_raw_flags(sub, a->raw);
    return {sub, [a] { return run_info(*a); }};
}

}  // namespace voxmesh::cli
