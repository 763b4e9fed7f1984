// A small persistent pool of worker threads: update() runs every frame, and starting and
// joining threads each time costs more than re-meshing a few blocks. The caller is worker 0;
// threads for workers 1..n-1 start on first use and wait on a condition variable between
// runs. One run at a time (a Sculpt is used from one thread at a time).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace voxmesh::detail::sculpt {

class WorkerPool {
public:
    WorkerPool() = default;
    WorkerPool(const WorkerPool&) = delete;
    WorkerPool& operator=(const WorkerPool&) = delete;

    ~WorkerPool() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            stopping_ = true;
        }
        wake_.notify_all();
        for (std::thread& t : threads_) t.join();
    }

    // Runs f(0..n-1) in parallel and returns when all have returned; rethrows the first
    // exception any of them threw.
    void run(unsigned n, const std::function<void(unsigned)>& f) {
        if (n <= 1) {
            f(0);
            return;
        }
        std::unique_lock<std::mutex> lock(mutex_);
        while (threads_.size() < n - 1) {
            const unsigned worker = static_cast<unsigned>(threads_.size()) + 1;
            threads_.emplace_back([this, worker] { loop(worker); });
        }
        job_ = &f;
        workers_ = n;
        pending_ = n - 1;
        failure_ = nullptr;
        ++generation_;
        lock.unlock();
        wake_.notify_all();

        guarded(0, f);
        lock.lock();
        done_.wait(lock, [&] { return pending_ == 0; });
        job_ = nullptr;
        if (failure_) std::rethrow_exception(std::exchange(failure_, nullptr));
    }

private:
    void guarded(unsigned worker, const std::function<void(unsigned)>& f) {
        try {
            f(worker);
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!failure_) failure_ = std::current_exception();
        }
    }

    void loop(unsigned worker) {
        std::uint64_t seen = 0;
        std::unique_lock<std::mutex> lock(mutex_);
        for (;;) {
            wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
            if (stopping_) return;
            seen = generation_;
            if (worker >= workers_) continue;  // this run needs fewer workers
            const std::function<void(unsigned)>* job = job_;
            lock.unlock();
            guarded(worker, *job);
            lock.lock();
            if (--pending_ == 0) done_.notify_one();
        }
    }

    std::mutex mutex_;
    std::condition_variable wake_, done_;
    std::vector<std::thread> threads_;
    const std::function<void(unsigned)>* job_ = nullptr;
    unsigned workers_ = 0, pending_ = 0;
    std::uint64_t generation_ = 0;
    std::exception_ptr failure_;
    bool stopping_ = false;
};

}  // namespace voxmesh::detail::sculpt
