// For the programs built on voxmesh (the CLI, the benchmark): dying of SIGINT, SIGTERM or
// SIGHUP without leaving a half-written output behind.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <csignal>

namespace voxmesh::detail {

// A signal handler: removes the temporaries of writes in progress, then dies of `sig` as
// if unhandled (exit status 128 + sig).
inline void remove_partial_outputs_and_die(int sig) {
    remove_partial_outputs();
    std::signal(sig, SIG_DFL);
    std::raise(sig);
}

// Installs `handler` for `sig`, unless the process inherited SIG_IGN for it: nohup and a
// non-interactive shell's `cmd &` stay immune.
inline void handle_signal_unless_ignored(int sig, void (*handler)(int)) {
    struct sigaction old {};
    if (sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) return;
    struct sigaction sa {};
    sa.sa_handler = handler;
    sa.sa_flags = SA_RESTART;  // as std::signal sets it: a handler that returns resumes reads and writes
    sigemptyset(&sa.sa_mask);
    sigaction(sig, &sa, nullptr);
}

}  // namespace voxmesh::detail
