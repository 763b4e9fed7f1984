#include "scratch.hpp"

#include "huge_pages.hpp"

#include <algorithm>
#include <deque>
#include <functional>
#include <mutex>

#if defined(__unix__) || defined(__APPLE__)
#include <pthread.h>
#endif

namespace voxmesh::detail {
namespace {

// Room for what a few extracts on a many-core machine let go of (two classify arrays per
// chunk, an id table per worker), and for 1024³ float volumes' kept bits (128 MB).
constexpr std::size_t kMaxKeptBlocks = 64;
constexpr std::size_t kMaxKeptBytes = std::size_t{512} << 20;
// A request takes a kept block at most this many times its size, or any block up to
// kAlwaysFits: a small volume's call does not hold on to a large one's blocks.
constexpr std::size_t kMaxOversize = 4;
constexpr std::size_t kAlwaysFits = std::size_t{1} << 20;

struct Block {
    std::shared_ptr<void> memory;  // allocate_zeroed
    std::size_t bytes = 0;
    Pages pages = Pages::Small;
    std::uint64_t given_back = 0;  // the request count when it came back
};

bool fits(const Block& block, std::size_t bytes, Pages pages) {
    return block.pages == pages && block.bytes >= bytes &&
           (block.bytes <= kAlwaysFits || block.bytes / kMaxOversize <= bytes);
}

class ScratchPool {
public:
    std::shared_ptr<void> acquire(std::size_t bytes, Pages pages) {
        bytes = std::max<std::size_t>(bytes, 1);
        Block block;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            ++requests_;
            drop_idle();
            // The smallest kept block of the kind that fits, so a small request does not take a
            // large one.
            auto best = kept_.end();
            for (auto it = kept_.begin(); it != kept_.end(); ++it)
                if (fits(*it, bytes, pages) && (best == kept_.end() || it->bytes < best->bytes)) best = it;
            if (best != kept_.end()) {
                block = std::move(*best);
                kept_bytes_ -= block.bytes;
                kept_.erase(best);
            }
        }
        if (!block.memory) block = Block{allocate_zeroed(bytes, pages == Pages::Huge), bytes, pages};
        void* data = block.memory.get();
        return std::shared_ptr<void>(data, [this, held = std::make_shared<Block>(std::move(block))](void*) {
            give_back(std::move(*held));
        });
    }

    ScratchKept kept() {
        std::lock_guard<std::mutex> lock(mutex_);
        return {kept_.size(), kept_bytes_};
    }

    // Runs f with the pool's lock held (a test standing for a thread caught inside acquire()).
    void while_locked(const std::function<void()>& f) {
        std::lock_guard<std::mutex> lock(mutex_);
        f();
    }

    // fork(): the lock is held across it, so that the child's copy of the lists is whole and its
    // lock free. Without that, a fork while another thread was inside acquire() or give_back()
    // left the child's first extract waiting for ever. Nothing under the lock forks or waits.
    void lock_for_fork() { mutex_.lock(); }
    void unlock_after_fork() { mutex_.unlock(); }

    void release() {
        std::deque<Block> freed;
        std::lock_guard<std::mutex> lock(mutex_);
        freed.swap(kept_);
        kept_bytes_ = 0;
    }

private:
    // Called from a shared_ptr's deleter, so it must not throw: a block that cannot be kept
    // is freed.
    void give_back(Block block) noexcept {
        if (block.bytes > kMaxKeptBytes) return;  // freed here
        std::lock_guard<std::mutex> lock(mutex_);
        block.given_back = requests_;
        try {
            kept_.push_back(std::move(block));
        } catch (...) {
            return;  // no room for the entry: the block is freed
        }
        kept_bytes_ += kept_.back().bytes;
        while (kept_.size() > kMaxKeptBlocks || kept_bytes_ > kMaxKeptBytes) {
            kept_bytes_ -= kept_.front().bytes;
            kept_.pop_front();  // freed (unmapped) under the lock: rare, and it allocates nothing
        }
    }

    // Frees the kept blocks that kScratchIdleRequests requests went by without (under the lock).
    void drop_idle() {
        for (auto it = kept_.begin(); it != kept_.end();) {
            if (requests_ - it->given_back > kScratchIdleRequests) {
                kept_bytes_ -= it->bytes;
                it = kept_.erase(it);
            } else {
                ++it;
            }
        }
    }

    std::mutex mutex_;
    std::deque<Block> kept_;  // oldest first
    std::size_t kept_bytes_ = 0;
    std::uint64_t requests_ = 0;  // acquire() calls so far
};

ScratchPool& pool();

ScratchPool* make_pool() {
    auto* created = new ScratchPool;
#if defined(__unix__) || defined(__APPLE__)
    pthread_atfork(+[] { pool().lock_for_fork(); }, +[] { pool().unlock_after_fork(); },
                   +[] { pool().unlock_after_fork(); });
#endif
    return created;
}

// Never destroyed: blocks may be let go of by static objects' destructors at exit.
ScratchPool& pool() {
    static ScratchPool* instance = make_pool();
    return *instance;
}

}  // namespace

std::shared_ptr<void> acquire_scratch(std::size_t bytes, Pages pages) { return pool().acquire(bytes, pages); }
ScratchKept scratch_kept() { return pool().kept(); }
void release_scratch() { pool().release(); }
void with_scratch_pool_locked_for_testing(const std::function<void()>& f) { pool().while_locked(f); }

}  // namespace voxmesh::detail
