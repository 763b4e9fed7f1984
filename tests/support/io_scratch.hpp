// Helpers of the test_io_*.cpp files (defined in tests/test_io_support.cpp): scratch
// directories, whole-file reads and writes, zlib streams.
#pragma once

#include <string>

namespace iotest {

std::string make_temp_dir();
void remove_tree(const std::string& dir);
void write_file(const std::string& path, const std::string& bytes);
std::string read_file(const std::string& path);
std::string deflate_bytes(const std::string& data, bool gzip);

// A scratch directory for one test case, removed afterwards.
struct Scratch {
    std::string dir = make_temp_dir();
    ~Scratch() { remove_tree(dir); }
    std::string file(const std::string& name, const std::string& bytes) const {
        const std::string path = dir + "/" + name;
        write_file(path, bytes);
        return path;
    }
};

}  // namespace iotest
