#include "child_process.hpp"
#include "sanitizers.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>

namespace vmtest {

std::string output_of_child(const std::function<std::string()>& body, unsigned seconds) {
    int fds[2];
    if (pipe(fds) != 0) return "pipe failed";
    const pid_t child = fork();
    if (child < 0) return "fork failed";
    if (child == 0) {
        close(fds[0]);
        alarm(seconds);  // SIGALRM's default action ends a child that hangs
        std::string out;
        try {
            out = body();
        } catch (...) {
            out = "exception";
        }
        const ssize_t written = write(fds[1], out.data(), out.size());
        _exit(written == static_cast<ssize_t>(out.size()) ? 0 : 1);
    }
    close(fds[1]);
    std::string out;
    char buffer[256];
    for (ssize_t n; (n = read(fds[0], buffer, sizeof buffer)) > 0;) out.append(buffer, static_cast<std::size_t>(n));
    close(fds[0]);
    int status = 0;
    if (waitpid(child, &status, 0) != child) return "waitpid failed";
    if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
    if (WEXITSTATUS(status) != 0) return "exited with " + std::to_string(WEXITSTATUS(status));
    return out;
}

bool threads_after_fork_supported() { return !kThreadSanitizer; }

std::size_t proc_status_number(const std::string& key) {
    std::ifstream status("/proc/self/status");
    for (std::string word; status >> word;) {
        std::size_t value = 0;
        if (word == key) return status >> value ? value : 0;
        status.ignore(1 << 20, '\n');
    }
    return 0;
}

}  // namespace vmtest
