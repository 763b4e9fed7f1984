// Per-call scratch memory that is reused from one extract to the next: the CPU engine's row
// metadata, the inside bits classify keeps, and the generators' vertex-id tables.
//
// Fresh memory costs a page fault per 4 KiB on first touch, about 1.3 µs each on the 2-core
// VM. Allocated per call, these arrays took 2245 faults per call on sphere f32 512³ (2
// threads) and 577 at 256³, 6-9 % of the call's CPU time; and glibc gave the calling
// thread's freed blocks back to the kernel but kept the workers', so the caller paid more of
// them and the other thread waited for it at the end of the pass. A block let go of is kept
// here for the next call that fits in it; the pool keeps at most kMaxKeptBlocks blocks and
// kMaxKeptBytes bytes (the oldest go first), and a block larger than that is never kept.
// So that one large volume does not leave its blocks held for good, a block is handed out
// only for a request at least a quarter of its size (below 1 MiB, any smaller one), and a
// kept block that kScratchIdleRequests requests went by without is freed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <new>
#include <type_traits>

namespace voxmesh::detail {

// Whether a large block is advised for transparent huge pages: for arrays read at scattered
// rows (the id tables, a TLB miss per row with 4 KiB pages), not for arrays a call may use
// only the start of, where huge pages make all of it resident.
enum class Pages { Small, Huge };

// At least `bytes` bytes (malloc's alignment), uninitialised (a kept block holds what its last
// user wrote); back to the pool when the last owner lets go. Throws std::bad_alloc.
std::shared_ptr<void> acquire_scratch(std::size_t bytes, Pages pages);

// Requests after which a kept block nobody took is freed: about 35 calls on 2 threads (each
// takes the row metadata, the kept bits for 16- to 64-bit samples and an id table per worker).
constexpr std::size_t kScratchIdleRequests = 128;

// What the pool keeps now (for tests).
struct ScratchKept {
    std::size_t blocks = 0, bytes = 0;
};
ScratchKept scratch_kept();

// Frees every kept block.
void release_scratch();

// Test hook: runs f while holding the pool's lock, as a thread inside acquire_scratch would.
void with_scratch_pool_locked_for_testing(const std::function<void()>& f);

// n T's of scratch (acquire_scratch): uninitialised, so whoever fills it writes every field it
// reads. T must need no constructor beyond its bytes and no destructor.
template <class T>
class ScratchArray {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

public:
    ScratchArray() = default;
    ScratchArray(std::size_t n, Pages pages)
        : storage_(acquire_scratch(n <= SIZE_MAX / sizeof(T) ? n * sizeof(T) : throw std::bad_alloc(), pages)),
          data_(static_cast<T*>(storage_.get())),
          size_(n) {}

    T* data() const { return data_; }
    std::size_t size() const { return size_; }
    T& operator[](std::size_t i) const { return data_[i]; }

private:
    std::shared_ptr<void> storage_;
    T* data_ = nullptr;
    std::size_t size_ = 0;
};

}  // namespace voxmesh::detail
