// Runs a built program (the voxmesh CLI, voxmesh-bench) through the shell, for the tests
// that check what a user of those programs sees.
#pragma once

#include <string>

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

}  // namespace vmtest
