#include "run_program.hpp"

#include "support/io_scratch.hpp"

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fcntl.h>
#include <spawn.h>
#include <stdexcept>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace vmtest {

std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

ProgramResult run_program(const std::string& program, const std::string& args, const std::string& scratch_dir,
                          const std::string& env) {
    const std::string out = scratch_dir + "/stdout.txt", err = scratch_dir + "/stderr.txt";
    const std::string cmd = (env.empty() ? "" : env + " ") + shell_quote(program) + " " + args + " > " +
                            shell_quote(out) + " 2> " + shell_quote(err);
    const int status = std::system(cmd.c_str());
    ProgramResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = iotest::read_file(out);
    r.err = iotest::read_file(err);
    return r;
}

StartedProgram start_program(const std::string& program, const std::vector<std::string>& args,
                             const std::string& scratch_dir, int stdin_fd, const std::vector<std::string>& env) {
    StartedProgram started;
    started.out_path = scratch_dir + "/stdout.txt";
    started.err_path = scratch_dir + "/stderr.txt";
    std::vector<std::string> argv_text{program};
    argv_text.insert(argv_text.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : argv_text) argv.push_back(a.data());
    argv.push_back(nullptr);

    posix_spawn_file_actions_t files;
    posix_spawn_file_actions_init(&files);
    posix_spawn_file_actions_addopen(&files, 1, started.out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&files, 2, started.err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (stdin_fd >= 0) posix_spawn_file_actions_adddup2(&files, stdin_fd, 0);
    std::vector<std::string> env_text(env);
    for (char** e = environ; *e; ++e) env_text.emplace_back(*e);  // earlier entries win in getenv
    std::vector<char*> envp;
    for (std::string& e : env_text) envp.push_back(e.data());
    envp.push_back(nullptr);
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t defaults, none;
    sigemptyset(&defaults);
    for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&defaults, sig);
    sigemptyset(&none);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setsigmask(&attr, &none);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
    const int rc = posix_spawn(&started.pid, program.c_str(), &files, &attr, argv.data(), envp.data());
    posix_spawnattr_destroy(&attr);
    posix_spawn_file_actions_destroy(&files);
    if (rc != 0) throw std::runtime_error("cannot start " + program);
    return started;
}

bool wait_for_stderr(const StartedProgram& program, const std::string& text, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
        if (iotest::read_file(program.err_path).find(text) != std::string::npos) return true;
        siginfo_t info{};
        if (waitid(P_PID, static_cast<id_t>(program.pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid != 0)
            return false;  // it ended (left for wait_program to reap)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
}

int wait_program(const StartedProgram& program) {
    int status = 0;
    while (waitpid(program.pid, &status, 0) < 0)
        if (errno != EINTR) throw std::runtime_error("waitpid failed");
    return status;
}

}  // namespace vmtest
