// "0 threads = all cores" counts the CPUs this process may run on (src/core/cpu_count.cpp):
// its affinity mask, and the cgroup CPU quota read from fake cgroup trees here.
#include <catch2/catch.hpp>

#include "core/cpu_count.hpp"
#include "core/parallel.hpp"
#include "support/mesh_checks.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#if defined(__linux__)
#include <sched.h>
#endif

using voxmesh::detail::cgroup_cpu_quota;

namespace {

void write_text(const std::filesystem::path& path, const std::string& text) {
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path) << text;
}

}  // namespace

TEST_CASE("cgroup v2: the tightest cpu.max from the process's cgroup up, rounded up", "[core][threads]") {
    vmtest::TempDir dir;
    const std::filesystem::path root = dir.path();
    const std::string cgroup = "0::/user.slice/job.scope\n";
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 0);  // no files: no quota
    write_text(root / "user.slice/job.scope/cpu.max", "max 100000\n");
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 0);
    write_text(root / "user.slice/job.scope/cpu.max", "250000 100000\n");
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 3);  // 2.5 CPUs: a third thread gets half a core
    write_text(root / "user.slice/cpu.max", "150000 100000\n");
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 2);  // the parent's quota binds its children too
    write_text(root / "cpu.max", "50000 100000\n");
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 1);
    write_text(root / "cpu.max", "garbage\n");
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 2);
    // In a container the path may name the host's cgroup, absent from the container's mount,
    // whose root is the container's own.
    write_text(root / "cpu.max", "400000 100000\n");
    CHECK(cgroup_cpu_quota("0::/docker/0123abcd\n", root.string()) == 4);
    CHECK(cgroup_cpu_quota("0::/\n", root.string()) == 4);
}

TEST_CASE("cgroup v1: cpu.cfs_quota_us over cpu.cfs_period_us under the cpu controller's mount", "[core][threads]") {
    vmtest::TempDir dir;
    const std::filesystem::path root = dir.path();
    const std::string cgroup = "12:pids:/a\n4:cpu,cpuacct:/slurm/job_7\n1:name=systemd:/\n0::/\n";
    write_text(root / "cpu,cpuacct/slurm/job_7/cpu.cfs_quota_us", "-1\n");
    write_text(root / "cpu,cpuacct/slurm/job_7/cpu.cfs_period_us", "100000\n");
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 0);  // -1: none
    write_text(root / "cpu,cpuacct/slurm/job_7/cpu.cfs_quota_us", "600000\n");
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 6);
    // Mounted as plain "cpu": found all the same.
    std::filesystem::rename(root / "cpu,cpuacct", root / "cpu");
    CHECK(cgroup_cpu_quota(cgroup, root.string()) == 6);
    CHECK(cgroup_cpu_quota("3:cpuacct:/slurm/job_7\n", root.string()) == 0);  // not the cpu controller
}

#if defined(__linux__)
TEST_CASE("the usable CPUs follow the affinity mask", "[core][threads]") {
    cpu_set_t all;
    REQUIRE(sched_getaffinity(0, sizeof all, &all) == 0);
    const unsigned allowed = static_cast<unsigned>(CPU_COUNT(&all));
    CHECK(voxmesh::detail::usable_cpus() <= allowed);
    CHECK(voxmesh::detail::resolve_threads(0) == voxmesh::detail::usable_cpus());
    CHECK(voxmesh::detail::resolve_threads(3) == 3);
    if (allowed < 2) {
        WARN("one CPU allowed: the narrowed mask cannot be told apart");
        return;
    }
    // This thread alone pinned to its first allowed CPU: it may use one.
    int first = 0;
    while (!CPU_ISSET(first, &all)) ++first;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    const unsigned at_load = voxmesh::detail::resolve_threads(0);
    REQUIRE(sched_setaffinity(0, sizeof one, &one) == 0);
    const unsigned pinned = voxmesh::detail::usable_cpus();
    const unsigned resolved_pinned = voxmesh::detail::resolve_threads(0);
    sched_setaffinity(0, sizeof all, &all);
    CHECK(pinned == 1);
    // "All cores" was counted at load: a caller pinning its own thread (a render thread on one
    // core) still gets every core the process has.
    CHECK(resolved_pinned == at_load);
}
#endif

TEST_CASE("Stats::workers: the threads asked for, capped at the CPUs this process may use", "[core][threads]") {
    const vmtest::Dims dims{24, 24, 24};
    const auto data = vmtest::sample_field<float>(dims, vmtest::sphere({11.5, 11.5, 11.5}, 8));
    const unsigned usable = voxmesh::detail::resolve_threads(0);
    for (const unsigned threads : {1u, 2u, 64u}) {
        INFO(threads << " threads asked for, " << usable << " usable");
        voxmesh::Stats stats;
        (void)voxmesh::extract(vmtest::view_of(data, dims), vmtest::cpu_options(0.0, threads), stats);
        CHECK(stats.threads == threads);
        CHECK(stats.workers == std::min(threads, usable));
    }
}
