// How many CPUs this process may run on, for "0 threads = all cores": not the machine's count
// (std::thread::hardware_concurrency), which a process pinned by taskset, given a cpuset by
// Slurm, or run in a container with a CPU quota (docker --cpus) does not get. More workers
// than that take turns on the same cores, and spin while they wait.
#pragma once

#include <string>

namespace voxmesh::detail {

// The affinity mask's CPUs, capped by the cgroup CPU quota (rounded up), at least 1. Counted
// afresh on every call (resolve_threads counts once per process).
unsigned usable_cpus();

// The cgroup CPU quota in whole CPUs (rounded up), 0 when there is none: the tightest
// cpu.max (cgroup v2) or cpu.cfs_quota_us / cpu.cfs_period_us (v1) of the process's cgroup
// and those above it. `proc_self_cgroup` is /proc/self/cgroup's text and `cgroup_root` where
// the cgroup file systems are mounted (/sys/fs/cgroup); parameters, so tests can fake both.
unsigned cgroup_cpu_quota(const std::string& proc_self_cgroup, const std::string& cgroup_root);

}  // namespace voxmesh::detail
