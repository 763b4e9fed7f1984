// Fresh output pages shared out among workers (src/core/huge_pages.hpp): every worker's share
// of the new arrays, and the prefault itself, which must leave contents alone.
#include <catch2/catch.hpp>

#include "core/huge_pages.hpp"

#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

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
