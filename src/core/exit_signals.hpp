// For the programs built on voxmesh (the CLI, the benchmark): dying of SIGINT, SIGTERM or
// SIGHUP without leaving a half-written output behind.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <csignal>

#include <pthread.h>

namespace voxmesh::detail {

// The signals the programs clean up after (remove_partial_outputs_and_die).
inline constexpr int kExitSignals[] = {SIGINT, SIGTERM, SIGHUP};

// Holds kExitSignals back on the calling thread while it lives; one sent meanwhile is delivered
// when it ends. For making a temporary whose name is known only once it exists (mkstemp) and
// listing it: a signal in between would leave the file behind. (A signal sent to the process
// can still go to another thread; the programs read their input before starting any.)
class ExitSignalsHeld {
public:
    ExitSignalsHeld() {
        sigset_t held;
        sigemptyset(&held);
        for (const int sig : kExitSignals) sigaddset(&held, sig);
        pthread_sigmask(SIG_BLOCK, &held, &previous_);
    }
    ~ExitSignalsHeld() { pthread_sigmask(SIG_SETMASK, &previous_, nullptr); }
    ExitSignalsHeld(const ExitSignalsHeld&) = delete;
    ExitSignalsHeld& operator=(const ExitSignalsHeld&) = delete;

private:
    sigset_t previous_;
};

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
