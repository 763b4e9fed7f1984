// The process's cache of idle worker threads behind run_workers (parallel.hpp).
//
// Starting and joining a std::thread costs tens of microseconds, more in virtual machines
// (about 0.4 ms for 15 threads on a 16-core one), and an extract forks and joins its workers
// two or three times, Hybrid more often: at 256³ that was a tenth of the call. Threads that
// finish a task wait here, each on its own condition variable, for the next; a run takes as
// many idle ones as it needs and starts new ones only when none is idle, so nested and
// concurrent runs (Hybrid's CPU worker inside the engine's workers, several extracts at once)
// never wait for each other's threads.
#include "parallel.hpp"

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace voxmesh::detail {
namespace {

class ThreadCache {
public:
    ~ThreadCache() {
        std::vector<std::unique_ptr<Worker>> all;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            all = std::move(workers_);
        }
        for (auto& w : all) {
            {
                std::lock_guard<std::mutex> lock(w->mutex);
                w->stop = true;
            }
            w->wake.notify_one();
            w->thread.join();
        }
    }

    // Runs task on an idle thread (or a new one).
    void post(std::function<void()> task) {
        Worker* w = nullptr;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!idle_.empty()) {
                w = idle_.back();
                idle_.pop_back();
            } else {
                workers_.push_back(std::make_unique<Worker>());
                w = workers_.back().get();
                w->thread = std::thread([this, w] { loop(*w); });
            }
        }
        {
            std::lock_guard<std::mutex> lock(w->mutex);
            w->task = std::move(task);
        }
        w->wake.notify_one();
    }

private:
    struct Worker {
        std::mutex mutex;
        std::condition_variable wake;
        std::function<void()> task;
        bool stop = false;
        std::thread thread;
    };

    void loop(Worker& w) {
        for (;;) {
            std::function<void()> task;
            {
                std::unique_lock<std::mutex> lock(w.mutex);
                w.wake.wait(lock, [&] { return w.stop || task_set(w); });
                if (w.stop) return;
                task = std::move(w.task);
                w.task = nullptr;
            }
            task();  // never throws: run_workers' tasks catch everything
            std::lock_guard<std::mutex> lock(mutex_);
            idle_.push_back(&w);
        }
    }

    static bool task_set(const Worker& w) { return static_cast<bool>(w.task); }

    std::mutex mutex_;
    std::vector<std::unique_ptr<Worker>> workers_;
    std::vector<Worker*> idle_;
};

ThreadCache& cache() {
    static ThreadCache instance;
    return instance;
}

}  // namespace

void run_on_threads(unsigned n, const std::function<void(unsigned)>& f) {
    if (n <= 1) {
        f(0);
        return;
    }
    // The count lives with the tasks: the last one may still be notifying when the caller,
    // seeing 0, returns.
    const auto pending = std::make_shared<std::atomic<unsigned>>(n - 1);
    for (unsigned w = 1; w < n; ++w)
        cache().post([&f, pending, w] {
            f(w);
            if (pending->fetch_sub(1, std::memory_order_acq_rel) == 1) pending->notify_one();
        });
    f(0);
    for (unsigned left = pending->load(std::memory_order_acquire); left != 0;
         left = pending->load(std::memory_order_acquire))
        pending->wait(left, std::memory_order_acquire);
}

unsigned resolve_threads(unsigned requested) {
    if (requested > 0) return requested;
    const unsigned hw = std::thread::hardware_concurrency();
    return hw > 0 ? hw : 1;
}

}  // namespace voxmesh::detail
