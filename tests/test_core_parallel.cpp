// run_workers on the cached threads (src/core/parallel.cpp): every worker runs once per run,
// runs nest and overlap without waiting on each other's threads, exceptions come back, a
// forked child starts threads of its own, and a worker whose thread cannot start runs anyway.
#include <catch2/catch.hpp>

#include "core/parallel.hpp"
#include "support/child_process.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#if defined(__linux__)
#include <sched.h>
#endif

using namespace voxmesh::detail;

TEST_CASE("run_workers runs each worker index once, run after run", "[core][parallel]") {
    for (unsigned n : {1u, 2u, 3u, 8u, 33u, 2u, 16u}) {
        std::vector<std::atomic<int>> seen(n);
        run_workers(n, [&](unsigned w) { seen[w] += 1; });
        for (unsigned w = 0; w < n; ++w) CHECK(seen[w] == 1);
    }
}

// A worker that has returned frees its thread for the run's later workers; ones that have not
// keep theirs, so that a run's workers can always all be running at once.
TEST_CASE("run_workers: workers of one run can wait for each other", "[core][parallel]") {
    const unsigned n = 12;
    std::atomic<unsigned> arrived{0};
    run_workers(n, [&](unsigned) {
        arrived += 1;
        while (arrived.load() < n) std::this_thread::yield();
    });
    CHECK(arrived == n);
}

TEST_CASE("run_workers nests and runs from several threads at once", "[core][parallel]") {
    std::atomic<unsigned> calls{0};
    run_workers(4, [&](unsigned) {
        run_workers(5, [&](unsigned) {
            run_workers(3, [&](unsigned) { calls += 1; });
        });
    });
    CHECK(calls == 4 * 5 * 3);
}

TEST_CASE("run_workers rethrows a worker's exception after all have returned", "[core][parallel]") {
    std::atomic<unsigned> finished{0};
    CHECK_THROWS_WITH(run_workers(6,
                                  [&](unsigned w) {
                                      if (w == 3) throw std::runtime_error("worker 3 failed");
                                      std::this_thread::sleep_for(std::chrono::milliseconds(5));
                                      finished += 1;
                                  }),
                      "worker 3 failed");
    CHECK(finished == 5);
    CHECK_THROWS_AS(run_workers(1, [](unsigned) { throw std::logic_error("alone"); }), std::logic_error);
    // The threads are usable again afterwards.
    std::atomic<unsigned> again{0};
    run_workers(6, [&](unsigned) { again += 1; });
    CHECK(again == 6);
}

// Runs from several threads at once, some nested, take and give back the same cached threads
// run after run. A run once waited for a worker's count of finished tasks to equal the count
// it expected: a worker that finished, went idle and was taken by another run before the
// first run looked was then never seen done, and the run waited for ever (within about 100
// runs per caller). The runs go on a thread of their own, so that a hang ends the test process
// at a deadline, failed; in process, so that ThreadSanitizer sees them.
TEST_CASE("run_workers: overlapping and nested runs on the same threads all return", "[core][parallel]") {
    constexpr unsigned kCallers = 3, kRuns = 1000;
    const auto size_of = [](unsigned caller, unsigned run) { return 1 + (7 * run + 5 * caller) % 17; };
    const auto nested = [](unsigned caller, unsigned run) { return (run + caller) % 4 == 0; };
    unsigned long expected = 0;
    for (unsigned c = 0; c < kCallers; ++c)
        for (unsigned r = 0; r < kRuns; ++r) expected += size_of(c, r) * (nested(c, r) ? 4 : 1);
    auto calls = std::make_shared<std::atomic<unsigned long>>(0);
    auto finished = std::make_shared<std::promise<void>>();
    std::future<void> done = finished->get_future();
    std::thread([=] {
        const auto caller = [&](unsigned c) {
            for (unsigned r = 0; r < kRuns; ++r)
                run_workers(size_of(c, r), [&](unsigned) {
                    if (nested(c, r)) run_workers(3, [&](unsigned) { *calls += 1; });
                    *calls += 1;
                });
        };
        std::vector<std::thread> others;
        for (unsigned c = 1; c < kCallers; ++c) others.emplace_back(caller, c);
        caller(0);
        for (auto& t : others) t.join();
        finished->set_value();
    }).detach();
    if (done.wait_for(std::chrono::seconds(120)) != std::future_status::ready) {
        // The hung runs' threads would keep the process from ending: end it here, failed.
        std::fprintf(stderr, "run_workers: runs still waiting after 120 s (a hang)\n");
        std::_Exit(1);
    }
    CHECK(calls->load() == expected);
}

#if defined(__linux__)
// A worker woken after a long sleep could be put on the CPU of the thread that woke it, and
// the two then took turns there (parallel.cpp); a run now wakes its workers off the caller's
// CPU and leaves their affinity as it was.
TEST_CASE("run_workers wakes a sleeping worker off the caller's CPU and keeps its affinity", "[core][parallel]") {
    cpu_set_t all;
    REQUIRE(sched_getaffinity(0, sizeof all, &all) == 0);
    if (CPU_COUNT(&all) < 2) {
        WARN("one CPU allowed: nothing to check");
        return;
    }
    run_workers(2, [](unsigned) {});  // a cached worker started with every CPU allowed
    int caller = 0;
    while (!CPU_ISSET(caller, &all)) ++caller;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(caller, &one);
    REQUIRE(sched_setaffinity(0, sizeof one, &one) == 0);  // the caller stays on `caller`
    for (int round = 0; round < 5; ++round) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        std::atomic<int> worker_cpu{-1};
        cpu_set_t worker_affinity;
        CPU_ZERO(&worker_affinity);
        run_workers(2, [&](unsigned w) {
            if (w == 0) {
                while (worker_cpu.load() < 0) std::this_thread::yield();  // keeps `caller` busy
                return;
            }
            sched_getaffinity(0, sizeof worker_affinity, &worker_affinity);
            worker_cpu = sched_getcpu();
        });
        CHECK(worker_cpu != caller);
        CHECK(CPU_EQUAL(&worker_affinity, &all));
    }
    sched_setaffinity(0, sizeof all, &all);
}
#endif

// A child of a process whose cache holds threads has none of them (fork copies only the
// thread that called it): its runs start threads of their own instead of waiting for ever.
TEST_CASE("run_workers in a forked child starts threads of its own", "[core][parallel]") {
    if (!vmtest::threads_after_fork_or_warn()) return;
    run_workers(4, [](unsigned) {});  // threads in the cache, idle
    const std::string child = vmtest::output_of_child(
        [] {
            std::vector<std::atomic<int>> seen(4);
            run_workers(4, [&](unsigned w) { seen[w] += 1; });
            for (auto& s : seen)
                if (s != 1) return std::string("a worker ran ") + std::to_string(s.load()) + " times";
            return std::string("ran");
        },
        30);
    CHECK(child == "ran");
    run_workers(4, [](unsigned) {});  // and the parent's cache still works
}

// A thread the cache cannot start (a limit on threads or memory; the hook stands for one)
// leaves its worker to the caller: a run still runs every worker once, where the exception
// used to escape mid-run and leave the started workers using the caller's finished frame.
TEST_CASE("run_workers runs on the caller the workers whose threads cannot start", "[core][parallel]") {
    const auto threads_here = static_cast<unsigned>(vmtest::proc_status_number("Threads:"));
    const unsigned n = threads_here + 8;  // more than the cache has idle: some must be started
    std::vector<std::atomic<int>> seen(n);
    std::atomic<unsigned> on_caller{0};
    const std::thread::id caller = std::this_thread::get_id();
    refuse_new_threads_for_testing(true);
    run_workers(n, [&](unsigned w) {
        seen[w] += 1;
        if (std::this_thread::get_id() == caller) on_caller += 1;
        else std::this_thread::sleep_for(std::chrono::milliseconds(50));  // busy: not idle for the next post
    });
    refuse_new_threads_for_testing(false);
    for (unsigned w = 0; w < n; ++w) CHECK(seen[w] == 1);
    CHECK(on_caller >= 8);  // worker 0 and at least the 7 the idle threads could not take
    std::atomic<unsigned> again{0};
    run_workers(n, [&](unsigned) { again += 1; });  // and threads start again afterwards
    CHECK(again == n);
}
