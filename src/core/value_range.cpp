// value_range: min, max, non-finite and equal samples in one pass over z-slabs. Each plane takes
// a loop without a branch per sample, which the compiler vectorises; a plane holding a NaN or
// an infinity is then redone sample by sample.
#include "cpu_engine.hpp"  // check_samples_readable
#include "out_of_memory.hpp"
#include "parallel.hpp"
#include "row_packer.hpp"  // use_avx2, VOXMESH_X86_DISPATCH
#include "scalar_dispatch.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>
#include <vector>

namespace voxmesh {

namespace {

struct Partial {
    double min = std::numeric_limits<double>::infinity(), max = -std::numeric_limits<double>::infinity();
    std::uint64_t nonfinite = 0, equal = 0;
    std::size_t first_nonfinite = 0;  // linear index
};

// Floats compared as integers: the sign-magnitude bits turned two's complement order the same
// way the floats do (NaN aside), and integer min, max and the finite test vectorise where a float
// min/max reduction would not (its NaN and signed-zero rules forbid reordering).
template <class T>
struct Keys {  // integer samples are their own keys
    using Key = T;
    static Key key(T v) { return v; }
    static T value(Key k) { return k; }
    static bool nonfinite(T) { return false; }
};
template <class T, class Bits, class Signed>
struct FloatKeys {
    using Key = Signed;
    static constexpr Bits kMagnitude = ~Bits{0} >> 1;
    static Bits bits(T v) {
        Bits b;
        std::memcpy(&b, &v, sizeof b);
        return b;
    }
    static Key key(T v) {
        const Signed s = static_cast<Signed>(bits(v));
        return s ^ ((s >> (8 * sizeof(Signed) - 1)) & static_cast<Signed>(kMagnitude));
    }
    static T value(Key k) {
        const Bits b = static_cast<Bits>(k ^ ((k >> (8 * sizeof(Signed) - 1)) & static_cast<Signed>(kMagnitude)));
        T v;
        std::memcpy(&v, &b, sizeof v);
        return v;
    }
    static bool nonfinite(T v) {  // all exponent bits set: an infinity or a NaN
        const Bits exponent = bits(std::numeric_limits<T>::infinity());
        return (bits(v) & exponent) == exponent;
    }
};
template <>
struct Keys<float> : FloatKeys<float, std::uint32_t, std::int32_t> {};
template <>
struct Keys<double> : FloatKeys<double, std::uint64_t, std::int64_t> {};

// One plane of `count` samples at `s` (linear index `base`) into `part`. Inlined into a
// baseline and an AVX2 copy below: AVX2 doubles the lanes of the integer min, max and compares,
// and SSE2 has no 32-bit integer min or max at all.
template <class T>
[[gnu::always_inline]] inline void plane_range(const T* s, std::size_t count, std::size_t base, bool count_equal, T target,
                                               Partial& part) {
    using K = Keys<T>;
    using Key = typename K::Key;
    Key lo = std::numeric_limits<Key>::max(), hi = std::numeric_limits<Key>::lowest();
    std::uint64_t equal = 0;
    unsigned bad = 0;
    // Stretches of at most 2^16 samples, so that the equal count fits lanes of the key's width.
    using Count = std::conditional_t<sizeof(Key) >= 4, std::make_unsigned_t<Key>, std::uint32_t>;
    for (std::size_t begin = 0; begin < count; begin += std::size_t{1} << 16) {
        const std::size_t end = std::min(count, begin + (std::size_t{1} << 16));
        Count stretch = 0;
        for (std::size_t i = begin; i < end; ++i) {
            const Key k = K::key(s[i]);
            lo = std::min(lo, k);
            hi = std::max(hi, k);
            stretch += s[i] == target;
            bad |= K::nonfinite(s[i]);
        }
        equal += stretch;
    }
    if (bad) {  // NaN or infinities: sample by sample, leaving them out of min and max
        for (std::size_t j = 0; j < count; ++j) {
            const T v = s[j];
            if (K::nonfinite(v)) {
                if (part.nonfinite++ == 0) part.first_nonfinite = base + j;
                continue;
            }
            part.min = std::min(part.min, static_cast<double>(v));
            part.max = std::max(part.max, static_cast<double>(v));
            if (count_equal) part.equal += v == target;
        }
        return;
    }
    part.min = std::min(part.min, static_cast<double>(K::value(lo)));
    part.max = std::max(part.max, static_cast<double>(K::value(hi)));
    if (count_equal) part.equal += equal;
}

template <class T>
void plane_range_baseline(const T* s, std::size_t count, std::size_t base, bool count_equal, T target, Partial& part) {
    plane_range(s, count, base, count_equal, target, part);
}
#ifdef VOXMESH_X86_DISPATCH
template <class T>
__attribute__((target("avx2"))) void plane_range_avx2(const T* s, std::size_t count, std::size_t base,
                                                      bool count_equal, T target, Partial& part) {
    plane_range(s, count, base, count_equal, target, part);
}
#endif

// Whether a sample of type T can equal `value` exactly, and that sample.
template <class T>
bool representable(double value, T& sample) {
    if (std::isnan(value)) return false;
    if constexpr (std::is_integral_v<T>) {
        if (value != std::floor(value) || value < static_cast<double>(std::numeric_limits<T>::lowest()) ||
            value > static_cast<double>(std::numeric_limits<T>::max()))
            return false;
    } else if (!(std::fabs(value) <= static_cast<double>(std::numeric_limits<T>::max())) ||
               static_cast<double>(static_cast<T>(value)) != value) {
        return false;  // an infinity, beyond the type's range (checked before converting), or between its values
    }
    sample = static_cast<T>(value);
    return true;
}

template <class T>
ValueRange typed_range(const VolumeView& volume, std::optional<double> equal_to, unsigned threads) {
    const std::size_t plane = volume.dims[0] * volume.dims[1], nz = volume.dims[2];
    T target{};
    const bool count_equal = equal_to && representable<T>(*equal_to, target);
    const unsigned slabs = detail::slab_count(threads, nz, 4);
    std::vector<Partial> parts(slabs);
    const T* data = static_cast<const T*>(volume.data);
    auto* scan = &plane_range_baseline<T>;
#ifdef VOXMESH_X86_DISPATCH
    if (detail::use_avx2()) scan = &plane_range_avx2<T>;
#endif
    detail::run_slabs(slabs, threads, [&](unsigned slab, unsigned) {
        const detail::Share share = detail::share_of(nz, slab, slabs);
        for (std::size_t z = share.begin; z < share.end; ++z)
            scan(data + z * plane, plane, z * plane, count_equal, target, parts[slab]);
    });
    Partial all;
    for (const Partial& p : parts) {  // in slab order, so the first non-finite is the volume's first
        if (p.nonfinite && !all.nonfinite) all.first_nonfinite = p.first_nonfinite;
        all.nonfinite += p.nonfinite;
        all.equal += p.equal;
        all.min = std::min(all.min, p.min);
        all.max = std::max(all.max, p.max);
    }
    ValueRange r;
    if (all.min <= all.max) {  // + 0.0: a -0.0 extreme reads 0, whichever path found it
        r.min = all.min + 0.0;
        r.max = all.max + 0.0;
    }
    r.nonfinite = all.nonfinite;
    r.equal = all.equal;
    if (all.nonfinite) {
        const std::size_t i = all.first_nonfinite;
        r.first_nonfinite = {i % volume.dims[0], i / volume.dims[0] % volume.dims[1], i / plane};
    }
    return r;
}

}  // namespace

ValueRange value_range(const VolumeView& volume, std::optional<double> equal_to, unsigned threads) {
    checked_volume_bytes(volume.dims, volume.type);
    if (volume.dims[0] * volume.dims[1] * volume.dims[2] == 0) return {};
    detail::check_samples_readable(volume);
    const unsigned resolved = detail::resolve_threads(threads);
    return detail::out_of_memory_as_error([] { return std::string("out of memory summing up a volume's samples"); }, [&] {
        return detail::dispatch_scalar(volume.type,
                                       [&](auto tag) { return typed_range<decltype(tag)>(volume, equal_to, resolved); });
    });
}

}  // namespace voxmesh
