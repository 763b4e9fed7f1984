// Built-in volumes for tests, demos and the benchmark.
//
// Every field is first evaluated as float "native" values row by row (x fastest), then
// stored as the requested scalar type. Integer types get a linear map of the field's native
// range onto (part of) the type's range, clamped, rounded; their iso is the mapped iso moved
// to the nearest half-integer so that no sample ever equals it. Generation runs on
// worker threads over z-planes; every value depends only on (x, y, z, seed), so the result is
// the same for any thread count.
#include <voxmesh/fields.hpp>

#include "core/out_of_memory.hpp"
#include "core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <type_traits>
#include <vector>

namespace voxmesh {

namespace {

// ---- deterministic randomness ------------------------------------------------------------

std::uint64_t splitmix64(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

// Uniform in [0, 1), the same on every platform (no <random> distributions).
double uniform01(std::uint64_t& state) { return double(splitmix64(state) >> 11) * 0x1.0p-53; }

// A hash of a sample position: triangular noise in (-1, 1), the mean of two uniforms.
inline float hash_noise(std::uint32_t x, std::uint32_t y, std::uint32_t z, std::uint32_t seed) {
    std::uint32_t h = x * 0x8DA6B343u ^ y * 0xD8163841u ^ z * 0xCB1AB31Fu ^ seed * 0x9E3779B9u;
    h ^= h >> 16;
    h *= 0x7FEB352Du;
    h ^= h >> 15;
    h *= 0x846CA68Bu;
    h ^= h >> 16;
    return float(int(h & 0xFFFFu) + int(h >> 16) - 65535) * (1.0f / 65536.0f);
}

// ---- native fields: fill one row of n floats at (y, z) ----------------------------------

struct FieldSpec {
    double iso = 0;         // native iso (inside where value >= iso)
    double lo = 0, hi = 1;  // native range mapped onto the integer types
};

class Generator {
public:
    virtual ~Generator() = default;
    virtual void row(std::size_t y, std::size_t z, float* out) const = 0;
    FieldSpec spec;
};

// Signed distance to a centred sphere of radius 0.4 n, in voxels, positive inside.
class SphereField final : public Generator {
public:
    explicit SphereField(std::size_t n) : n_(n), c_(0.5 * double(n - 1)), r_(0.4 * double(n)) {
        spec.iso = 0;
        spec.lo = -16;  // a band of +-16 voxels around the surface is resolved by integer types
        spec.hi = 16;
    }
    void row(std::size_t y, std::size_t z, float* out) const override {
        const double dy = double(y) - c_, dz = double(z) - c_;
        const double yz = dy * dy + dz * dz;
        for (std::size_t x = 0; x < n_; ++x) {
            const double dx = double(x) - c_;
            out[x] = float(r_ - std::sqrt(dx * dx + yz));
        }
    }

private:
    std::size_t n_;
    double c_, r_;
};

// Schoen's gyroid sin x cos y + sin y cos z + sin z cos x with kPeriods periods across the
// cube: about 10 M triangles at 512^3, like VTK's dense reference case.
class GyroidField final : public Generator {
public:
    static constexpr double kPeriods = 4;
    explicit GyroidField(std::size_t n) : n_(n), s_(n), c_(n) {
        spec.iso = 0;
        spec.lo = -1.5;
        spec.hi = 1.5;
        const double k = 2 * std::numbers::pi * kPeriods / double(n);
        for (std::size_t i = 0; i < n; ++i) {
            // A small phase keeps samples off the exact zeros of the sines.
            const double a = k * (double(i) + 0.25);
            s_[i] = float(std::sin(a));
            c_[i] = float(std::cos(a));
        }
    }
    void row(std::size_t y, std::size_t z, float* out) const override {
        const float sy = s_[y], cy = c_[y], sz = s_[z], cz = c_[z];
        const float syz = sy * cz;
        for (std::size_t x = 0; x < n_; ++x) out[x] = s_[x] * cy + syz + sz * c_[x];
    }

private:
    std::size_t n_;
    std::vector<float> s_, c_;
};

// Metaballs: a sum of compactly supported smooth bumps w (1 - d^2/R^2)^3, placed by the seed.
class BlobsField final : public Generator {
public:
    explicit BlobsField(std::size_t n, std::uint32_t seed) : n_(n) {
        spec.iso = 0.5;
        spec.lo = 0;
        spec.hi = 2;
        std::uint64_t state = 0xB10B5ull ^ (std::uint64_t(seed) << 32) ^ seed;
        const double N = double(n);
        const int count = 12 + int(uniform01(state) * 9);  // 12..20 blobs
        for (int i = 0; i < count; ++i) {
            Blob b;
            b.x = (0.2 + 0.6 * uniform01(state)) * N;
            b.y = (0.2 + 0.6 * uniform01(state)) * N;
            b.z = (0.2 + 0.6 * uniform01(state)) * N;
            b.r = (0.1 + 0.12 * uniform01(state)) * N;
            b.w = 0.8 + 0.6 * uniform01(state);
            blobs_.push_back(b);
        }
    }
    void row(std::size_t y, std::size_t z, float* out) const override {
        std::fill(out, out + n_, 0.0f);
        for (const Blob& b : blobs_) {
            const double dy = double(y) - b.y, dz = double(z) - b.z;
            const double r2 = b.r * b.r, yz = dy * dy + dz * dz;
            if (yz >= r2) continue;
            const double half = std::sqrt(r2 - yz);  // x-span of the bump on this row
            const double lo = std::max(0.0, std::ceil(b.x - half));
            const double hi = std::min(double(n_) - 1, std::floor(b.x + half));
            const double inv = 1.0 / r2;
            for (std::size_t x = std::size_t(lo); double(x) <= hi; ++x) {
                const double dx = double(x) - b.x;
                const double t = 1.0 - (dx * dx + yz) * inv;
                if (t > 0) out[x] += float(b.w * t * t * t);
            }
        }
    }

private:
    struct Blob {
        double x, y, z, r, w;
    };
    std::size_t n_;
    std::vector<Blob> blobs_;
};

// A CT-like head phantom in Hounsfield units: air, skin and soft tissue, a skull shell with
// a foramen at the bottom, brain, two ventricles, a few calcifications, and noise. The
// boundaries are ramps about one voxel wide (partial volume), so surfaces are smooth.
class CtField final : public Generator {
public:
    static constexpr float kAir = -1000, kSoft = 40, kBone = 1200, kBrain = 35, kCsf = 5, kCalc = 700;
    static constexpr float kNoise = 20;  // amplitude of the (triangular) noise, HU

    CtField(std::size_t n, std::uint32_t seed) : n_(n), seed_(seed) {
        spec.iso = 400;  // bone
        spec.lo = -1024;
        spec.hi = 3071;
        const double N = double(n), c = 0.5 * (N - 1);
        auto ell = [&](double cx, double cy, double cz, double a, double b, double e) {
            return Ellipsoid{c + cx * N, c + cy * N, c + cz * N, a * N, b * N, e * N};
        };
        head_ = ell(0, 0, 0, 0.36, 0.44, 0.45);
        skull_out_ = ell(0, 0, 0, 0.335, 0.415, 0.425);
        skull_in_ = ell(0, 0.005, 0.01, 0.305, 0.385, 0.39);
        vent_[0] = ell(-0.06, 0.02, 0.04, 0.04, 0.12, 0.06);
        vent_[1] = ell(0.06, 0.02, 0.04, 0.04, 0.12, 0.06);
        foramen_ = ell(0, 0.05, -0.41, 0.07, 0.08, 0.08);
        std::uint64_t state = 0xC7ull ^ (std::uint64_t(seed) << 32) ^ seed;
        for (auto& s : calc_) {
            s = ell((uniform01(state) - 0.5) * 0.35, (uniform01(state) - 0.5) * 0.45,
                    (uniform01(state) - 0.5) * 0.4, 0, 0, 0);
            s.a = s.b = s.c = (0.008 + 0.012 * uniform01(state)) * N + 1.0;
        }
    }

    void row(std::size_t y, std::size_t z, float* out) const override {
        const double py = double(y), pz = double(z);
        const auto uy = std::uint32_t(y), uz = std::uint32_t(z);
        // Air and noise everywhere, then the head only over the x-span it covers.
        for (std::size_t x = 0; x < n_; ++x) {
            const auto ux = std::uint32_t(x);
            out[x] = kAir + kNoise * hash_noise(ux, uy, uz, seed_);
        }
        std::size_t x0 = 0, x1 = 0;
        if (!head_.span(py, pz, n_, x0, x1)) return;
        std::size_t s0 = 0, s1 = 0, f0 = 0, f1 = 0, b0 = 0, b1 = 0;
        const bool skull = skull_out_.span(py, pz, n_, s0, s1);
        const bool foramen = foramen_.span(py, pz, n_, f0, f1);
        const bool brain_row = skull_in_.span(py, pz, n_, b0, b1);
        for (std::size_t x = x0; x <= x1; ++x) {
            const double px = double(x);
            float v = kAir + (kSoft - kAir) * head_.cover(px, py, pz);
            if (skull && x >= s0 && x <= s1) {
                float bone = skull_out_.cover(px, py, pz);
                if (foramen && x >= f0 && x <= f1) bone *= 1.0f - foramen_.cover(px, py, pz);
                v += (kBone - v) * bone;
                if (brain_row && x >= b0 && x <= b1) {
                    const float brain = skull_in_.cover(px, py, pz);
                    if (brain > 0) {
                        v += (kBrain - v) * brain;
                        for (const auto& e : vent_) {
                            const float f = e.cover(px, py, pz);
                            if (f > 0) v += (kCsf - v) * f;
                        }
                        for (const auto& e : calc_) {
                            const float f = e.cover(px, py, pz);
                            if (f > 0) v += (kCalc - v) * f;
                        }
                    }
                }
            }
            out[x] += v - kAir;
        }
    }

private:
    struct Ellipsoid {
        double cx, cy, cz, a, b, c;
        // Fraction of the sample inside: a linear ramp one voxel wide across the surface,
        // using the first-order distance (1 - e) / |grad e| with e the normalised radius.
        float cover(double x, double y, double z) const {
            const double ux = (x - cx) / a, uy = (y - cy) / b, uz = (z - cz) / c;
            const double e2 = ux * ux + uy * uy + uz * uz;
            if (e2 > 1.5) return 0.0f;  // far outside (every ellipsoid here spans > 4 voxels)
            const double e = std::sqrt(e2);
            if (e < 1e-9) return 1.0f;
            const double gx = ux / a, gy = uy / b, gz = uz / c;
            const double grad = std::sqrt(gx * gx + gy * gy + gz * gz) / e;
            const double d = (1.0 - e) / grad;  // voxels, positive inside
            return float(std::clamp(d + 0.5, 0.0, 1.0));
        }
        // The x-range [x0, x1] of samples where cover() may be non-zero on row (y, z).
        bool span(double y, double z, std::size_t n, std::size_t& x0, std::size_t& x1) const {
            const double uy = (y - cy) / b, uz = (z - cz) / c;
            const double rest = 1.5 - uy * uy - uz * uz;
            if (rest <= 0) return false;
            const double half = a * std::sqrt(rest);
            const double lo = std::max(0.0, std::floor(cx - half)), hi = std::min(double(n - 1), std::ceil(cx + half));
            if (lo > hi) return false;
            x0 = std::size_t(lo);
            x1 = std::size_t(hi);
            return true;
        }
    };
    std::size_t n_;
    std::uint32_t seed_;
    Ellipsoid head_{}, skull_out_{}, skull_in_{}, foramen_{};
    Ellipsoid vent_[2]{};
    Ellipsoid calc_[4]{};
};

// ---- storing as a scalar type ------------------------------------------------------------

// Linear map native -> stored value: stored = offset + scale * native.
struct Quantizer {
    double scale = 1, offset = 0;
};

template <class T>
Quantizer integer_quantizer(Field field, const FieldSpec& spec) {
    using L = std::numeric_limits<T>;
    const double tmin = double(L::min()), tmax = double(L::max());
    if (field == Field::Ct) {
        // CT-like storage: i16/i32 hold Hounsfield units, u16/u32 HU + 1024 (the usual
        // unsigned CT offset), 8-bit types a window from -1000 to 1500 HU.
        if constexpr (sizeof(T) >= 2) {
            if (L::is_signed) return {1.0, 0.0};
            return {1.0, 1024.0};
        } else {
            const double scale = (tmax - tmin) / 2500.0;
            return {scale, tmin + 1000.0 * scale};
        }
    }
    // Other fields: the native range onto the type's range, leaving a small margin.
    const double span = std::min(tmax - tmin, 65535.0);  // 32-bit types: a 16-bit span suffices
    const double mid = 0.5 * (tmin + tmax);
    const double scale = span * 0.98 / (spec.hi - spec.lo);
    const double native_mid = 0.5 * (spec.lo + spec.hi);
    return {scale, std::floor(mid) - scale * native_mid};
}

template <class T>
void store_row(const float* in, T* out, std::size_t n, const Quantizer& q) {
    if constexpr (std::is_floating_point_v<T>) {
        for (std::size_t i = 0; i < n; ++i) out[i] = T(in[i]);
    } else {
        using L = std::numeric_limits<T>;
        const double lo = double(L::min()), hi = double(L::max());
        for (std::size_t i = 0; i < n; ++i) {
            const double v = std::nearbyint(q.offset + q.scale * double(in[i]));
            out[i] = T(std::clamp(v, lo, hi));
        }
    }
}

// Runs rows (y, z) of the volume on all cores; every z-plane is one work item.
template <class T>
void fill(const Generator& gen, std::size_t n, T* data, const Quantizer& q) {
    const unsigned workers = std::min<unsigned>(detail::resolve_threads(0), unsigned(std::max<std::size_t>(n, 1)));
    std::atomic<std::size_t> next{0};
    detail::run_workers(workers, [&](unsigned) {
        std::vector<float> buf(n);
        for (std::size_t z; (z = next.fetch_add(1)) < n;)
            for (std::size_t y = 0; y < n; ++y) {
                gen.row(y, z, buf.data());
                store_row(buf.data(), data + n * (y + n * z), n, q);
            }
    });
}

template <class T>
double make_typed(Field field, const Generator& gen, std::size_t n, void* data) {
    Quantizer q;
    if constexpr (!std::is_floating_point_v<T>) q = integer_quantizer<T>(field, gen.spec);
    fill(gen, n, static_cast<T*>(data), q);
    if constexpr (std::is_floating_point_v<T>) {
        return gen.spec.iso;
    } else {
        // The mapped iso, moved to the nearest half-integer: no stored sample equals it.
        return std::floor(q.offset + q.scale * gen.spec.iso) + 0.5;
    }
}

// make_field, its arguments checked.
FieldVolume make_field_unchecked(Field field, std::size_t n, ScalarType type, std::uint32_t seed) {
    std::unique_ptr<Generator> gen;
    switch (field) {
        case Field::Sphere: gen = std::make_unique<SphereField>(n); break;
        case Field::Gyroid: gen = std::make_unique<GyroidField>(n); break;
        case Field::Blobs: gen = std::make_unique<BlobsField>(n, seed); break;
        case Field::Ct: gen = std::make_unique<CtField>(n, seed); break;
        default: throw Error("unknown built-in field");
    }
    FieldVolume out;
    out.volume = Volume::allocate(type, {n, n, n});
    void* data = out.volume.data;
    switch (type) {
        case ScalarType::U8: out.iso = make_typed<std::uint8_t>(field, *gen, n, data); break;
        case ScalarType::I8: out.iso = make_typed<std::int8_t>(field, *gen, n, data); break;
        case ScalarType::U16: out.iso = make_typed<std::uint16_t>(field, *gen, n, data); break;
        case ScalarType::I16: out.iso = make_typed<std::int16_t>(field, *gen, n, data); break;
        case ScalarType::U32: out.iso = make_typed<std::uint32_t>(field, *gen, n, data); break;
        case ScalarType::I32: out.iso = make_typed<std::int32_t>(field, *gen, n, data); break;
        case ScalarType::F32: out.iso = make_typed<float>(field, *gen, n, data); break;
        case ScalarType::F64: out.iso = make_typed<double>(field, *gen, n, data); break;
        default: throw Error("unknown scalar type");
    }
    return out;
}

}  // namespace

FieldVolume make_field(Field field, std::size_t n, ScalarType type, std::uint32_t seed) {
    // Below 8 samples the iso can miss every sample: the sphere (radius 0.4 n) lies between the
    // samples at n = 2, the gyroid's 4 periods alias to 0 at n = 2 and 4, and seeded blobs can
    // fall between them up to n = 6.
    if (n < kMinFieldSize)
        throw Error("a built-in field needs at least " + std::to_string(kMinFieldSize) + " samples per axis (got " +
                    std::to_string(n) + ")");
    if (n > (std::size_t(1) << 20)) throw Error("built-in field size " + std::to_string(n) + " is too large");
    // Volume::allocate names the volume's bytes itself; this is for the generators' own memory.
    return detail::out_of_memory_as_error(
        [&] { return "out of memory making the built-in " + std::string(field_name(field)) + " field of " +
                        std::to_string(n) + "^3 samples"; },
        [&] { return make_field_unchecked(field, n, type, seed); });
}

Field parse_field(const std::string& name) {
    if (name == "sphere") return Field::Sphere;
    if (name == "gyroid") return Field::Gyroid;
    if (name == "blobs") return Field::Blobs;
    if (name == "ct") return Field::Ct;
    throw Error("unknown field '" + name + "' (expected sphere, gyroid, blobs or ct)");
}

const char* field_name(Field field) {
    switch (field) {
        case Field::Sphere: return "sphere";
        case Field::Gyroid: return "gyroid";
        case Field::Blobs: return "blobs";
        case Field::Ct: return "ct";
    }
    return "?";
}

}  // namespace voxmesh
