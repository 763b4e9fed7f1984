// The scratch pool (src/core/scratch.hpp): blocks are kept for the next call that fits, within
// its limits, and whatever an earlier call left in them never reaches a mesh.
#include <catch2/catch.hpp>

#include "core/scratch.hpp"
#include "support/child_process.hpp"
#include "support/mesh_checks.hpp"
#include "support/reference_mc.hpp"

#include <voxmesh/voxmesh.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

using namespace voxmesh::detail;
using vmtest::Dims;

TEST_CASE("scratch blocks are kept and handed out again, the smallest that fits first", "[core][scratch]") {
    release_scratch();
    CHECK(scratch_kept().blocks == 0);
    void* small_at = nullptr;
    void* large_at = nullptr;
    {
        const auto small = acquire_scratch(100 << 10, Pages::Small);
        const auto large = acquire_scratch(3 << 20, Pages::Small);
        small_at = small.get();
        large_at = large.get();
        std::memset(small.get(), 1, 100 << 10);  // writable, all of it
        std::memset(large.get(), 2, 3 << 20);
        CHECK(scratch_kept().blocks == 0);  // out, not kept
    }
    CHECK(scratch_kept().blocks == 2);
    CHECK(scratch_kept().bytes == (100u << 10) + (3u << 20));
    {
        const auto a = acquire_scratch(50 << 10, Pages::Small);  // fits both: gets the small one
        CHECK(a.get() == small_at);
        const auto b = acquire_scratch(1 << 20, Pages::Small);  // fits only the large one
        CHECK(b.get() == large_at);
        CHECK(scratch_kept().blocks == 0);
        const auto c = acquire_scratch(4 << 20, Pages::Small);  // nothing fits: a new block
        CHECK(c.get() != small_at);
        CHECK(c.get() != large_at);
    }
    CHECK(scratch_kept().blocks == 3);
    {
        // A block is handed out again only for its kind of pages.
        const auto huge = acquire_scratch(50 << 10, Pages::Huge);
        CHECK(huge.get() != small_at);
        CHECK(huge.get() != large_at);
        CHECK(scratch_kept().blocks == 3);
    }
    CHECK(scratch_kept().blocks == 4);
    release_scratch();
    CHECK(scratch_kept().blocks == 0);
    CHECK(scratch_kept().bytes == 0);
}

TEST_CASE("the scratch pool keeps at most its limits, the oldest blocks going first", "[core][scratch]") {
    release_scratch();
    {
        std::vector<std::shared_ptr<void>> many;
        for (int i = 0; i < 100; ++i) many.push_back(acquire_scratch(4096, Pages::Small));
    }
    CHECK(scratch_kept().blocks == 64);
    {
        // Larger than everything the pool may keep: freed, not kept, and nothing else goes.
        const auto huge = acquire_scratch(std::size_t{600} << 20, Pages::Small);
        CHECK(huge.get() != nullptr);
    }
    CHECK(scratch_kept().blocks == 64);
    release_scratch();
    SECTION("an array's size that overflows is refused") {
        CHECK_THROWS_AS(ScratchArray<std::uint64_t>(SIZE_MAX / 4, Pages::Small), std::bad_alloc);
    }
}

TEST_CASE("a large block is not held for small requests and goes once it sits idle", "[core][scratch]") {
    release_scratch();
    void* large_at = nullptr;
    {
        const auto large = acquire_scratch(std::size_t{8} << 20, Pages::Small);
        large_at = large.get();
    }
    CHECK(scratch_kept().bytes == std::size_t{8} << 20);
    {
        // Less than a quarter of it: a block of its own, the large one stays kept.
        const auto small = acquire_scratch(std::size_t{1} << 20, Pages::Small);
        CHECK(small.get() != large_at);
        CHECK(scratch_kept().blocks == 1);
        // A quarter or more: the large one.
        const auto quarter = acquire_scratch(std::size_t{2} << 20, Pages::Small);
        CHECK(quarter.get() == large_at);
    }
    CHECK(scratch_kept().blocks == 2);
    {
        // Below 1 MiB a kept block serves any smaller request.
        const auto tiny = acquire_scratch(100, Pages::Small);
        CHECK(tiny.get() != large_at);
    }
    // Small requests only, as a program meshing small volumes after a large one. The large
    // block came back at request 3: it is kept through request 3 + kScratchIdleRequests and
    // goes at the next, while the small one keeps being reused.
    for (std::size_t request = 5; request <= 3 + kScratchIdleRequests; ++request)
        acquire_scratch(std::size_t{1} << 20, Pages::Small);
    CHECK(scratch_kept().blocks == 2);
    CHECK(scratch_kept().bytes >= std::size_t{8} << 20);
    acquire_scratch(std::size_t{1} << 20, Pages::Small);
    CHECK(scratch_kept().blocks == 1);
    CHECK(scratch_kept().bytes == std::size_t{1} << 20);
    release_scratch();
}

namespace {

// Fills the pool with blocks of every size an extract below asks for, all bytes `garbage`.
void dirty_pool(unsigned char garbage) {
    release_scratch();
    std::vector<std::shared_ptr<void>> blocks;
    for (const Pages pages : {Pages::Small, Pages::Huge})
        for (std::size_t bytes = 1 << 10; bytes <= std::size_t{8} << 20; bytes *= 2) {
            blocks.push_back(acquire_scratch(bytes, pages));
            std::memset(blocks.back().get(), garbage, bytes);
        }
}

// Meshes `values` from scratch filled with each garbage byte, on 1 to 3 threads, and compares
// with the reference mesh.
template <class T>
void check_from_dirty_scratch(const std::vector<T>& values, const Dims& dims, double iso) {
    vmtest::RefOptions ro;
    ro.iso = iso;
    const vmtest::RefMesh ref = vmtest::reference_mc(vmtest::to_doubles(values), dims, ro);
    for (unsigned char garbage : {0x00, 0xff, 0xa5}) {
        for (unsigned threads : {1u, 2u, 3u}) {
            INFO("garbage " << int(garbage) << ", threads " << threads);
            dirty_pool(garbage);
            const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(values, dims), vmtest::cpu_options(iso, threads));
            REQUIRE(mesh.triangle_count() > 1000);
            const vmtest::Comparison cmp = vmtest::compare_with_reference(mesh, ref);
            INFO(cmp.first_problem);
            CHECK(cmp.same_indices);
            CHECK(cmp.max_position_error < 1e-5);
        }
    }
    release_scratch();
}

}  // namespace

TEST_CASE("meshes from dirty scratch are the reference's", "[core][scratch]") {
    // f32 keeps classify's bits in scratch, u8 does not; both keep row metadata and ids there.
    const Dims dims{45, 38, 41};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
    std::vector<std::uint8_t> bytes(values.size());
    for (std::size_t i = 0; i < values.size(); ++i)
        bytes[i] = static_cast<std::uint8_t>(std::lround(127 + 50 * values[i]));  // wavy: within ±2.5
    check_from_dirty_scratch(values, dims, 0.15);
    check_from_dirty_scratch(bytes, dims, 131.5);
}

TEST_CASE("an extract's scratch is kept for the next one and release_scratch_memory frees it", "[core][scratch]") {
    const Dims dims{64, 48, 40};
    const std::vector<float> values = vmtest::sample_field<float>(dims, vmtest::wavy(0.45));
    const voxmesh::VolumeView view = vmtest::view_of(values, dims);
    voxmesh::release_scratch_memory();
    // One thread: one generator, so exactly the row metadata (20 bytes a row), the kept bits
    // (8 bytes a row here) and one id table.
    const voxmesh::Mesh first = voxmesh::extract(view, vmtest::cpu_options(0.15, 1));
    const ScratchKept kept = scratch_kept();
    CHECK(kept.blocks == 3);
    CHECK(kept.bytes >= std::size_t{48} * 40 * (20 + 8));
    const voxmesh::Mesh second = voxmesh::extract(view, vmtest::cpu_options(0.15, 1));
    CHECK(scratch_kept().blocks == kept.blocks);  // reused, none added
    CHECK(scratch_kept().bytes == kept.bytes);
    CHECK(first.indices == second.indices);
    // Two threads: a call makes a generator (and takes an id table) per thread that got a
    // slab, one or two as the threads happen to run, so repeated calls keep at most one more.
    for (int call = 0; call < 5; ++call) {
        CHECK(voxmesh::extract(view, vmtest::cpu_options(0.15, 2)).indices == first.indices);
        CHECK(scratch_kept().blocks <= kept.blocks + 1);
    }
    voxmesh::release_scratch_memory();
    CHECK(scratch_kept().blocks == 0);
}

// Another thread inside the pool (taking or giving back a block) when this one forks: the pool's
// lock is held across fork(), so the fork waits for that thread to let go and the child's pool
// is whole and unlocked; before, the child's first extract waited for ever on the lock.
TEST_CASE("a child forked while another thread is inside the scratch pool can mesh", "[core][scratch]") {
    if (!vmtest::threads_after_fork_or_warn()) return;
    const vmtest::Dims dims{20, 20, 20};
    const auto data = vmtest::sample_field<float>(dims, vmtest::sphere({9.5, 9.5, 9.5}, 6));
    const voxmesh::Mesh expected = voxmesh::extract(vmtest::view_of(data, dims), vmtest::cpu_options(0.0, 2));
    std::promise<void> locked;
    // The holder stays alive until the child is done: a thread that ends frees its allocator
    // caches, and had it been doing that when fork() went on (right after it let go of the
    // pool), the child would inherit the allocator's lock held (AddressSanitizer's allocator,
    // in GCC 12, takes no locks across fork; the child's next malloc then waited for ever).
    std::atomic<int> child_done{0};
    std::thread holder([&] {
        voxmesh::detail::with_scratch_pool_locked_for_testing([&] {
            locked.set_value();
            std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the fork waits for this
        });
        child_done.wait(0);
    });
    locked.get_future().wait();
    const std::string child = vmtest::output_of_child(
        [&] {
            const voxmesh::Mesh mesh = voxmesh::extract(vmtest::view_of(data, dims), vmtest::cpu_options(0.0, 2));
            return std::string(mesh.indices == expected.indices ? "same mesh" : "another mesh");
        },
        30);
    child_done.store(1);
    child_done.notify_one();
    holder.join();
    CHECK(child == "same mesh");
}
