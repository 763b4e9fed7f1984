// 36 MiB MADV_HUGEPAGE mapping per round, faulted in by one thread pinned to CPU `fault_cpu`,
// unmapped by the main thread pinned to CPU `free_cpu`: populate times per round.
#include <sched.h>
#include <sys/mman.h>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>
using C = std::chrono::steady_clock;
static void pin(int cpu) { cpu_set_t s; CPU_ZERO(&s); CPU_SET(cpu, &s); sched_setaffinity(0, sizeof s, &s); }
int main(int argc, char** argv) {
    int fault_cpu = atoi(argv[1]), free_cpu = atoi(argv[2]);
    pin(free_cpu);
    const size_t n = 36u << 20;
    for (int round = 0; round < 10; ++round) {
        char* p = (char*)mmap(nullptr, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        madvise(p, n, MADV_HUGEPAGE);
        double ms = 0;
        std::thread t([&] { pin(fault_cpu); auto t0 = C::now(); for (size_t o = 0; o < n; o += 4096) p[o] = 1;
                            ms = std::chrono::duration<double>(C::now() - t0).count() * 1e3; });
        t.join();
        std::printf("%6.2f ", ms);
        munmap(p, n);
    }
    std::printf(" ms (fault on cpu %d, free on cpu %d)\n", fault_cpu, free_cpu);
}
