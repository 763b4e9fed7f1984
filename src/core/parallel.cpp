// The process's cache of idle worker threads behind run_workers (parallel.hpp).
//
// Starting and joining a std::thread costs tens of microseconds, more in virtual machines
// (about 0.4 ms for 15 threads on a 16-core one), and an extract forks and joins its workers
// two or three times, Hybrid more often: at 256³ that was a tenth of the call. Threads that
// finish a task wait here, each on its own condition variable, for the next; a run takes as
// many idle ones as it needs and starts new ones only when none is idle, so nested and
// concurrent runs (Hybrid's CPU worker inside the engine's workers, several extracts at once)
// never wait for each other's threads.
//
// Waking a sleeping thread takes a futex call and the scheduler, about 25 µs each way on the
// 2-core VM (an empty two-thread run took 50 µs), and an extract forks and joins two or three
// times. So both sides spin a little before they sleep: a thread that finishes a task
// watches for the next one for kSpin, and the caller of a run watches for its tasks' end as
// long before it waits on the count.
//
// A thread that cannot be started (a limit on threads or memory) is not an error: its worker
// runs on the caller after worker 0, so a run's workers must never wait for each other
// without a deadline (none in voxmesh does).
//
// fork(): the child has only the thread that forked, so the cache forgets its threads there
// (pthread_atfork below) and the child starts its own; without that a run in the child posted
// its tasks to threads that were not there and waited for ever.
//
// A run also keeps its threads off the caller's CPU when it wakes or starts them (keep_off
// below): on Linux a thread woken or started after the process was idle for a while can be
// put on the CPU of the thread that woke it, and then the two take turns there.
#include "parallel.hpp"
#include "cpu_count.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

#if defined(__unix__) || defined(__APPLE__)
#include <pthread.h>
#endif
#if defined(__linux__)
#include <sched.h>
#endif

namespace voxmesh::detail {
namespace {

// Long enough to cover the gaps between an extract's passes (a scan, a small allocation),
// short enough that a thread with nothing coming soon gives its core back quickly.
constexpr auto kSpin = std::chrono::microseconds(100);

// Spins until ready() or kSpin has passed; returns ready().
template <class Ready>
bool spin_until(Ready ready) {
    const auto until = std::chrono::steady_clock::now() + kSpin;
    for (unsigned i = 0;; ++i) {
        if (ready()) return true;
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
        if (i % 64 == 63 && std::chrono::steady_clock::now() >= until) return ready();
    }
}

int current_cpu() {
#if defined(__linux__)
    return sched_getcpu();
#else
    return -1;
#endif
}

std::atomic<bool> g_refuse_new_threads{false};  // refuse_new_threads_for_testing

class ThreadCache;
std::atomic<ThreadCache*> g_live_cache{nullptr};  // for the fork handlers; null once destroyed

class ThreadCache {
public:
    ThreadCache() {
        g_live_cache.store(this);
#if defined(__unix__) || defined(__APPLE__)
        static std::once_flag registered;  // handlers cannot be removed: register them once
        std::call_once(registered, [] { pthread_atfork(before_fork, after_fork_in_parent, after_fork_in_child); });
#endif
    }

    ~ThreadCache() {
        g_live_cache.store(nullptr);
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

    struct Worker {
        std::mutex mutex;
        std::condition_variable wake;
        const std::function<void(unsigned)>* job = nullptr;  // the task: (*job)(index)
        unsigned index = 0;
        std::atomic<bool> has_task{false};  // job is set; read while spinning, without the lock
        std::atomic<bool> spinning{false};  // awake, watching has_task: no wake-up to place
        std::atomic<std::uint32_t> finished{0};  // tasks done; a Ticket waits on it
        bool stop = false;
        std::thread thread;
#if defined(__linux__)
        bool kept_off = false;      // its affinity is narrowed until it runs: restore `allowed`
        cpu_set_t allowed;
#endif
    };

    // A worker's part of a run: done once the worker's `finished` count has reached `target`.
    // Reached, not equal: once done the worker is idle, and another run may have it finish
    // more before this one looks.
    struct Ticket {
        Worker* worker;
        std::uint32_t target;
        bool reached(std::uint32_t count) const { return static_cast<std::int32_t>(count - target) >= 0; }
        bool done() const { return reached(worker->finished.load(std::memory_order_acquire)); }
        void wait() const {
            for (std::uint32_t seen = worker->finished.load(std::memory_order_acquire); !reached(seen);
                 seen = worker->finished.load(std::memory_order_acquire))
                worker->finished.wait(seen, std::memory_order_acquire);
        }
    };

    // Runs job(index) on an idle thread (or a new one), off caller_cpu if it can. job must
    // outlive the ticket's wait(). Allocates only when it starts a thread.
    Ticket post(const std::function<void(unsigned)>& job, unsigned index, int caller_cpu) {
        Worker* w = nullptr;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!idle_.empty()) {
                w = idle_.back();
                idle_.pop_back();
            } else {
                workers_.push_back(std::make_unique<Worker>());
                w = workers_.back().get();
                try {
                    // Room for every worker, so that a worker going idle never allocates.
                    idle_.reserve(workers_.size());
                    if (g_refuse_new_threads.load(std::memory_order_relaxed))
                        throw std::system_error(std::make_error_code(std::errc::resource_unavailable_try_again));
                    w->thread = std::thread([this, w] { loop(*w); });
                } catch (...) {
                    workers_.pop_back();  // no thread to join later
                    throw;
                }
            }
        }
        Ticket ticket{w, 0};
        {
            std::lock_guard<std::mutex> lock(w->mutex);
            w->job = &job;
            w->index = index;
            // Only this worker advances its count, and it is idle: the count is settled.
            ticket.target = w->finished.load(std::memory_order_relaxed) + 1;
            // A spinning worker takes the task where it runs; only a sleeping one is placed
            // by the wake. (One whose spin is ending blocks on this lock and finds the task.)
            if (!w->spinning.load(std::memory_order_relaxed)) w->kept_off = keep_off(*w, caller_cpu);
            w->has_task.store(true, std::memory_order_release);
        }
        w->wake.notify_one();
        return ticket;
    }

private:
    // The cache's own lock is held across fork(), so the child's copy of the lists is whole.
    static void before_fork() {
        if (ThreadCache* c = g_live_cache.load()) c->mutex_.lock();
    }
    static void after_fork_in_parent() {
        if (ThreadCache* c = g_live_cache.load()) c->mutex_.unlock();
    }
    // The workers' threads do not exist in the child: their records are kept (a std::thread
    // still joinable must not be destroyed, and leak checkers see them as reachable) but no
    // longer offered, and the child's runs start threads of their own.
    static void after_fork_in_child() {
        ThreadCache* c = g_live_cache.load();
        if (!c) return;
        static std::vector<std::unique_ptr<Worker>>* abandoned = new std::vector<std::unique_ptr<Worker>>;
        for (auto& w : c->workers_) abandoned->push_back(std::move(w));
        c->workers_.clear();
        c->idle_.clear();
        c->mutex_.unlock();
    }

#if defined(__linux__)
    // On this project's 2-core VM (Linux 6.18) a thread woken, or started, after the process
    // had been idle for about 5 ms was put on the CPU of the thread that woke or started it,
    // and both stayed there: sphere u8 256³ on 2 threads with a 10 ms pause before each call
    // took 5.7 ms, as long as on one thread, where back to back it took 2.9 ms. So before it
    // wakes or starts a worker, the caller leaves its own CPU out of the worker's affinity
    // (the kernel places the thread within it), and the worker restores its affinity when it
    // takes the task.
    static bool keep_off(Worker& w, int cpu) {
        const pthread_t thread = w.thread.native_handle();
        if (cpu < 0 || cpu >= CPU_SETSIZE) return false;
        if (pthread_getaffinity_np(thread, sizeof w.allowed, &w.allowed) != 0) return false;
        if (!CPU_ISSET(cpu, &w.allowed) || CPU_COUNT(&w.allowed) < 2) return false;
        cpu_set_t others = w.allowed;
        CPU_CLR(cpu, &others);
        return pthread_setaffinity_np(thread, sizeof others, &others) == 0;
    }
#else
    static bool keep_off(Worker&, int) { return false; }
#endif

    // After its task a worker frees nothing and allocates nothing: the run it served may have
    // returned, and its caller forked, at any point from the count's step on. (An allocator
    // that takes no locks across fork, as ASan's, would leave the child a lock held.)
    void loop(Worker& w) {
        for (;;) {
            w.spinning.store(true, std::memory_order_relaxed);
            spin_until([&] { return w.has_task.load(std::memory_order_acquire); });
            w.spinning.store(false, std::memory_order_relaxed);
            const std::function<void(unsigned)>* job = nullptr;
            unsigned index = 0;
            {
                std::unique_lock<std::mutex> lock(w.mutex);
                w.wake.wait(lock, [&] { return w.stop || w.job != nullptr; });
                if (w.stop) return;
                job = w.job;
                index = w.index;
                w.job = nullptr;
                w.has_task.store(false, std::memory_order_relaxed);
#if defined(__linux__)
                // On a CPU of the narrowed set, which the full one includes: nothing moves.
                if (w.kept_off) sched_setaffinity(0, sizeof w.allowed, &w.allowed);
                w.kept_off = false;
#endif
            }
            (*job)(index);  // never throws: run_workers' tasks catch everything
            // Counted before the worker is idle again, so a run that takes it next reads the
            // settled count for its target.
            w.finished.fetch_add(1, std::memory_order_acq_rel);
            w.finished.notify_one();
            std::lock_guard<std::mutex> lock(mutex_);
            idle_.push_back(&w);  // within the room post() reserved
        }
    }

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
    const int caller_cpu = current_cpu();
    std::vector<ThreadCache::Ticket> tickets;
    tickets.reserve(n - 1);
    unsigned posted = 1;
    for (; posted < n; ++posted) {
        try {
            tickets.push_back(cache().post(f, posted, caller_cpu));
        } catch (...) {
            break;  // no thread to be had (a limit on threads or memory): the caller runs the rest
        }
    }
    f(0);
    for (unsigned w = posted; w < n; ++w) f(w);
    spin_until([&] { return std::all_of(tickets.begin(), tickets.end(), [](const auto& t) { return t.done(); }); });
    for (const auto& t : tickets) t.wait();
}

void refuse_new_threads_for_testing(bool refuse) { g_refuse_new_threads.store(refuse); }

unsigned resolve_threads(unsigned requested) {
    if (requested > 0) return requested;
    // Counted once: the engines size per-worker tables and their runs by it separately in one
    // call, so it must not change under them.
    static const unsigned usable = usable_cpus();
    return usable;
}

namespace {
// ... and counted when the library is loaded, before the program pins threads of its own (as
// libgomp counts its threads): the affinity mask is the calling thread's, and a render
// thread pinned to one core must not make every extract it calls single-threaded.
[[maybe_unused]] const unsigned g_counted_at_load = resolve_threads(0);
}  // namespace

}  // namespace voxmesh::detail
