// Worker threads for the engines: run_workers, run_slabs and the thread count to use.
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace voxmesh::detail {

// Runs f(0..n-1) in parallel, worker 0 on the calling thread and the others on threads from
// a process-wide cache of idle threads (parallel.cpp), and returns when all have returned.
// f must not throw. A worker whose thread cannot be started runs on the caller after worker 0,
// so workers must not wait for each other without a deadline.
void run_on_threads(unsigned n, const std::function<void(unsigned)>& f);

// Test hook: the cache starts no new thread while set (as when a limit on threads or memory
// refuses one); idle threads still take work.
void refuse_new_threads_for_testing(bool refuse);

// run_on_threads for any callable: rethrows the first exception a worker threw, after all
// have returned.
template <class F>
void run_workers(unsigned n, F&& f) {
    if (n <= 1) {
        f(0u);
        return;
    }
    std::exception_ptr failure;
    std::mutex failure_mutex;
    run_on_threads(n, [&](unsigned w) {
        try {
            f(w);
        } catch (...) {
            std::lock_guard<std::mutex> lock(failure_mutex);
            if (!failure) failure = std::current_exception();
        }
    });
    if (failure) std::rethrow_exception(failure);
}

// `requested`, or when it is 0 the CPUs this process may run on (its affinity mask, capped by
// a cgroup CPU quota; cpu_count.hpp), counted when the library is loaded.
unsigned resolve_threads(unsigned requested);

// The workers that run for `requested` threads: resolve_threads(requested) capped at the CPUs
// (resolve_threads(0)); more only take turns on the same cores, each with its own scratch.
inline unsigned running_threads(unsigned requested) {
    return std::min(resolve_threads(requested), resolve_threads(0));
}

// Slabs for `threads` requested threads over `planes` planes: one for a single thread, else
// `per_thread` for each thread that actually runs (run_slabs caps them at resolve_threads(0)).
inline unsigned slab_count(unsigned threads, std::size_t planes, unsigned per_thread) {
    const unsigned running = running_threads(std::max(threads, 1u));
    const std::size_t slabs = running > 1 ? std::size_t{per_thread} * running : 1;
    return static_cast<unsigned>(std::max<std::size_t>(1, std::min(slabs, planes)));
}

// Share `part` of [0, n) split into `parts` consecutive shares of near-equal size: the range
// [begin, end) a worker takes when each takes its own.
struct Share {
    std::size_t begin, end;
};
inline Share share_of(std::size_t n, unsigned part, unsigned parts) {
    return {n * part / parts, n * (part + 1) / parts};
}

// Runs f(0..n-1) for n independent pieces of work (slabs) on at most max_threads threads and
// at most as many as this process can run at once (resolve_threads(0)): more threads than that only take turns on the same cores, and a slab
// whose thread is descheduled holds up the rest. Threads pull slabs in order; the partition,
// and so the output, is the caller's and does not depend on the cap.
// f(slab, worker): worker < the number of threads used, so per-thread scratch can be kept
// from one slab to the next.
// Errors: the exception of the lowest slab that threw is rethrown, not the first in time, so
// a volume gives the same Error (e.g. the first z-plane holding NaN) on any thread count.
// Slabs after a failed one are skipped; those before it were taken already, in order.
template <class F>
void run_slabs(unsigned n, unsigned max_threads, F&& f) {
    const unsigned threads = std::min({n, std::max(max_threads, 1u), resolve_threads(0)});
    std::atomic<unsigned> next{0};
    std::atomic<unsigned> stop{n};  // the lowest failed slab so far
    std::exception_ptr failure;
    std::mutex failure_mutex;
    run_workers(threads, [&](unsigned worker) {
        for (unsigned slab = next++; slab < stop.load(std::memory_order_relaxed); slab = next++) {
            try {
                f(slab, worker);
            } catch (...) {
                std::lock_guard<std::mutex> lock(failure_mutex);
                if (slab < stop.load(std::memory_order_relaxed)) {
                    stop.store(slab, std::memory_order_relaxed);
                    failure = std::current_exception();
                }
            }
        }
    });
    if (failure) std::rethrow_exception(failure);
}

}  // namespace voxmesh::detail
