// voxmesh-cl-bandwidth: how fast host memory reaches each OpenCL GPU or accelerator, from
// pageable memory (what enqueueWriteBuffer gets from a std::vector) and from pinned memory
// (a mapped CL_MEM_ALLOC_HOST_PTR buffer), beside the host's own memcpy on 1 and N threads.
// It is why the engine copies through pinned blocks (src/cl/pinned_staging.hpp): on an H100
// host pageable copies ran at 10-14 GB/s and pinned ones at 55 GB/s. Best of 5, GB/s.
#include <CL/opencl.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

template <class F>
double best_gbs(std::size_t bytes, F&& f) {
    double best = 1e30;
    for (int i = 0; i < 5; ++i) {
        const auto t0 = Clock::now();
        f();
        best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count());
    }
    return static_cast<double>(bytes) / best / 1e9;
}

void threaded_copy(unsigned char* dst, const unsigned char* src, std::size_t bytes, unsigned threads) {
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t)
        pool.emplace_back([=] {
            const std::size_t a = bytes * t / threads, b = bytes * (t + 1) / threads;
            std::memcpy(dst + a, src + a, b - a);
        });
    for (auto& t : pool) t.join();
}

void measure(const cl::Device& device) {
    std::printf("%s\n", device.getInfo<CL_DEVICE_NAME>().c_str());
    const cl::Context context(device);
    cl::CommandQueue queue(context, device);
    const unsigned threads = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
    for (std::size_t mib : {8, 64, 512}) {
        const std::size_t n = mib << 20;
        if (n > device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>()) continue;
        std::vector<unsigned char> pageable(n, 1);
        cl::Buffer on_device(context, CL_MEM_READ_WRITE, n);
        cl::Buffer pinned_buffer(context, CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR, n);
        auto* pinned = static_cast<unsigned char*>(
            queue.enqueueMapBuffer(pinned_buffer, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, n));
        std::memset(pinned, 2, n);
        const double up = best_gbs(n, [&] { queue.enqueueWriteBuffer(on_device, CL_TRUE, 0, n, pageable.data()); });
        const double down = best_gbs(n, [&] { queue.enqueueReadBuffer(on_device, CL_TRUE, 0, n, pageable.data()); });
        const double pin_up = best_gbs(n, [&] { queue.enqueueWriteBuffer(on_device, CL_TRUE, 0, n, pinned); });
        const double pin_down = best_gbs(n, [&] { queue.enqueueReadBuffer(on_device, CL_TRUE, 0, n, pinned); });
        const double copy1 = best_gbs(n, [&] { threaded_copy(pinned, pageable.data(), n, 1); });
        const double copyn = best_gbs(n, [&] { threaded_copy(pinned, pageable.data(), n, threads); });
        queue.enqueueUnmapMemObject(pinned_buffer, pinned);
        queue.finish();
        std::printf("  %4zu MiB: pageable up %5.1f down %5.1f | pinned up %5.1f down %5.1f | memcpy 1 thread %5.1f, %u "
                    "threads %5.1f GB/s\n",
                    mib, up, down, pin_up, pin_down, copy1, threads, copyn);
    }
}

}  // namespace

int main() {
    try {
        std::vector<cl::Platform> platforms;
        cl::Platform::get(&platforms);
        int found = 0;
        for (const auto& platform : platforms) {
            std::vector<cl::Device> devices;
            platform.getDevices(CL_DEVICE_TYPE_GPU | CL_DEVICE_TYPE_ACCELERATOR, &devices);
            for (const auto& d : devices) {
                measure(d);
                ++found;
            }
        }
        if (found == 0) std::printf("no OpenCL GPU or accelerator (CPU devices share host memory: nothing to copy)\n");
        return 0;
    } catch (const cl::Error& e) {
        std::fprintf(stderr, "voxmesh-cl-bandwidth: OpenCL error in %s (%d)\n", e.what(), e.err());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "voxmesh-cl-bandwidth: %s\n", e.what());
    }
    return 1;
}
