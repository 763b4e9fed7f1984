// Runs f(0..n-1) on n std::threads (the caller runs worker 0) and rethrows the first
// exception a worker threw.
#pragma once

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

}  // namespace voxmesh::detail
