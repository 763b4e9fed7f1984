// Vertex normals queued and normalised in batches. Normalising one vertex at a time puts a
// square root and a divide (≈ 35 cycles of latency) in every vertex's chain: in a profile
// of the generator (sphere u8 512³) 14 % of its samples waited there. In batches they run
// four lanes at a time, off the vertex's path. Same operations per lane as
// normalise_normal, so the same bits.
#pragma once

#include <cstddef>
#include <cstdint>

namespace voxmesh::detail {

// Normalises normals v < count, given as x[v], y[v], z[v] with their flat-gradient fallback
// flat[v] (see normalise_normal), into out[3v..3v+2].
void normalise_normals(const double* x, const double* y, const double* z, const std::uint8_t* flat,
                       std::size_t count, float* out);

class NormalBatch {
public:
    // The normals pushed next go to out, out + 3, ... (whatever is queued is written first).
    void start(float* out) {
        flush();
        out_ = out;
    }

    void push(const double n[3], unsigned flat) {
        x_[count_] = n[0];
        y_[count_] = n[1];
        z_[count_] = n[2];
        flat_[count_] = static_cast<std::uint8_t>(flat);
        if (++count_ == kSize) flush();
    }

    void flush() {
        if (count_ == 0) return;
        normalise_normals(x_, y_, z_, flat_, count_, out_);
        out_ += 3 * count_;
        count_ = 0;
    }

private:
    static constexpr std::size_t kSize = 128;
    float* out_ = nullptr;
    std::size_t count_ = 0;
    double x_[kSize], y_[kSize], z_[kSize];
    std::uint8_t flat_[kSize];
};

}  // namespace voxmesh::detail
