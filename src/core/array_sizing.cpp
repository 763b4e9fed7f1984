#include "array_sizing.hpp"

#include "parallel.hpp"

#include <algorithm>

namespace voxmesh::detail {

void ArraySizing::run(unsigned threads) {
    std::size_t total = 0, fresh_total = 0;
    for (const Resize& array : arrays_) total += array.bytes;
    for (const ByteRange& range : fresh_) fresh_total += range.bytes;
    // Below this, waking workers costs about what they would save.
    constexpr std::size_t kWorthThreads = std::size_t{8} << 20;
    const unsigned cores = running_threads(threads);
    if (fresh_total >= kWorthThreads && cores > arrays_.size()) {
        run_workers(cores, [&](unsigned w) {
            for (const ByteRange& share : worker_share(fresh_, cores, w)) populate_for_writing(share.data, share.bytes);
        });
    }
    // The resizes, largest first, each on the least loaded worker.
    std::sort(arrays_.begin(), arrays_.end(), [](const Resize& a, const Resize& b) { return a.bytes > b.bytes; });
    const unsigned workers = total < kWorthThreads ? 1u : std::min(cores, static_cast<unsigned>(arrays_.size()));
    std::vector<std::size_t> load(workers, 0);
    std::vector<unsigned> owner(arrays_.size());
    for (std::size_t i = 0; i < arrays_.size(); ++i) {
        const auto least = std::min_element(load.begin(), load.end()) - load.begin();
        owner[i] = static_cast<unsigned>(least);
        load[least] += arrays_[i].bytes;
    }
    run_workers(workers, [&](unsigned w) {
        for (std::size_t i = 0; i < arrays_.size(); ++i)
            if (owner[i] == w) arrays_[i].resize();
    });
}

}  // namespace voxmesh::detail
