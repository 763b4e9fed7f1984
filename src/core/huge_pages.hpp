// Large arrays that are written once right after they are allocated (the mesh, per-row
// metadata) pay one page fault per 4 KiB on first touch, and on a VM a
// fault costs microseconds: 40 MB cost ~30 ms of faults here. Asking for transparent huge
// pages on such an array (Linux, THP in "madvise" mode, the common default) cuts that to a
// fault per 2 MiB. Only advice: where THP is off or unsupported nothing changes.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

namespace voxmesh::detail {

// Whether the library advises huge pages: yes unless VOXMESH_HUGE_PAGES is "off" or "0" (read
// once; another value than on/1/off/0 is named on stderr and ignored). Off is for machines where
// a fresh huge page costs more than 512 small ones: a VM whose host takes back the guest's free
// 2 MiB blocks (free page reporting) faults each in again on the host, 4-5 ms per 2 MiB in a
// process's first calls on the project's machine (bench/NOTES.md, fifty-third session).
bool huge_pages_advised();

// Advises huge pages for the 2 MiB-aligned part of [data, data + bytes); smaller ranges are
// left alone, and so is everything where huge_pages_advised() is false.
void advise_huge_pages(const void* data, std::size_t bytes);

// Faults in the whole pages of [data, data + bytes) for writing now (Linux's
// MADV_POPULATE_WRITE, 5.14 and later): the kernel zeroes each fresh page there, so threads
// that each populate a part share that work. Contents are unchanged. False where the kernel or
// platform cannot (nothing happened: the first writes fault the pages in, as without it).
bool populate_for_writing(void* data, std::size_t bytes);

// Whether the page holding p is in memory (Linux's mincore; false where unknown). Storage a
// heap hands out again is usually in memory already, and fresh mappings are not.
bool page_resident(const void* p);

struct ByteRange {
    char* data;
    std::size_t bytes;
};

// Worker w's share of `ranges` laid end to end: one of `workers` about equal shares, each cut
// moved forward to the next 2 MiB address inside its range, so that no huge page is faulted
// in by two workers. The shares cover every range exactly once, in order.
std::vector<ByteRange> worker_share(const std::vector<ByteRange>& ranges, unsigned workers, unsigned w);

// `bytes` of zeroed memory, advised for huge pages when large and `huge_pages` (fresh pages
// from the kernel are already zero, so nothing is written here: pages are faulted in by their
// first user). Throws std::bad_alloc when the memory cannot be had.
std::shared_ptr<void> allocate_zeroed(std::size_t bytes, bool huge_pages = true);

// v.reserve(n), with new storage advised before anything touches it; then resize or assign.
template <class T>
void reserve_huge(std::vector<T>& v, std::size_t n) {
    if (n <= v.capacity()) return;
    v.reserve(n);
    advise_huge_pages(v.data(), v.capacity() * sizeof(T));
}

}  // namespace voxmesh::detail
