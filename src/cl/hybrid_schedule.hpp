// How Hybrid shares a volume's z-chunks between the CPU worker and the OpenCL devices.
//
// The chunks not taken yet are a range [lo, hi). Devices take one chunk at a time from the
// front; the CPU worker, which meshes a run of chunks with all its threads at once, takes
// runs from the back. The two estimates below keep the slower side from holding up the
// end of a pass: a device whose copies cost more than the CPU's whole remaining work takes
// no further chunk, and once the CPU worker has meshed its own pieces it takes over a
// device's counted pieces while that is quicker than waiting for the device.
//
// Times are seconds per chunk measured in this call; 0 means not measured yet.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace voxmesh::detail {

// How many of the `remaining` chunks the CPU worker takes next: its share of the combined
// throughput, or a quarter while the rates are unknown (so that a fast device is not left
// idle behind one long CPU run). At least one.
inline std::size_t hybrid_cpu_run(std::size_t remaining, double cpu_chunk_s, double device_chunks_per_s) {
    if (remaining == 0) return 0;
    double share = 0.25;
    if (cpu_chunk_s > 0 && device_chunks_per_s > 0) {
        const double cpu_rate = 1.0 / cpu_chunk_s;
        share = cpu_rate / (cpu_rate + device_chunks_per_s);
    } else if (device_chunks_per_s <= 0 && cpu_chunk_s > 0) {
        share = 0.5;  // the devices have not finished a chunk in the CPU's whole first run
    }
    const auto n = static_cast<std::size_t>(std::ceil(share * static_cast<double>(remaining)));
    return std::clamp<std::size_t>(n, 1, remaining);
}

// Whether a device takes one more chunk: only if it would be done with it no later than the
// CPU worker would be done with everything left (`remaining` chunks, this one included)
// after the `cpu_busy_s` its current run still needs.
inline bool hybrid_device_takes(double device_chunk_s, double cpu_chunk_s, double cpu_busy_s, std::size_t remaining) {
    if (device_chunk_s <= 0 || cpu_chunk_s <= 0) return true;
    return device_chunk_s <= std::max(0.0, cpu_busy_s) + static_cast<double>(remaining) * cpu_chunk_s;
}

// Whether the CPU worker, done with its own pieces, meshes one of a device's counted pieces
// itself (counting it again): only if that is quicker than the device working through the
// `device_pieces_left` it has not started.
inline bool hybrid_cpu_takes_over(double cpu_piece_s, double device_piece_s, std::size_t device_pieces_left) {
    if (cpu_piece_s <= 0 || device_piece_s <= 0 || device_pieces_left == 0) return false;
    return cpu_piece_s < device_piece_s * static_cast<double>(device_pieces_left);
}

}  // namespace voxmesh::detail
