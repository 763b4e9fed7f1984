// Fresh output pages shared out among workers (src/core/huge_pages.hpp, array_sizing.hpp):
// every worker's share of the new arrays, the prefault itself, which must leave contents
// alone, and the residency test that tells fresh storage from storage a heap had.
#include <catch2/catch.hpp>

#include "core/array_sizing.hpp"
#include "core/huge_pages.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

using voxmesh::detail::ByteRange;
using voxmesh::detail::populate_for_writing;
using voxmesh::detail::worker_share;

namespace {

constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;

bool on_huge_boundary(const char* p) { return reinterpret_cast<std::uintptr_t>(p) % kHuge == 0; }

}  // namespace

TEST_CASE("worker shares cover the fresh ranges exactly once, cut on 2 MiB addresses", "[core][pages]") {
    // Real memory, so that the ranges' addresses are real: 24 MiB, ranges at odd offsets in it.
    std::vector<char> memory(std::size_t{24} << 20);
    std::mt19937 random(7);
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<ByteRange> ranges;
        std::size_t at = random() % 4096;
        const unsigned count = 1 + random() % 3;
        for (unsigned r = 0; r < count; ++r) {
            const std::size_t left = memory.size() - at;
            const std::size_t bytes = random() % 4 == 0 ? random() % 5000 : random() % (left / (count - r) + 1);
            ranges.push_back({memory.data() + at, bytes});
            at += bytes + random() % 100;
        }
        const unsigned workers = 1 + random() % 17;
        INFO("trial " << trial << ", " << count << " ranges, " << workers << " workers");
        // Walk every range once, in order, through the workers' shares in worker order.
        std::size_t range = 0, offset = 0;
        for (unsigned w = 0; w < workers; ++w) {
            const std::vector<ByteRange> share = worker_share(ranges, workers, w);
            for (std::size_t s = 0; s < share.size(); ++s) {
                REQUIRE(share[s].bytes > 0);
                while (range < ranges.size() && offset == ranges[range].bytes) range++, offset = 0;
                REQUIRE(range < ranges.size());
                REQUIRE(share[s].data == ranges[range].data + offset);
                // A share starts at its range's start or on a huge page, and ends at its
                // range's end or on one.
                CHECK((offset == 0 || on_huge_boundary(share[s].data)));
                offset += share[s].bytes;
                REQUIRE(offset <= ranges[range].bytes);
                CHECK((offset == ranges[range].bytes || on_huge_boundary(ranges[range].data + offset)));
            }
        }
        while (range < ranges.size() && offset == ranges[range].bytes) range++, offset = 0;
        CHECK(range == ranges.size());
    }
}

TEST_CASE("worker shares split large ranges about evenly", "[core][pages]") {
    std::vector<char> memory(std::size_t{64} << 20);
    const std::vector<ByteRange> ranges{{memory.data() + 100, std::size_t{40} << 20},
                                        {memory.data() + (std::size_t{41} << 20), std::size_t{20} << 20}};
    for (unsigned workers : {2u, 3u, 8u, 16u}) {
        std::size_t most = 0, least = SIZE_MAX;
        for (unsigned w = 0; w < workers; ++w) {
            std::size_t bytes = 0;
            for (const ByteRange& s : worker_share(ranges, workers, w)) bytes += s.bytes;
            most = std::max(most, bytes);
            least = std::min(least, bytes);
        }
        INFO(workers << " workers");
        // Each cut moves at most one huge page (and a range's end can leave a worker less).
        CHECK(most <= (std::size_t{60} << 20) / workers + kHuge);
        CHECK(least + 2 * kHuge >= (std::size_t{60} << 20) / workers);
    }
}

TEST_CASE("populating pages for writing leaves their contents alone", "[core][pages]") {
    std::vector<unsigned char> bytes((std::size_t{5} << 20) + 123);
    for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<unsigned char>(i * 31 + 7);
    const std::vector<unsigned char> before = bytes;
    populate_for_writing(bytes.data() + 1, bytes.size() - 2);  // unaligned ends: whole pages only
    populate_for_writing(bytes.data(), 0);
    populate_for_writing(bytes.data() + 10, 100);  // within one page: nothing to do
    CHECK(bytes == before);
}

#if defined(__linux__)
TEST_CASE("a page written is resident, a fresh mapping's is not", "[core][pages]") {
    std::vector<unsigned char> written(1 << 20, 1);
    CHECK(voxmesh::detail::page_resident(written.data() + written.size() / 2));
    // A private anonymous mapping's pages come on first touch; MAP_NORESERVE keeps it light.
    const std::size_t bytes = std::size_t{8} << 20;
    void* fresh = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    REQUIRE(fresh != MAP_FAILED);
    char* middle = static_cast<char*>(fresh) + bytes / 2;
    CHECK_FALSE(voxmesh::detail::page_resident(middle));
    if (populate_for_writing(fresh, bytes)) CHECK(voxmesh::detail::page_resident(middle));
    munmap(fresh, bytes);
}

namespace {

// The VmFlags line of the mapping that holds p in /proc/self/smaps ("hg": huge pages advised);
// empty where there is none.
std::string vm_flags(const void* p) {
    const auto at = reinterpret_cast<std::uintptr_t>(p);
    std::ifstream smaps("/proc/self/smaps");
    bool inside = false;
    for (std::string line; std::getline(smaps, line);) {
        unsigned long long begin = 0, end = 0;
        char dash = 0;
        std::istringstream words(line);
        if (words >> std::hex >> begin >> dash >> end && dash == '-' && line.find(':') > line.find(' '))
            inside = begin <= at && at < end;
        else if (inside && line.rfind("VmFlags:", 0) == 0)
            return line + " ";
    }
    return {};
}

}  // namespace

// The ctest voxmesh_pages_without_huge_pages runs the [pages] tests again with
// VOXMESH_HUGE_PAGES=off (tests/pages.cmake).
TEST_CASE("huge pages are advised unless VOXMESH_HUGE_PAGES is off", "[core][pages]") {
    const char* setting = std::getenv("VOXMESH_HUGE_PAGES");
    if (setting && std::string(setting) != "off") {
        WARN("skipped: VOXMESH_HUGE_PAGES is neither unset nor off");
        return;
    }
    const bool off = setting != nullptr;
    CHECK(voxmesh::detail::huge_pages_advised() == !off);
    const std::shared_ptr<void> block = voxmesh::detail::allocate_zeroed(std::size_t{8} << 20);
    const std::string flags = vm_flags(block.get());
    INFO(flags);
    REQUIRE(flags.rfind("VmFlags:", 0) == 0);
    // madvise(MADV_HUGEPAGE) sets the flag whatever THP's mode, where the kernel has THP at all.
    if (std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled")) CHECK((flags.find(" hg ") != std::string::npos) == !off);
    // Advice only: the memory is the same zeroed memory either way.
    const auto* bytes = static_cast<const unsigned char*>(block.get());
    CHECK(std::all_of(bytes, bytes + (std::size_t{8} << 20), [](unsigned char b) { return b == 0; }));
}
#endif

TEST_CASE("ArraySizing gives every array its size, whatever storage it had", "[core][pages]") {
    const std::size_t large = (std::size_t{9} << 20) / sizeof(float);  // past the threaded sizing's 8 MiB
    for (unsigned threads : {0u, 1u, 2u, 16u}) {
        for (std::size_t n : {std::size_t{0}, std::size_t{1000}, large}) {
            INFO("threads " << threads << ", n " << n);
            std::vector<float> empty, small(10, 5.f), big(large + 7, 6.f);
            std::vector<std::uint32_t> other(3, 9u);
            voxmesh::detail::ArraySizing sizing;
            sizing.add(empty, n);
            sizing.add(small, n);
            sizing.add(big, n);
            sizing.add(other, 2 * n + 1);
            sizing.run(threads);
            CHECK(empty.size() == n);
            CHECK(small.size() == n);
            CHECK(big.size() == n);
            CHECK(other.size() == 2 * n + 1);
            // Elements past an array's old size are value-initialised, as resize makes them.
            CHECK(std::all_of(empty.begin(), empty.end(), [](float v) { return v == 0.f; }));
            if (n > 10) CHECK(std::all_of(small.begin(), small.end(), [](float v) { return v == 0.f; }));
            if (n > 3) CHECK(std::all_of(other.begin() + 3, other.end(), [](std::uint32_t v) { return v == 0u; }));
        }
    }
}

TEST_CASE("ArraySizing says whether it replaced some array's storage", "[core][pages]") {
    std::vector<float> a(100), b;
    b.reserve(50);
    voxmesh::detail::ArraySizing room;
    room.add(a, 80);  // shrinks
    room.add(b, 50);  // grows within its capacity
    room.run(2);
    CHECK_FALSE(room.replaced());
    voxmesh::detail::ArraySizing grows;
    grows.add(a, 80);
    grows.add(b, 51);
    grows.run(2);
    CHECK(grows.replaced());
    CHECK(b.size() == 51);
}
