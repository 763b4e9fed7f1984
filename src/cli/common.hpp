// Shared pieces of the voxmesh CLI: exit codes, error kinds, input/output checks, small
// formatting helpers. Each subcommand lives in its own cmd_*.cpp and registers itself
// with add_*(app), which returns the function that runs it once parsing succeeded.
#pragma once

#include <voxmesh/io.hpp>
#include <voxmesh/voxelize.hpp>
#include <voxmesh/voxmesh.hpp>

#include "core/dims_text.hpp"
#include "option_checks.hpp"

#include <CLI/CLI.hpp>

#include <array>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <map>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace voxmesh::cli {

enum ExitCode : int {
    kExitOk = 0,
    kExitInternal = 1,  // a bug or resource failure (out of memory during a call, ...)
    kExitBadInput = 2,  // bad input file, bad flag combination, unusable output path
};

// Bad input or usage: exit code 2, message on stderr. The message names the file.
struct BadInput : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// A registered subcommand and what runs it once parsing succeeded.
struct Command {
    CLI::App* sub = nullptr;
    std::function<int()> run;
};

Command add_mesh(CLI::App& app);
Command add_voxelize(CLI::App& app);
Command add_info(CLI::App& app);
Command add_devices(CLI::App& app);
Command add_demo(CLI::App& app);
Command add_sculpt(CLI::App& app);

// Before any OpenCL call: pin PoCL's worker threads where that is safe (pocl_threads.cpp).
void pin_pocl_workers();

// `message` naming `path`, prefixed with it where it does not already.
inline std::string naming(const std::string& path, const std::string& message) {
    return message.find(path) != std::string::npos ? message : "'" + path + "': " + message;
}

// Runs f; a voxmesh::Error it throws becomes BadInput whose message names `path`, except
// running out of memory, which stays an OutOfMemoryError (exit code 1).
template <class F>
auto about_file(const std::string& path, F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const voxmesh::OutOfMemoryError& e) {
        throw voxmesh::OutOfMemoryError(naming(path, e.what()));
    } catch (const voxmesh::Error& e) {
        throw BadInput(naming(path, e.what()));
    }
}

// --dims/--type/... for headerless .raw input (mesh and info).
struct RawFlags {
    std::vector<std::size_t> dims;
    std::string type;
    std::string endian;  // "" (not given: little), "little" or "big"
    std::size_t offset = 0;
    std::vector<double> spacing, origin;
    bool any_given() const {
        return !dims.empty() || !type.empty() || !endian.empty() || offset != 0 || !spacing.empty() || !origin.empty();
    }
};
void add_raw_flags(CLI::App* sub, RawFlags& raw);
// --largest N (N >= 1): write only the N connected pieces with the most triangles; `why` ends
// the help text.
void add_largest_option(CLI::App* sub, std::size_t& largest, const std::string& why);

bool is_raw_path(const std::string& path);

// --device picks an OpenCL device: with the cpu backend it would be ignored, so refused;
// `advice` ends the message (which backends to give instead).
void refuse_device_on_cpu(const std::string& backend, int device, const std::string& advice);
std::string lower_extension(const std::string& path);

// A readable, non-empty regular file, or BadInput naming it.
void check_input_file(const std::string& path);
// A model file (read_mesh's .stl, .ply, .obj), by its extension; check_model_extension throws
// BadInput naming it otherwise.
bool is_model_path(const std::string& path);
void check_model_extension(const std::string& path, const std::string& command);
// The output's extension is one of `extensions` and its directory exists; else BadInput.
// "-" is standard output, which must not be a terminal.
void check_output_path(const std::string& path, const std::vector<std::string>& extensions);

// -o -: the output goes to standard output, and what a command reports to standard error.
inline bool is_stdout(const std::string& output) { return output == "-"; }
inline std::FILE* report_file(const std::string& output) { return is_stdout(output) ? stderr : stdout; }
std::ostream& report_stream(const std::string& output);
// How messages name an output.
inline std::string output_name(const std::string& output) { return is_stdout(output) ? "standard output" : output; }

// --format for a mesh written to standard output: the format -o's extension gives otherwise.
void add_mesh_format_option(CLI::App* sub, std::string& format);
// check_output_path for a mesh, and --format given exactly when the output is standard output.
void check_mesh_output(const std::string& output, const std::string& format);
// The mesh to `output` (a file, atomically, or standard output in `format`); BadInput naming it.
void write_mesh_output(const std::string& output, const std::string& format, const Mesh& mesh);
// The volume to `output` as NRRD (a file, atomically, or standard output), with `key_values`
// as its "key:=value" lines; BadInput naming it.
void write_volume_output(const std::string& output, const VolumeView& volume,
                         const std::map<std::string, std::string>& key_values = {});

// Reads a volume file (raw with the flags, else by extension) and rejects NaN/inf samples,
// scanning for them on `threads` threads (0: every CPU this process may use).
// info (may be null): the file's header as read_volume gives it (a default VolumeInfo for raw samples).
// world: the caller places the mesh with to_world, so a dropped rotation is not warned about
// (unless to_world cannot apply it, see has_world_transform).
Volume load_volume(const std::string& path, const RawFlags& raw, unsigned threads = 0, VolumeInfo* info = nullptr,
                   bool world = false);
RawLayout raw_layout(const std::string& path, const RawFlags& raw);


std::string format_bytes(std::uint64_t bytes);
std::string format_double(double v);  // shortest round-trip-ish text
std::string format_ms(double seconds);
std::string json_string(const std::string& s);
using voxmesh::detail::dims_text;  // "NXxNYxNZ"
std::string triple_text(const std::array<double, 3>& v);
std::string pieces_text(std::size_t pieces);  // "1 piece", "29 pieces"
std::string device_type_name(DeviceType type);

// The library's advice names its API ("use Backend::Cpu", "list_devices()"); here the options
// and commands that do the same. For errors and warnings alike.
std::string in_cli_words(std::string message);
// Options::log for the commands: "voxmesh: warning: " and the message in the CLI's words.
void print_warning(const std::string& message);
Backend parse_backend(const std::string& name);
// --fill evenodd|nonzero for the commands that voxelize a model (VoxelizeOptions::fill).
void add_fill_option(CLI::App* sub, std::string& fill);
FillRule parse_fill_rule(const std::string& name);

}  // namespace voxmesh::cli
