// run_workers on the cached threads (src/core/parallel.cpp): every worker runs once per run,
// runs nest and overlap without waiting on each other's threads, and exceptions come back.
#include <catch2/catch.hpp>

#include "core/parallel.hpp"

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

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
