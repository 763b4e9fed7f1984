#include "common.hpp"

#include <cstdlib>

#if defined(__linux__)
#include <sched.h>
#include <unistd.h>
#endif

namespace voxmesh::cli {

// A process's first OpenCL calls on PoCL (OpenCL on the CPU) took up to twice their steady
// time, while PoCL's two worker threads took turns on one core before Linux spread them
// (the demo printed OpenCL at 0.50-0.67x the CPU engine, 0.64-0.69x pinned; bench/NOTES.md,
// eighteenth session). POCL_AFFINITY=1 pins PoCL's worker i to CPU i. Set here, in the tool,
// not in the library: it is the process's environment. Not where the user set it, and not
// where this process may not run on every CPU 0..n-1 (PoCL would pin to one it may not use).
void pin_pocl_workers() {
#if defined(__linux__)
    if (std::getenv("POCL_AFFINITY")) return;
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    if (sched_getaffinity(0, sizeof(allowed), &allowed) != 0) return;
    const long cpus = sysconf(_SC_NPROCESSORS_CONF);
    if (cpus <= 0 || cpus > CPU_SETSIZE) return;
    for (long c = 0; c < cpus; ++c)
        if (!CPU_ISSET(static_cast<int>(c), &allowed)) return;
    setenv("POCL_AFFINITY", "1", 0);
#endif
}

}  // namespace voxmesh::cli
