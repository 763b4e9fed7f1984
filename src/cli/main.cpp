// voxmesh: mesh volumes, voxelize and sculpt STL models, inspect files and devices, run the demo.
// Exit codes: 0 success, 2 bad input or usage (message on stderr), 1 internal failure (out of
// memory during the work included).
#include "common.hpp"
#include "core/exit_signals.hpp"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <new>
#include <string>
#include <utility>
#include <vector>
#include <sys/resource.h>

namespace {

bool file_size_limited() {
    rlimit limit{};
    return getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY;
}

// PoCL compiles kernels into files; under a file size limit its LLVM can fail that write and
// end the process with exit(1) ("LLVM ERROR: IO failure on output stream"), or fail the build.
const char* const kFileSizeLimitHint =
    "a file size limit (ulimit -f) is set, and the OpenCL runtime writes the kernels it compiles to files: raise "
    "the limit or use --backend cpu";

// Set while a command runs: a library that calls exit() then (PoCL's LLVM does, after printing
// its own message) leaves the process without a word from voxmesh or its temporaries removed.
std::atomic<bool> g_command_running{false};

void on_exit_during_command() {
    if (!g_command_running.load()) return;
    voxmesh::remove_partial_outputs();
    const bool limited = file_size_limited();
    std::fprintf(stderr, "voxmesh: error: a library ended the program during the work (its message is above)%s%s\n",
                 limited ? "; " : "", limited ? kFileSizeLimitHint : "");
}

struct CommandRunning {
    CommandRunning() { g_command_running = true; }
    ~CommandRunning() { g_command_running = false; }
};

// A command's exit code, unless what it printed on standard output (info's report, mesh's
// --json) could not all be written (a full disk, a closed descriptor): then an error, as the
// output is lost.
int report_written(int code) {
    std::cout.flush();
    const bool failed = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout);
    if (!failed) return code;
    std::cerr << "voxmesh: error: cannot write standard output: " << std::strerror(errno) << "\n";
    return code == voxmesh::cli::kExitOk ? voxmesh::cli::kExitBadInput : code;
}

}  // namespace

int main(int argc, char** argv) {
    using namespace voxmesh::cli;
    // Interrupted while writing an output: nothing half-written is left behind, nor the copy
    // of standard input (stdin_input.hpp lists it with the outputs' temporaries).
    for (const int sig : voxmesh::detail::kExitSignals)
        voxmesh::detail::handle_signal_unless_ignored(sig, voxmesh::detail::remove_partial_outputs_and_die);
    // A file size limit (ulimit -f) reached while writing: the write fails with EFBIG, so the
    // temporary is removed and the error named, instead of SIGXFSZ killing the process with
    // the temporary (or the copy of standard input) left behind. (PoCL's LLVM installs a
    // one-shot SIGXFSZ handler of its own, so without this the outcome depended on whether
    // OpenCL had been loaded.)
    std::signal(SIGXFSZ, SIG_IGN);
    pin_pocl_workers();
    CLI::App app{"voxmesh " VOXMESH_VERSION_STRING
                 ": marching cubes on every compute device (CPU threads, OpenCL), voxelization of STL, PLY and OBJ models"};
    app.name("voxmesh");
    app.set_version_flag("--version", VOXMESH_VERSION_STRING);
    app.require_subcommand(1);

    std::vector<Command> commands;
    try {
        for (auto make : {add_mesh, add_voxelize, add_sculpt, add_info, add_devices, add_demo}) commands.push_back(make(app));
        refuse_empty_values(app);
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? kExitOk : kExitBadInput;
    }

    std::atexit(on_exit_during_command);
    try {
        const CommandRunning running;
        for (const Command& c : commands)
            if (c.sub->parsed()) return report_written(c.run());
        std::cerr << "voxmesh: no subcommand given (see voxmesh --help)\n";
        return kExitBadInput;
    } catch (const BadInput& e) {  // it may carry the library's message (about_file): its advice too
        std::cerr << "voxmesh: error: " << in_cli_words(e.what()) << "\n";
        return kExitBadInput;
    } catch (const voxmesh::OutOfMemoryError& e) {
        std::cerr << "voxmesh: error: " << e.what() << "\n";
        return kExitInternal;
    } catch (const voxmesh::Error& e) {
        std::string message = in_cli_words(e.what());
        if (message.find("OpenCL program build failed") != std::string::npos && file_size_limited())
            message += std::string("; ") + kFileSizeLimitHint;
        std::cerr << "voxmesh: error: " << message << "\n";
        return kExitBadInput;
    } catch (const std::bad_alloc&) {
        std::cerr << "voxmesh: internal error: out of memory\n";
        return kExitInternal;
    } catch (const std::exception& e) {
        std::cerr << "voxmesh: internal error: " << e.what() << "\n";
        return kExitInternal;
    }
}
