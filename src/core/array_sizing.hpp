// Sizing result arrays (the mesh's, the list queries') that are about to be overwritten in
// full, on several threads. A std::vector's resize writes zeros on one thread, and for new
// storage the kernel zeroes every fresh page first, on that thread, as it faults in: most of
// what sizing costs. Where more threads would run than there are arrays, every thread first
// faults in an equal share of the new pages (populate_for_writing), and the resizes then
// write into pages already there. On this 2-core VM one thread faults in and zeroes 240 MB
// in about 33 ms, two threads populating it take 14 ms and a resize of the resident pages
// 9 ms (bench/NOTES.md, thirty-seventh session); with as many threads as arrays the two
// passes over memory lose to one.
#pragma once

#include "huge_pages.hpp"

#include <algorithm>
#include <cstddef>
#include <functional>
#include <vector>

namespace voxmesh::detail {

class ArraySizing {
public:
    // `array` to get n elements when run() runs; its contents will be overwritten, so storage
    // too small is replaced (now) without copying them. Throws std::bad_alloc when it cannot be.
    template <class T>
    void add(std::vector<T>& array, std::size_t n) {
        if (n > array.capacity()) {
            replaced_ = true;
            array.clear();  // reserve then copies nothing
            reserve_huge(array, n);
            // Only pages not yet in memory are worth faulting in first: the heap often hands
            // out memory it had (populating that only walks it: +1 ms on 40 MB), a new mapping
            // none. Its middle page tells which (the first holds the heap's own header).
            char* data = reinterpret_cast<char*>(array.data());
            if (!page_resident(data + sizeof(T) * n / 2)) fresh_.push_back({data, sizeof(T) * n});
        }
        // Nothing to write where a reused array has the size already.
        arrays_.push_back({sizeof(T) * (n - std::min(n, array.size())), [&array, n] { array.resize(n); }});
    }

    // Sizes the arrays on up to `threads` threads (0: all cores), no more than the cores.
    void run(unsigned threads);

    // Whether some array's storage was too small and has been replaced.
    bool replaced() const { return replaced_; }

private:
    struct Resize {
        std::size_t bytes;  // what it writes
        std::function<void()> resize;
    };
    std::vector<Resize> arrays_;
    std::vector<ByteRange> fresh_;
    bool replaced_ = false;
};

}  // namespace voxmesh::detail
