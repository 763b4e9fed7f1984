// Scratch latency benchmark for sculpting (the real entry point is voxmesh-bench --sculpt,
// which calls the same run_sculpt_benchmark).
//   voxmesh-sculpt-bench [N ...] [--dabs D] [--threads T] [--block B] [--repeats R]
#include <voxmesh/sculpt.hpp>

#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
    try {
        std::vector<std::size_t> sizes;
        voxmesh::SculptBenchOptions base;
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            auto value = [&]() -> std::size_t {
                if (i + 1 >= argc) throw voxmesh::Error(a + " needs a value");
                return std::stoul(argv[++i]);
            };
            if (a == "--dabs") base.dabs = value();
            else if (a == "--threads") base.threads = static_cast<unsigned>(value());
            else if (a == "--block") base.block_size = value();
            else if (a == "--repeats") base.extract_repeats = value();
            else sizes.push_back(std::stoul(a));
        }
        if (sizes.empty()) sizes = {256, 512};
        for (std::size_t n : sizes) {
            voxmesh::SculptBenchOptions o = base;
            o.resolution = n;
            const auto r = voxmesh::run_sculpt_benchmark(o, [](const std::string& s) { std::cerr << s << "\n"; });
            std::cout << voxmesh::format_sculpt_benchmark(r) << std::flush;
        }
        return 0;
    } catch (const std::exception& e) {
        std::cerr << "voxmesh-sculpt-bench: " << e.what() << "\n";
        return 1;
    }
}
