// One process of extract() calls (or extract_into() with "r"): per call its time, classify and
// generate (which includes sizing the output), page faults, THP allocations, user and system CPU.
//   calls THREADS CALLS [r|x] [s|g sphere|gyroid] [f|u f32|u8] [SIZE]
#include <voxmesh/voxmesh.hpp>
#include <voxmesh/fields.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <sys/resource.h>
static long vmstat(const char* key) {
    std::ifstream f("/proc/vmstat"); std::string k; long v;
    while (f >> k >> v) if (k == key) return v;
    return -1;
}
int main(int argc, char** argv) {
    unsigned threads = argc > 1 ? std::atoi(argv[1]) : 2;
    int calls = argc > 2 ? std::atoi(argv[2]) : 12;
    bool reuse = argc > 3 && argv[3][0] == 'r';
    bool gyroid = argc > 4 && argv[4][0] == 'g'; bool u8 = argc > 5 && argv[5][0] == 'u';
    std::size_t size = argc > 6 ? std::atoi(argv[6]) : 512;
    auto field = voxmesh::make_field(gyroid ? voxmesh::Field::Gyroid : voxmesh::Field::Sphere, size, u8 ? voxmesh::ScalarType::U8 : voxmesh::ScalarType::F32);
    voxmesh::Options o; o.iso = field.iso; o.backend = voxmesh::Backend::Cpu; o.threads = threads;
    voxmesh::Mesh kept;
    for (int c = 0; c < calls; ++c) {
        rusage r0, r1; getrusage(RUSAGE_SELF, &r0);
        long a0 = vmstat("thp_fault_alloc"), f0 = vmstat("thp_fault_fallback");
        voxmesh::Stats st;
        auto t0 = std::chrono::steady_clock::now();
        std::size_t tris;
        if (reuse) { voxmesh::extract_into(field.volume.view(), o, kept, st); tris = kept.triangle_count(); }
        else { auto m = voxmesh::extract(field.volume.view(), o, st); tris = m.triangle_count(); }
        double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        getrusage(RUSAGE_SELF, &r1);
        auto tv=[](timeval a){return a.tv_sec*1e3+a.tv_usec*1e-3;};
        std::printf("call %2d %.4f s cls %.4f gen %.4f  minflt %6ld  thp_alloc %4ld fallback %ld tris %zu user %.1f sys %.1f ms ivcsw %ld vcsw %ld\n", c, s,
                    st.times.classify, st.times.generate, r1.ru_minflt - r0.ru_minflt,
                    vmstat("thp_fault_alloc") - a0, vmstat("thp_fault_fallback") - f0, tris, tv(r1.ru_utime)-tv(r0.ru_utime), tv(r1.ru_stime)-tv(r0.ru_stime), r1.ru_nivcsw-r0.ru_nivcsw, r1.ru_nvcsw-r0.ru_nvcsw);
    }
}
