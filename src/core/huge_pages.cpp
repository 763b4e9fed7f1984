#include "huge_pages.hpp"

#include "env_word.hpp"
#include "parallel.hpp"  // share_of

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <optional>
#include <string>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace voxmesh::detail {

namespace {
constexpr std::size_t kHuge = std::size_t{2} << 20;  // a transparent huge page on x86-64 and arm64
}  // namespace

bool huge_pages_advised() {
    static const bool advised = [] {
        const std::optional<std::string> value = env_word("VOXMESH_HUGE_PAGES");
        if (!value || *value == "on" || *value == "1") return true;
        if (*value == "off" || *value == "0") return false;
        std::fprintf(stderr, "voxmesh: warning: VOXMESH_HUGE_PAGES='%s' is not 'on', 'off', '1' or '0'; ignored\n",
                     std::getenv("VOXMESH_HUGE_PAGES"));
        return true;
    }();
    return advised;
}

void advise_huge_pages(const void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (!huge_pages_advised()) return;
    const auto begin = (reinterpret_cast<std::uintptr_t>(data) + kHuge - 1) & ~(kHuge - 1);
    const auto end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHuge - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // advice: errors ignored
#else
    (void)data;
    (void)bytes;
#endif
}

bool populate_for_writing(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
    // Whole pages only: the partial pages at the ends may hold another allocation's bytes, and
    // the first write faults them in anyway.
    const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
    const auto begin = (reinterpret_cast<std::uintptr_t>(data) + page - 1) & ~(page - 1);
    const auto end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(page - 1);
    if (end <= begin) return true;
    return madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE) == 0;
#else
    (void)data;
    (void)bytes;
    return false;
#endif
}

bool page_resident(const void* p) {
#if defined(__linux__)
    const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
    unsigned char in_memory = 0;
    void* start = reinterpret_cast<void*>(reinterpret_cast<std::uintptr_t>(p) & ~(page - 1));
    return mincore(start, page, &in_memory) == 0 && (in_memory & 1);
#else
    (void)p;
    return false;
#endif
}

std::vector<ByteRange> worker_share(const std::vector<ByteRange>& ranges, unsigned workers, unsigned w) {
    std::size_t total = 0;
    for (const ByteRange& r : ranges) total += r.bytes;
    const auto [from, to] = share_of(total, w, workers);
    std::vector<ByteRange> share;
    std::size_t start = 0;  // of range r, laid end to end
    for (const ByteRange& r : ranges) {
        const std::size_t end = start + r.bytes;
        // A cut inside r, moved to the next 2 MiB address (or r's end); r's own ends stay.
        const auto align = [&](std::size_t at) {
            if (at <= start || at >= end) return std::clamp(at, start, end) - start;
            const auto address = reinterpret_cast<std::uintptr_t>(r.data) + (at - start);
            return std::min(r.bytes, at - start + static_cast<std::size_t>((kHuge - address % kHuge) % kHuge));
        };
        const std::size_t lo = align(from), hi = align(to);
        if (hi > lo) share.push_back({r.data + lo, hi - lo});
        start = end;
    }
    return share;
}

std::shared_ptr<void> allocate_zeroed(std::size_t bytes, bool huge_pages) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr std::size_t kWorthIt = 2 * kHuge;
    if (bytes >= kWorthIt && bytes <= SIZE_MAX - kHuge) {
        // A private anonymous mapping, one huge page longer so its start can be aligned. Mapped
        // even without the advice: calloc may take a block this large from a heap and zero it
        // all, making every page resident however little of it is used.
        const std::size_t mapped = bytes + kHuge;
        void* raw = mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (raw == MAP_FAILED) throw std::bad_alloc();
        const auto start = (reinterpret_cast<std::uintptr_t>(raw) + kHuge - 1) & ~std::uintptr_t{kHuge - 1};
        void* data = reinterpret_cast<void*>(start);
        if (huge_pages) advise_huge_pages(data, bytes);
        return std::shared_ptr<void>(data, [raw, mapped](void*) { munmap(raw, mapped); });
    }
#else
    (void)huge_pages;
#endif
    void* block = std::calloc(bytes == 0 ? 1 : bytes, 1);
    if (!block) throw std::bad_alloc();
    return std::shared_ptr<void>(block, std::free);
}

}  // namespace voxmesh::detail
