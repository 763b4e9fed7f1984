// Runs f(0..n-1) on n std::threads (the caller runs worker 0) and rethrows the first
// exception a worker threw.
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace voxmesh::detail {

template <class F>
void run_workers(unsigned n, F&& f) {
    if (n <= 1) {
        f(0u);
        return;
    }
    std::exception_ptr failure;
    std::mutex failure_mutex;
    auto guarded = [&](unsigned w) {
        try {
            f(w);
        } catch (...) {
            std::lock_guard<std::mutex> lock(failure_mutex);
            if (!failure) failure = std::current_exception();
        }
    };
    std::vector<std::thread> pool;
    pool.reserve(n - 1);
    for (unsigned w = 1; w < n; ++w) pool.emplace_back(guarded, w);
    guarded(0);
    for (auto& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
}

// Hardware concurrency when `requested` is 0, at least 1.
unsigned resolve_threads(unsigned requested);

// Runs f(0..n-1) for n independent pieces of work (slabs) on at most max_threads threads and
// at most as many as the machine runs at once: more threads than that only take turns on the same cores, and a slab
// whose thread is descheduled holds up the rest. Threads pull slabs in order; the partition,
// and so the output, is the caller's and does not depend on the cap.
// f(slab, worker): worker < the number of threads used, so per-thread scratch can be kept
// from one slab to the next.
template <class F>
void run_slabs(unsigned n, unsigned max_threads, F&& f) {
    const unsigned threads = std::min({n, std::max(max_threads, 1u), resolve_threads(0)});
    std::atomic<unsigned> next{0};
    run_workers(threads, [&](unsigned worker) {
        for (unsigned slab = next++; slab < n; slab = next++) f(slab, worker);
    });
}

}  // namespace voxmesh::detail
