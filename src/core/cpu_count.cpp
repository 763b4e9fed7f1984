#include "cpu_count.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#if defined(__linux__)
#include <sched.h>
#endif

namespace voxmesh::detail {

namespace {

namespace fs = std::filesystem;

// The tighter of two quotas, 0 meaning none.
unsigned tighter(unsigned a, unsigned b) { return a == 0 ? b : b == 0 ? a : std::min(a, b); }

// CPUs of `quota` over `period` microseconds, rounded up; 0 for no quota or nonsense.
unsigned cpus_of(double quota, double period) {
    if (!(quota > 0) || !(period > 0)) return 0;
    const double cpus = std::ceil(quota / period);
    return cpus >= 1e6 ? 0u : static_cast<unsigned>(cpus);
}

// The quota set in `dir`: cpu.max ("max 100000" or "200000 100000") for v2, else the v1 pair.
unsigned quota_in(const fs::path& dir, bool v2) {
    if (v2) {
        std::ifstream file(dir / "cpu.max");
        std::string quota;
        double period = 0;
        if (!(file >> quota >> period) || quota == "max") return 0;
        try {
            return cpus_of(std::stod(quota), period);
        } catch (const std::exception&) {
            return 0;
        }
    }
    std::ifstream quota_file(dir / "cpu.cfs_quota_us"), period_file(dir / "cpu.cfs_period_us");
    double quota = 0, period = 0;
    if (!(quota_file >> quota) || !(period_file >> period)) return 0;
    return cpus_of(quota, period);  // -1: no quota
}

// The tightest quota from `dir` up to `top`. In a container the path /proc/self/cgroup names
// may not exist under its own mount, whose root is then the container's cgroup: the walk
// up reaches it.
unsigned tightest_quota(const fs::path& top, const fs::path& relative, bool v2) {
    unsigned tightest = 0;
    for (fs::path dir = relative.empty() ? top : top / relative;;) {
        tightest = tighter(tightest, quota_in(dir, v2));
        const fs::path up = dir.parent_path();
        if (dir == top || up == dir || up.native().size() < top.native().size()) break;
        dir = up;
    }
    return tightest;
}

}  // namespace

unsigned cgroup_cpu_quota(const std::string& proc_self_cgroup, const std::string& cgroup_root) {
    const fs::path root(cgroup_root);
    std::istringstream lines(proc_self_cgroup);
    unsigned tightest = 0;
    // Lines "id:controllers:path": v2 is "0::path"; v1's CPU controller is listed as "cpu",
    // usually with "cpuacct", and mounted under that list's name.
    for (std::string line; std::getline(lines, line);) {
        const std::size_t first = line.find(':'), second = line.find(':', first + 1);
        if (first == std::string::npos || second == std::string::npos) continue;
        const std::string controllers = line.substr(first + 1, second - first - 1);
        const std::string path = line.substr(second + 1);
        const fs::path relative = fs::path(path).relative_path();
        if (line.compare(0, first, "0") == 0 && controllers.empty()) {
            tightest = tighter(tightest, tightest_quota(root, relative, true));
            continue;
        }
        std::istringstream names(controllers);
        bool cpu = false;
        for (std::string name; std::getline(names, name, ',');) cpu = cpu || name == "cpu";
        if (!cpu) continue;
        for (const std::string& mount : {controllers, std::string("cpu"), std::string("cpu,cpuacct")}) {
            const fs::path top = root / mount;
            std::error_code ec;
            if (!fs::is_directory(top, ec)) continue;
            tightest = tighter(tightest, tightest_quota(top, relative, false));
            break;
        }
    }
    return tightest;
}

unsigned usable_cpus() {
    unsigned cpus = std::thread::hardware_concurrency();
#if defined(__linux__)
    cpu_set_t mask;
    if (sched_getaffinity(0, sizeof mask, &mask) == 0 && CPU_COUNT(&mask) > 0)
        cpus = static_cast<unsigned>(CPU_COUNT(&mask));
    std::ifstream file("/proc/self/cgroup");
    const std::string cgroups((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    if (const unsigned quota = cgroup_cpu_quota(cgroups, "/sys/fs/cgroup"); quota > 0) cpus = std::min(cpus, quota);
#endif
    return std::max(cpus, 1u);
}

}  // namespace voxmesh::detail
