#include "pinned_staging.hpp"

#include "core/parallel.hpp"

#include <algorithm>
#include <cstring>

namespace voxmesh::detail::cl_engine {
namespace {

// memcpy on up to `threads` threads, each at least 1 MiB.
void parallel_copy(void* dst, const void* src, std::size_t bytes, unsigned threads) {
    const std::size_t parts = std::clamp<std::size_t>(bytes >> 20, 1, std::max(threads, 1u));
    run_workers(static_cast<unsigned>(parts), [&](unsigned w) {
        const auto [begin, end] = share_of(bytes, w, static_cast<unsigned>(parts));
        std::memcpy(static_cast<unsigned char*>(dst) + begin, static_cast<const unsigned char*>(src) + begin,
                    end - begin);
    });
}

}  // namespace

PinnedStaging::PinnedStaging(const cl::Context& context, const cl::CommandQueue& queue, std::size_t block_bytes)
    : queue_(queue), block_bytes_(block_bytes) {
    for (int b = 0; b < 2; ++b) {
        block_[b] = cl::Buffer(context, CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR, block_bytes_);
        // Mapped once for good: the pointer is pinned host memory the copies read and write.
        host_[b] = static_cast<unsigned char*>(
            queue_.enqueueMapBuffer(block_[b], CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, block_bytes_));
    }
}

PinnedStaging::~PinnedStaging() {
    try {
        wait_idle();
        for (int b = 0; b < 2; ++b)
            if (host_[b] != nullptr) queue_.enqueueUnmapMemObject(block_[b], host_[b]);
        queue_.finish();
    } catch (const cl::Error&) {
    }
}

void PinnedStaging::wait_idle() {
    for (cl::Event& e : busy_)
        if (e() != nullptr) {
            e.wait();
            e = cl::Event();
        }
}

void PinnedStaging::upload(const cl::Buffer& dst, std::size_t offset, const void* src, std::size_t bytes,
                           unsigned threads, EventLog& log) {
    const auto* from = static_cast<const unsigned char*>(src);
    for (std::size_t done = 0, i = 0; done < bytes; ++i) {
        const std::size_t n = std::min(block_bytes_, bytes - done);
        const std::size_t b = i & 1;
        if (busy_[b]() != nullptr) busy_[b].wait();  // the device has read this block's last contents
        parallel_copy(host_[b], from + done, n, threads);
        cl::Event& e = log.add(Pass::Transfer);
        queue_.enqueueWriteBuffer(dst, CL_FALSE, offset + done, n, host_[b], nullptr, &e);
        busy_[b] = e;
        queue_.flush();  // start it while the next block is copied
        done += n;
    }
}

void PinnedStaging::download(const cl::Buffer& src, std::size_t offset, void* dst, std::size_t bytes,
                             unsigned threads, EventLog& log) {
    if (bytes == 0) return;
    wait_idle();
    auto* to = static_cast<unsigned char*>(dst);
    const auto read = [&](std::size_t at, std::size_t b) {
        const std::size_t n = std::min(block_bytes_, bytes - at);
        cl::Event& e = log.add(Pass::Transfer);
        queue_.enqueueReadBuffer(src, CL_FALSE, offset + at, n, host_[b], nullptr, &e);
        busy_[b] = e;
        queue_.flush();
    };
    read(0, 0);
    for (std::size_t done = 0, i = 0; done < bytes; ++i) {
        const std::size_t n = std::min(block_bytes_, bytes - done);
        const std::size_t b = i & 1;
        if (done + n < bytes) read(done + n, b ^ 1);  // the next block comes in while this one goes out
        busy_[b].wait();
        busy_[b] = cl::Event();
        parallel_copy(to + done, host_[b], n, threads);
        done += n;
    }
}

}  // namespace voxmesh::detail::cl_engine
