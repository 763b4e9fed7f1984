// Runs a built program (the voxmesh CLI, voxmesh-bench) through the shell, for the tests
// that check what a user of those programs sees.
#pragma once

#include <string>
#include <sys/types.h>
#include <vector>

namespace vmtest {

// `s` in single quotes for /bin/sh.
std::string shell_quote(const std::string& s);

struct ProgramResult {
    int code = -1;  // the exit status; -1 when the program did not exit normally
    std::string out, err;
};

// `program args` with stdout and stderr caught in files under `scratch_dir`; `env` holds
// NAME=value assignments for the command's environment (the shell's prefix form).
ProgramResult run_program(const std::string& program, const std::string& args, const std::string& scratch_dir,
                          const std::string& env = "");

// A program started in the background, to be signalled while it runs. It gets the default
// action for SIGINT, SIGTERM and SIGHUP whatever this process has (a shell's `cmd &` would
// start it with SIGINT ignored); stdout and stderr go to `out_path` and `err_path`.
// `stdin_fd` (if >= 0) becomes its standard input; `env` adds NAME=value entries to this
// process's environment for it.
struct StartedProgram {
    pid_t pid = -1;
    std::string out_path, err_path;
};
StartedProgram start_program(const std::string& program, const std::vector<std::string>& args,
                             const std::string& scratch_dir, int stdin_fd = -1,
                             const std::vector<std::string>& env = {});

// Polls the program's stderr until it contains `text` (true) or the program exits or
// `timeout_s` passes (false).
bool wait_for_stderr(const StartedProgram& program, const std::string& text, double timeout_s);

// Waits for the program to end; returns the wait status (WIFEXITED, WTERMSIG, ...).
int wait_program(const StartedProgram& program);

}  // namespace vmtest
