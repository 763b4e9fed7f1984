// Helpers of the test_io_*.cpp files (defined in tests/test_io_support.cpp): scratch
// directories, whole-file reads and writes, zlib streams.
#pragma once

#include <array>
#include <cstddef>
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

// For every sample p of a volume of dims n as loaded, check(at, f): `at` its index in the
// loaded samples, `f` the position the file stored it at ((n-1-i) on each flipped axis).
template <class Check>
void for_each_sample_of_file(std::array<std::size_t, 3> n, std::array<bool, 3> flipped, Check check) {
    std::array<std::size_t, 3> p{};
    for (p[2] = 0; p[2] < n[2]; ++p[2])
        for (p[1] = 0; p[1] < n[1]; ++p[1])
            for (p[0] = 0; p[0] < n[0]; ++p[0]) {
                std::array<std::size_t, 3> f = p;
                for (std::size_t a = 0; a < 3; ++a)
                    if (flipped[a]) f[a] = n[a] - 1 - p[a];
                check(p[0] + n[0] * (p[1] + n[1] * p[2]), f);
            }
}

}  // namespace iotest
