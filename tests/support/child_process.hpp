// A forked child for the tests that must not run in the test process itself: under a memory
// cap, or to check what a child of a process with running threads can do.
#pragma once

#include <catch2/catch.hpp>

#include <cstddef>
#include <functional>
#include <string>

namespace vmtest {

// Runs `body` in a forked child and returns the text it returned; when it returned none,
// why: "exception", "killed by signal N" (SIGALRM: still running after `seconds`, a hang)
// or "exited with N". The child ends with _exit: no destructors, no atexit handlers.
std::string output_of_child(const std::function<std::string()>& body, unsigned seconds = 120);

// False under ThreadSanitizer, which dies rather than start a thread in a child forked from a
// multi-threaded process (unless TSAN_OPTIONS=die_after_fork=0): tests of such children
// return early there, with a WARN saying so (threads_after_fork_or_warn).
bool threads_after_fork_supported();

// threads_after_fork_supported(), with the WARN when not: `if (!threads_after_fork_or_warn()) return;`
inline bool threads_after_fork_or_warn() {
    if (threads_after_fork_supported()) return true;
    WARN("skipped under ThreadSanitizer: it dies rather than start threads in a forked child");
    return false;
}

// The number after `key` (e.g. "VmData:", in kB; "Threads:") in /proc/self/status; 0 when absent.
std::size_t proc_status_number(const std::string& key);

}  // namespace vmtest
