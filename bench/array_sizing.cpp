// voxmesh-array-sizing: what sizing a result array costs (src/core/array_sizing.hpp), for new
// storage (every allocation a fresh mapping: the pages are faulted in and zeroed by the kernel)
// and for storage a heap hands out again (already in memory). Per size: a plain
// std::vector::resize on one thread, as the library sized its lists before, against
// ArraySizing on one thread and on all (or --threads). Medians of --repeat, in ms, and the
// ratio to the plain resize.
//   voxmesh-array-sizing [--threads N] [--repeat R] [MB...]   (default 10 40 80 240)
#include "core/array_sizing.hpp"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

namespace {

double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

template <class F>
double median_ms(int repeat, F&& run) {
    std::vector<double> times;
    for (int r = 0; r < repeat; ++r) {
        const double start = now_s();
        run();
        times.push_back(now_s() - start);
    }
    std::sort(times.begin(), times.end());
    return 1e3 * times[times.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    int repeat = 15;
    std::vector<std::size_t> sizes_mb;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--threads" && i + 1 < argc) threads = static_cast<unsigned>(std::max(1, std::atoi(argv[++i])));
        else if (arg == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
        else if (std::atoi(arg.c_str()) > 0) sizes_mb.push_back(static_cast<std::size_t>(std::atoi(arg.c_str())));
        else {
            std::fprintf(stderr, "usage: voxmesh-array-sizing [--threads N] [--repeat R] [MB...]\n");
            return 2;
        }
    }
    if (sizes_mb.empty()) sizes_mb = {10, 40, 80, 240};
    std::printf("storage  MB   resize_ms  sizing_1_ms  sizing_%u_ms   x_resize(1)  x_resize(%u)\n", threads, threads);
    for (const bool fresh : {true, false}) {
        // Fixed thresholds turn off glibc's own adjustment: every block a new mapping, or none.
        mallopt(M_MMAP_THRESHOLD, fresh ? 1 << 20 : 1 << 30);
        mallopt(M_TRIM_THRESHOLD, fresh ? 1 << 20 : 1 << 30);
        for (const std::size_t mb : sizes_mb) {
            const std::size_t n = (mb << 20) / sizeof(std::uint64_t);
            // Each run touches its array's middle, so nothing is optimised away.
            const auto plain = [&] {
                std::vector<std::uint64_t> v;
                v.resize(n);
                static_cast<volatile std::uint64_t*>(v.data())[n / 2] = 1;
            };
            const auto sized = [&](unsigned t) {
                return [&, t] {
                    std::vector<std::uint64_t> v;
                    voxmesh::detail::ArraySizing sizing;
                    sizing.add(v, n);
                    sizing.run(t);
                    static_cast<volatile std::uint64_t*>(v.data())[n / 2] = 1;
                };
            };
            plain();  // the heap's blocks exist before the reused runs
            const double a = median_ms(repeat, plain), b = median_ms(repeat, sized(1)), c = median_ms(repeat, sized(threads));
            std::printf("%-7s %4zu  %9.2f  %11.2f  %11.2f   %11.2f  %11.2f\n", fresh ? "fresh" : "reused", mb, a, b, c,
                        b / a, c / a);
        }
    }
}
