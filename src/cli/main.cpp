// voxmesh: mesh volumes, voxelize and sculpt STL models, inspect files and devices, run the demo.
// Exit codes: 0 success, 2 bad input or usage (message on stderr), 1 internal failure.
#include "common.hpp"

#include <csignal>
#include <exception>
#include <iostream>
#include <new>
#include <vector>

namespace {

// Interrupted while writing an output: remove the temporary, then die of the signal as
// usual (exit status 128 + signal), so that nothing half-written is left behind.
extern "C" void on_fatal_signal(int sig) {
    voxmesh::remove_partial_outputs();
    std::signal(sig, SIG_DFL);
    std::raise(sig);
}

}  // namespace

int main(int argc, char** argv) {
    using namespace voxmesh::cli;
    for (const int sig : {SIGINT, SIGTERM, SIGHUP})
        if (std::signal(sig, on_fatal_signal) == SIG_IGN) std::signal(sig, SIG_IGN);  // nohup, `cmd &` stay immune
    pin_pocl_workers();
    CLI::App app{"voxmesh " VOXMESH_VERSION_STRING
                 ": marching cubes on every compute device (CPU threads, OpenCL), STL voxelization"};
    app.name("voxmesh");
    app.set_version_flag("--version", VOXMESH_VERSION_STRING);
    app.require_subcommand(1);

    std::vector<Command> commands;
    try {
        for (auto make : {add_mesh, add_voxelize, add_sculpt, add_info, add_devices, add_demo}) commands.push_back(make(app));
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? kExitOk : kExitBadInput;
    }

    try {
        for (const Command& c : commands)
            if (c.sub->parsed()) return c.run();
        std::cerr << "voxmesh: no subcommand given (see voxmesh --help)\n";
        return kExitBadInput;
    } catch (const BadInput& e) {
        std::cerr << "voxmesh: error: " << e.what() << "\n";
        return kExitBadInput;
    } catch (const voxmesh::Error& e) {
        std::cerr << "voxmesh: error: " << e.what() << "\n";
        return kExitBadInput;
    } catch (const std::bad_alloc&) {
        std::cerr << "voxmesh: internal error: out of memory\n";
        return kExitInternal;
    } catch (const std::exception& e) {
        std::cerr << "voxmesh: internal error: " << e.what() << "\n";
        return kExitInternal;
    }
}
