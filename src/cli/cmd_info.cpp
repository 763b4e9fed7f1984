// voxmesh info FILE [raw flags]: for a volume, the header first (no samples loaded), then the
// value range; for a model (.stl, .ply, .obj), its size, bounds, topology, area and volume.
#include "common.hpp"
#include "stdin_input.hpp"
#include "io/header_text.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

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

// What voxelize needs to know before it is run on a model: whether it is closed (every edge
// in two triangles), how large it is, and whether its triangles face outward (a positive
// enclosed volume).
int run_model_info(const InputPath& input) {
    const std::string& path = input.path();
    const Mesh m = input.read([&] { return read_mesh(path); });
    const MeshTopology t = analyze_topology(m);
    // Bounds of the surface, as voxelize grids it: vertices no triangle uses are left out
    // (and counted), except in a point cloud, where every vertex is all there is.
    std::vector<bool> used(m.vertex_count(), m.triangle_count() == 0);
    for (const std::uint32_t i : m.indices) used[i] = true;
    const auto unused = static_cast<std::size_t>(std::count(used.begin(), used.end(), false));
    std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};
    bool first = true;
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
        if (!used[v]) continue;
        for (std::size_t c = 0; c < 3; ++c) {
            const double x = m.positions[3 * v + c];
            lo[c] = first ? x : std::min(lo[c], x);
            hi[c] = first ? x : std::max(hi[c], x);
        }
        first = false;
    }
    double area = 0, volume = 0;  // volume: the divergence theorem, exact for a closed mesh
    for (std::size_t i = 0; i < m.indices.size(); i += 3) {
        std::array<std::array<double, 3>, 3> p{};
        for (std::size_t k = 0; k < 3; ++k)
            for (std::size_t c = 0; c < 3; ++c) p[k][c] = m.positions[3 * std::size_t{m.indices[i + k]} + c];
        const std::array<double, 3> u{p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
        const std::array<double, 3> w{p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
        const std::array<double, 3> n{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        area += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        volume += (p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
                   p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0])) / 6;
    }
    const std::string ext = lower_extension(path);
    std::cout << "file:      " << input.display() << "\n"
              << "format:    " << ext.substr(1) << " mesh" << (ext == ".stl" ? " (vertices welded by position)" : "")
              << "\n"
              << "triangles: " << m.triangle_count() << "\n"
              << "vertices:  " << m.vertex_count() << (m.normals.empty() ? "" : " (with normals)")
              << (unused > 0 ? ", " + std::to_string(unused) + " not used by any triangle (left out of the bounds)" : "")
              << "\n";
    if (m.vertex_count() > 0)
        std::cout << "bounds:    " << triple_text(lo) << " .. " << triple_text(hi) << "\n";
    if (m.triangle_count() == 0)
        std::cout << "topology:  no triangles (a point cloud; voxelize needs a closed model)\n";
    else if (t.closed())
        // "closed": each edge in exactly two triangles. Not "2-manifold": analyze_topology
        // checks neither the vertices' fans (two pieces sharing a vertex) nor the winding.
        std::cout << "topology:  closed (every edge in two triangles), euler " << t.euler << ", " << pieces_text(t.components) << "\n"
                  << "area:      " << format_double(area) << "\n"
                  << "volume:    " << format_double(volume)
                  << (volume < 0 ? " (negative: the triangles face inward)" : "") << "\n";
    else if (t.boundary_edges == 0)
        // No hole, but edges shared by more than two triangles: bodies that share a face or an
        // edge, whose union voxelize fills, or a wall or fin (an odd number), which it refuses.
        std::cout << "topology:  not manifold: " << t.nonmanifold_edges << " edges in three or more triangles, euler "
                  << t.euler << ", " << pieces_text(t.components)
                  << " (voxelize takes bodies sharing edges or faces, each edge in an even number of triangles)\n"
                  << "area:      " << format_double(area) << "\n";
    else
        std::cout << "topology:  open: " << t.boundary_edges << " boundary edges, " << t.nonmanifold_edges
                  << " edges in three or more triangles, euler " << t.euler << ", " << pieces_text(t.components)
                  << " (voxelize needs a closed model)\n"
                  << "area:      " << format_double(area) << "\n";
    return kExitOk;
}

int run_info(const InfoArgs& a) {
    // "-": standard input, in a format told from its content, or raw samples with the flags.
    const InputPath input(a.input, a.input == "-" && a.raw.any_given() ? InputKind::Raw : InputKind::VolumeOrModel);
    const std::string& path = input.path();
    const bool is_raw = is_raw_path(path);
    if (!is_raw && a.raw.any_given())
        throw BadInput("'" + input.display() + "': --dims/--type/--endian/--offset/--spacing/--origin apply only to .raw input");
    if (is_model_path(path)) return run_model_info(input);
    const RawLayout layout = is_raw ? raw_layout(input.display(), a.raw) : RawLayout{};
    const VolumeInfo info = input.read([&] { return is_raw ? read_raw_info(path, layout) : read_volume_info(path); });

    const std::size_t samples = info.dims[0] * info.dims[1] * info.dims[2];
    std::cout << "file:      " << input.display() << "\n"
              << "format:    " << info.format << " (" << info.encoding
              << (info.encoding == "ascii" ? "" : info.big_endian ? ", big endian" : ", little endian")  // text has none
              << ")\n"
              << "dims:      " << dims_text(info.dims) << " (" << samples << " samples)\n"
              << "type:      " << scalar_name(info.type) << "\n"
              << "spacing:   " << triple_text(info.spacing) << "\n"
              << "origin:    " << triple_text(info.origin) << "\n"
              << "size:      " << format_bytes(std::uint64_t(samples) * scalar_size(info.type)) << " of samples; file "
              << format_bytes(info.file_bytes) << "\n";
    if (const std::string axes = flipped_axes(info.flipped); !axes.empty())
        std::cout << "flipped:   " << axes
                  << " (stored in the negative direction; reversed on load, origin is the minimum corner)\n";
    if (info.rotation_dropped && !has_world_transform(info)) {
        std::cout << "rotation:  dropped (the direction matrix is not axis-aligned and its directions do not span "
                     "3-D; mesh --world cannot apply it)\n";
    } else if (info.rotation_dropped) {
        // The loaded axes' directions (columns of D), so the user can see what --world applies.
        const auto column = [&](std::size_t a) {  // + 0.0: a negated zero prints as 0, not -0
            const auto& d = info.directions;
            return triple_text({d[a] + 0.0, d[3 + a] + 0.0, d[6 + a] + 0.0});
        };
        std::cout << "rotation:  dropped (the direction matrix is not axis-aligned; spacing and origin as above; "
                     "mesh --world applies it)\n"
                  << "world:     sample 0 at " << triple_text(info.world_origin) << "; axes x: " << column(0)
                  << ", y: " << column(1) << ", z: " << column(2) << "\n";
    }
    if (!info.data_file.empty() && info.data_file != path) std::cout << "data file: " << info.data_file << "\n";
    if (info.value_scale != 1 || info.value_offset != 0)
        std::cout << "scaling:   physical = stored * " << format_double(info.value_scale) << " + "
                  << format_double(info.value_offset) << " (not applied; values below are stored values)\n";
    if (const auto iso = info.key_values.find(kRecordedIsoKey); iso != info.key_values.end()) {
        std::cout << "iso:       " << io::shown(iso->second) << " (" << kRecordedIsoKey;
        try {
            (void)recorded_iso(info, path);
            std::cout << ", as voxelize records it: mesh's default)\n";
        } catch (const Error&) {
            std::cout << ", not a finite number: mesh refuses it without --iso)\n";
        }
    }
    std::cout.flush();

    // The value range needs the samples (memory-mapped where the reader can).
    const Volume v = input.read([&] { return is_raw ? read_raw(path, layout) : read_volume(path); });
    const ValueRange r = value_range(v.view());
    std::cout << "range:     " << format_double(r.min) << " .. " << format_double(r.max);
    if (r.nonfinite) std::cout << " (" << r.nonfinite << " NaN or infinite samples)";
    std::cout << "\n";
    return kExitOk;
}

}  // namespace

Command add_info(CLI::App& app) {
    auto a = std::make_shared<InfoArgs>();
    CLI::App* sub = app.add_subcommand(
        "info", "Print a volume file's dims, type, spacing, origin, value range, size; or a model's size and topology");
    sub->add_option("FILE", a->input,
                    "volume: .nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz, .vtk, .npy, or .raw with --dims --type; model: .stl, .ply, .obj; "
                    "-: standard input (the format told from its content, or raw with --dims --type)")
        ->required();
    add_raw_flags(sub, a->raw);
    return {sub, [a] { return run_info(*a); }};
}

}  // namespace voxmesh::cli
