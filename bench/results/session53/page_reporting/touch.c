// Times first writes to fresh anonymous memory: each round maps MiB mebibytes, optionally
// advises transparent huge pages, memsets it and unmaps it. On this VM (Firecracker, free page
// reporting of 2 MiB blocks) a process's first round after a pause shows what memory the guest
// had handed back to the host costs.
//   cc -O2 -o /tmp/touch touch.c && /tmp/touch MiB ROUNDS [huge]
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

int main(int argc, char** argv) {
    if (argc < 3) return fprintf(stderr, "usage: touch MiB ROUNDS [huge]\n"), 2;
    const size_t bytes = (size_t)atol(argv[1]) << 20;
    const int rounds = atoi(argv[2]), huge = argc > 3;
    for (int i = 0; i < rounds; ++i) {
        char* p = mmap(NULL, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (p == MAP_FAILED) return perror("mmap"), 1;
        if (huge) madvise(p, bytes, MADV_HUGEPAGE);
        const double t = now();
        memset(p, 1, bytes);
        printf("%.1f ", (now() - t) * 1e3);
        munmap(p, bytes);
    }
    printf("ms\n");
    return 0;
}
