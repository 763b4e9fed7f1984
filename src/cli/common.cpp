#include "common.hpp"
#include "stdin_input.hpp"

#include "core/atomic_file.hpp"
#include "core/write_to_stream.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <limits>
#include <system_error>
#include <utility>

#include <unistd.h>

namespace voxmesh::cli {

namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kScalarNames{"u8", "i8", "u16", "i16", "u32", "i32", "f32", "f64"};

ScalarType parse_scalar(const std::string& name) {
    for (ScalarType t : {ScalarType::U8, ScalarType::I8, ScalarType::U16, ScalarType::I16, ScalarType::U32,
                         ScalarType::I32, ScalarType::F32, ScalarType::F64})
        if (name == scalar_name(t)) return t;
    throw BadInput("unknown sample type '" + name + "' (use u8, i8, u16, i16, u32, i32, f32 or f64)");
}

}  // namespace

void refuse_device_on_cpu(const std::string& backend, int device, const std::string& advice) {
    if (backend == "cpu" && device >= 0)
        throw BadInput("--device " + std::to_string(device) + " picks an OpenCL device, which the cpu backend does not use; " +
                       advice);
}

void add_largest_option(CLI::App* sub, std::size_t& largest, const std::string& why) {
    sub->add_option("--largest", largest, "write only the N connected pieces with the most triangles (" + why + ")")
        ->transform(whole_number_in(1, 1LL << 32));
}

void add_raw_flags(CLI::App* sub, RawFlags& raw) {
    const char* group = "Headerless .raw input";
    // In decimal: CLI11 alone would read "010" as octal 8.
    const CLI::Validator size = whole_number_in(0, std::numeric_limits<long long>::max());
    sub->add_option("--dims", raw.dims, "samples along x, y, z")->expected(3)->transform(size)->group(group);
    sub->add_option("--type", raw.type, "sample type")->check(CLI::IsMember(kScalarNames))->group(group);
    sub->add_option("--endian", raw.endian, "byte order of the samples (default little)")
        ->check(CLI::IsMember({"little", "big"}))
        ->group(group);
    sub->add_option("--offset", raw.offset, "bytes to skip before the first sample")->transform(size)->group(group);
    sub->add_option("--spacing", raw.spacing, "sample spacing SX SY SZ (default 1 1 1; a negative one runs its axis down from the origin)")
        ->expected(3)
        ->transform(decimal_number())
        ->group(group);
    sub->add_option("--origin", raw.origin, "position of the first sample OX OY OZ (default 0 0 0)")
        ->expected(3)
        ->transform(decimal_number())
        ->group(group);
}

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

bool is_raw_path(const std::string& path) { return lower_extension(path) == ".raw"; }

void check_input_file(const std::string& path) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw BadInput("'" + path + "': no such file");
    if (fs::is_directory(st)) throw BadInput("'" + path + "': is a directory, not a file");
    if (!fs::is_regular_file(st)) throw BadInput("'" + path + "': is not a regular file");
    const auto size = fs::file_size(path, ec);
    if (ec) throw BadInput("'" + path + "': cannot read its size (" + ec.message() + ")");
    if (size == 0) throw BadInput("'" + path + "': is empty");
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw BadInput("'" + path + "': cannot be opened for reading");
    std::fclose(f);
}

bool is_model_path(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == ".stl" || ext == ".ply" || ext == ".obj";
}

void check_model_extension(const std::string& path, const std::string& command) {
    if (!is_model_path(path))
        throw BadInput("'" + path + "': not a mesh file (" + command + " reads .stl, .ply and .obj models)");
}

void check_output_path(const std::string& path, const std::vector<std::string>& extensions) {
    if (is_stdout(path)) {
        // Binary meshes and volumes would fill the screen with noise.
        if (::isatty(STDOUT_FILENO))
            throw BadInput("-o -: standard output is a terminal; redirect or pipe it, or give -o FILE");
        return;
    }
    const std::string ext = lower_extension(path);
    if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end()) {
        std::string list;
        for (const auto& e : extensions) list += (list.empty() ? "" : ", ") + e;
        throw BadInput("'" + path + "': unknown output format '" + ext + "' (use " + list + ")");
    }
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw BadInput("'" + path + "': output is a directory");
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    if (!fs::is_directory(dir, ec))
        throw BadInput("'" + path + "': output directory '" + dir.string() + "' does not exist");
    // Refused now rather than after the work (a read-only directory or file).
    try {
        voxmesh::detail::check_writable(path);
    } catch (const Error& e) {
        throw BadInput(e.what());
    }
}

std::ostream& report_stream(const std::string& output) { return is_stdout(output) ? std::cerr : std::cout; }

void add_mesh_format_option(CLI::App* sub, std::string& format) {
    sub->add_option("--format", format, "stl, ply, obj or glb: the format with -o - (standard output)")
        ->check(CLI::IsMember({"stl", "ply", "obj", "glb"}));
}

void check_mesh_output(const std::string& output, const std::string& format) {
    check_output_path(output, {".stl", ".ply", ".obj", ".glb"});
    if (is_stdout(output) && format.empty()) throw BadInput("-o - (standard output) needs --format stl, ply, obj or glb");
    if (!is_stdout(output) && !format.empty())
        throw BadInput("--format applies only to -o - (standard output); '" + output +
                       "' is written in the format its extension names");
}

void write_mesh_output(const std::string& output, const std::string& format, const Mesh& mesh) {
    const std::string name = output_name(output);
    about_file(name, [&] {
        if (!is_stdout(output)) return write_mesh(output, mesh);
        std::cout.flush();  // nothing of ours is buffered ahead of the mesh
        detail::write_mesh_to(stdout, mesh, "." + format, name);
    });
}

void write_volume_output(const std::string& output, const VolumeView& volume,
                         const std::map<std::string, std::string>& key_values) {
    const std::string name = output_name(output);
    about_file(name, [&] {
        if (!is_stdout(output)) return write_nrrd(output, volume, key_values);
        std::cout.flush();
        detail::write_nrrd_to(stdout, volume, key_values, name);
    });
}

RawLayout raw_layout(const std::string& path, const RawFlags& raw) {
    if (raw.dims.size() != 3 || raw.type.empty())
        throw BadInput("'" + path + "': a headerless raw volume needs --dims NX NY NZ and --type");
    RawLayout layout;
    for (int a = 0; a < 3; ++a) {
        if (raw.dims[a] == 0) throw BadInput("'" + path + "': --dims must be positive");
        layout.dims[a] = raw.dims[a];
        if (!raw.spacing.empty()) layout.spacing[a] = raw.spacing[a];
        if (!raw.origin.empty()) layout.origin[a] = raw.origin[a];
    }
    layout.type = parse_scalar(raw.type);
    layout.big_endian = raw.endian == "big";
    layout.offset = raw.offset;
    return layout;
}

namespace {

// `v`, or BadInput naming `name` when it holds NaN or infinite samples.
Volume finite_samples(Volume v, const std::string& name, unsigned threads) {
    if (v.type == ScalarType::F32 || v.type == ScalarType::F64) {
        const ValueRange r = value_range(v.view(), std::nullopt, threads);
        if (r.nonfinite)
            throw BadInput("'" + name + "': " + std::to_string(r.nonfinite) + " samples are NaN or infinite (first at " +
                           std::to_string(r.first_nonfinite[0]) + ", " + std::to_string(r.first_nonfinite[1]) + ", " +
                           std::to_string(r.first_nonfinite[2]) + ")");
    }
    return v;
}

}  // namespace

Volume load_volume(const std::string& arg, const RawFlags& raw, unsigned threads, VolumeInfo* info_out, bool world) {
    if (arg == "-" && raw.any_given()) {  // raw samples piped in: the flags say what they are
        if (::isatty(STDIN_FILENO))
            throw BadInput(std::string(kStdinName) + " is a terminal: pipe or redirect raw samples into it");
        return finite_samples(about_file(kStdinName, [&] { return read_raw(std::cin, kStdinName, raw_layout(kStdinName, raw)); }),
                              kStdinName, threads);
    }
    const InputPath input(arg, InputKind::Volume);  // "-": a file format, told from its content
    const std::string& path = input.path();
    const bool is_raw = is_raw_path(path);
    if (!is_raw && raw.any_given())
        throw BadInput("'" + input.display() + "': --dims/--type/--endian/--offset/--spacing/--origin apply only to .raw input");
    VolumeInfo info;
    Volume v = input.read([&] { return is_raw ? read_raw(path, raw_layout(path, raw)) : read_volume(path, info); });
    // A Volume has no orientation: say so when the file's direction matrix is left out,
    // since the mesh then lies in index-aligned axes, not where other tools put it.
    if (info.rotation_dropped && !has_world_transform(info))
        std::cerr << "voxmesh: warning: '" << input.display()
                  << "': the direction matrix is not axis-aligned and its directions do not span 3-D; its rotation "
                     "is dropped (--world too cannot apply it) and the mesh is in the volume's index axes\n";
    else if (info.rotation_dropped && !world)
        std::cerr << "voxmesh: warning: '" << input.display()
                  << "': the direction matrix is not axis-aligned; its rotation is dropped and the mesh is in the "
                     "volume's index axes, each running the way it mostly points (--world places it in the file's "
                     "world frame)\n";
    if (info_out) *info_out = std::move(info);
    return finite_samples(std::move(v), input.display(), threads);
}

std::string format_bytes(std::uint64_t bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    double v = double(bytes);
    int u = 0;
    while (v >= 1024 && u < 4) {
        v /= 1024;
        ++u;
    }
    char buf[64];
    if (u == 0) std::snprintf(buf, sizeof buf, "%llu B", static_cast<unsigned long long>(bytes));
    else std::snprintf(buf, sizeof buf, "%.1f %s", v, units[u]);
    return buf;
}

std::string format_double(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return buf;
}

std::string format_ms(double seconds) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f ms", seconds * 1e3);
    return buf;
}

namespace {

// The length of the well-formed UTF-8 sequence at s[i] (RFC 3629: no overlong forms, no
// surrogates, nothing past U+10FFFF), or 0 where there is none.
std::size_t utf8_sequence(const std::string& s, std::size_t i) {
    const auto byte = [&](std::size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0u; };
    const unsigned b0 = byte(i);
    const auto tail = [&](std::size_t k) { return (byte(k) & 0xC0) == 0x80; };
    if (b0 >= 0xC2 && b0 <= 0xDF) return tail(i + 1) ? 2 : 0;
    if (b0 >= 0xE0 && b0 <= 0xEF) {
        const unsigned b1 = byte(i + 1);
        const bool ok = (b0 == 0xE0 ? b1 >= 0xA0 : true) && (b0 == 0xED ? b1 < 0xA0 : true);
        return ok && tail(i + 1) && tail(i + 2) ? 3 : 0;
    }
    if (b0 >= 0xF0 && b0 <= 0xF4) {
        const unsigned b1 = byte(i + 1);
        const bool ok = (b0 == 0xF0 ? b1 >= 0x90 : true) && (b0 == 0xF4 ? b1 < 0x90 : true);
        return ok && tail(i + 1) && tail(i + 2) && tail(i + 3) ? 4 : 0;
    }
    return 0;
}

}  // namespace

std::string json_string(const std::string& s) {
    std::string out = "\"";
    for (std::size_t i = 0; i < s.size(); ++i) {
        const auto c = static_cast<unsigned char>(s[i]);
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\t': out += "\\t"; break;
            case '\r': out += "\\r"; break;
            default:
                if (c < 0x20) {
                    char buf[8];
                    std::snprintf(buf, sizeof buf, "\\u%04x", c);
                    out += buf;
                } else if (c < 0x80) {
                    out += char(c);
                } else if (const std::size_t n = utf8_sequence(s, i)) {
                    out.append(s, i, n);
                    i += n - 1;
                } else {
                    // A byte of no UTF-8 sequence (a file name in another encoding): JSON text
                    // must be UTF-8, so it becomes U+FFFD, as Python's errors="replace" reads it.
                    out += "\\ufffd";
                }
        }
    }
    return out + "\"";
}

std::string triple_text(const std::array<double, 3>& v) {
    return format_double(v[0]) + " " + format_double(v[1]) + " " + format_double(v[2]);
}

std::string pieces_text(std::size_t pieces) { return std::to_string(pieces) + (pieces == 1 ? " piece" : " pieces"); }

std::string device_type_name(DeviceType type) {
    switch (type) {
        case DeviceType::Any: return "any";
        case DeviceType::Cpu: return "cpu";
        case DeviceType::Gpu: return "gpu";
        case DeviceType::Accelerator: return "accelerator";
    }
    return "?";
}

Backend parse_backend(const std::string& name) {
    for (Backend b : {Backend::Auto, Backend::Cpu, Backend::OpenCL, Backend::Hybrid})
        if (name == backend_name(b)) return b;
    throw BadInput("unknown backend '" + name + "' (use auto, cpu, opencl or hybrid)");
}

void add_fill_option(CLI::App* sub, std::string& fill) {
    sub->add_option("--fill", fill,
                    "which samples are inside: evenodd, after an odd number of surface crossings (default; any "
                    "winding, but overlapping shells leave their overlap out and nested shells a hollow); nonzero, "
                    "the union of the closed shells (overlapping CAD bodies; needs consistent winding)")
        ->check(CLI::IsMember({"evenodd", "nonzero"}));
}

FillRule parse_fill_rule(const std::string& name) {
    if (name == "evenodd") return FillRule::EvenOdd;
    if (name == "nonzero") return FillRule::NonZero;
    throw BadInput("unknown fill rule '" + name + "' (use evenodd or nonzero)");
}

std::string in_cli_words(std::string message) {
    static const std::pair<const char*, const char*> kWords[] = {
        // Hybrid's advice when the only devices are CPUs: the CLI has no device_type option.
        {"name one in Options::devices, or set device_type to Cpu, to use it anyway", "name one with --device to use it anyway"},
        {"Backend::Cpu", "--backend cpu"},       {"Backend::Auto", "--backend auto"},
        {"Backend::OpenCL", "--backend opencl"}, {"Backend::Hybrid", "--backend hybrid"},
        {"list_devices()", "voxmesh devices"},   {"Options::devices", "--device"},
        {"FillRule::EvenOdd", "--fill evenodd"}, {"the NonZero fill rule", "--fill nonzero"}};
    for (const auto& [api, cli] : kWords)
        for (std::size_t at = message.find(api); at != std::string::npos; at = message.find(api, at + std::strlen(cli)))
            message.replace(at, std::strlen(api), cli);
    return message;
}

void print_warning(const std::string& message) { std::cerr << "voxmesh: warning: " << in_cli_words(message) << "\n"; }

}  // namespace voxmesh::cli
