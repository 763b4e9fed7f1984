#include "run_program.hpp"

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sys/wait.h>

namespace vmtest {

namespace {
std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
}  // namespace

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
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

}  // namespace vmtest
