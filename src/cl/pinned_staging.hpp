// Copies between the caller's (pageable) memory and a discrete device through two pinned
// blocks. A copy from pageable memory runs at about a fifth of the bus's speed (the driver
// copies it through a pinned buffer of its own, one block at a time, on one thread; an H100:
// 10-14 GB/s against 55 GB/s pinned); here the host copies into one block on several
// threads while the device reads the other, so both run at once.
#pragma once

#include "cl_runtime.hpp"

#include <cstddef>

namespace voxmesh::detail::cl_engine {

class PinnedStaging {
public:
    PinnedStaging(const cl::Context& context, const cl::CommandQueue& queue, std::size_t block_bytes);
    ~PinnedStaging();
    PinnedStaging(const PinnedStaging&) = delete;
    PinnedStaging& operator=(const PinnedStaging&) = delete;

    // bytes from src into dst at offset, on `threads` host threads. Returns once src may
    // change; the device may still be copying, but the queue runs later commands after it.
    void upload(const cl::Buffer& dst, std::size_t offset, const void* src, std::size_t bytes, unsigned threads,
                EventLog& log);
    std::size_t block_bytes() const { return block_bytes_; }
    // bytes from src at offset into dst. Returns when dst holds them.
    void download(const cl::Buffer& src, std::size_t offset, void* dst, std::size_t bytes, unsigned threads,
                  EventLog& log);

private:
    void wait_idle();

    cl::CommandQueue queue_;
    std::size_t block_bytes_;
    cl::Buffer block_[2];
    unsigned char* host_[2] = {nullptr, nullptr};
    cl::Event busy_[2];  // the device's last copy from or into each block
};

}  // namespace voxmesh::detail::cl_engine
