// How Hybrid shares a volume's z-chunks between the CPU worker and the OpenCL devices.
//
// The chunks not taken yet are a range [lo, hi). Devices take one chunk at a time from the
// front; the CPU worker, which meshes a run of chunks with all its threads at once, takes
// runs from the back. The two estimates below keep the slower side from holding up the
// end of a pass: a device whose copies cost more than the CPU's whole remaining work takes
// no further chunk, and once the CPU worker has meshed its own pieces it takes over a
// device's counted pieces while that is quicker than waiting for the device.
//
// Times are seconds per chunk measured in this call; 0 means not measured yet. Where an
// earlier call on the same device and volume shape measured both sides, the split is planned
// from those rates instead (hybrid_device_chunks) and the rules above only mend it.
//
// Sharing is not always quicker: the host threads that feed a GPU are the CPU engine's too, and
// where host memory bandwidth bounds both, splitting a volume costs more than it gains. So a
// call with one device picks, from what earlier calls with the same device, shape and settings
// took end to end, the quickest of the split, the CPU engine alone and the device alone
// (hybrid_choose_mode), kept per volume (HybridModeBook).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <map>
#include <utility>

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

// What a previous call on the same device, volume shape and settings measured, in seconds
// per sample: counting and generating on the CPU worker and on the device (0: not measured).
struct HybridRates {
    double cpu_count = 0, cpu_generate = 0, device_count = 0, device_generate = 0;
    bool known() const { return cpu_count > 0 && cpu_generate > 0 && device_count > 0 && device_generate > 0; }
};

// A side that the plan left without work measured nothing in a call: its rates from earlier
// calls grow more hopeful call by call until it gets a chunk to be measured by again, so that
// a side slow once (busy, a cold start) is not planned out for good, while one that stays
// slow costs a call now and then.
inline void hybrid_hope_for_idle(HybridRates& r, bool cpu_worked, bool device_worked) {
    constexpr double kHope = 0.8;
    if (!cpu_worked) {
        r.cpu_count *= kHope;
        r.cpu_generate *= kHope;
    }
    if (!device_worked) {
        r.device_count *= kHope;
        r.device_generate *= kHope;
    }
}

// How many of `chunks` equal chunks (of `samples` samples each) the device should mesh so that
// the call ends soonest. Every worker counts before anyone generates (the mesh is allocated in
// between), so a call takes max(device count, CPU count) + max(device generate, CPU generate):
// where the CPU's generate pass is the longer one, the device may count beyond the point
// where counting alone is balanced. Evaluated for every split; ties go to the CPU.
// A device planned out altogether still gets one chunk where that costs no more than the CPU
// needs for all the others, so that its rates stay measured.
inline std::size_t hybrid_device_chunks(std::size_t chunks, double samples, const HybridRates& r) {
    std::size_t best = 0;
    double best_s = 0;
    for (std::size_t k = 0; k <= chunks; ++k) {
        const double dev = static_cast<double>(k) * samples, cpu = static_cast<double>(chunks - k) * samples;
        const double s = std::max(dev * r.device_count, cpu * r.cpu_count) +
                         std::max(dev * r.device_generate, cpu * r.cpu_generate);
        if (k == 0 || s < best_s) {
            best = k;
            best_s = s;
        }
    }
    const double one_on_device = samples * (r.device_count + r.device_generate);
    const double rest_on_cpu = static_cast<double>(chunks - 1) * samples * (r.cpu_count + r.cpu_generate);
    if (best == 0 && chunks > 1 && one_on_device <= rest_on_cpu) best = 1;
    return best;
}

// What Hybrid runs in one call with one device.
enum class HybridMode : unsigned { Split = 0, CpuAlone = 1, DeviceAlone = 2 };
constexpr unsigned kHybridModes = 3;

// End-to-end seconds of earlier calls per mode, with one device, volume shape and settings, less
// the time a call spent replacing the mesh's arrays (allocate_output): that comes once where a
// reused mesh grows, in whichever mode ran then, and one such call once kept a mode 2x quicker
// from being picked (a GPU alone, gyroid u8 512^3 on the H200 machine, forty-third session).
struct HybridModeTimes {
    double seconds[kHybridModes] = {0, 0, 0};             // 0: not measured yet
    std::uint64_t measured_at[kHybridModes] = {0, 0, 0};  // `calls` when last measured
    std::uint64_t calls = 0;                              // calls measured
    std::uint64_t split_calls = 0;                        // split calls, the first included
    bool stale[kHybridModes] = {false, false, false};     // due for a recheck: the data changed
    std::uint64_t triangles_at[kHybridModes] = {0, 0, 0};  // the mesh's triangles when last measured
    bool unsettled[kHybridModes] = {false, false, false};  // last timed with a set-up in it
    double measured_s[kHybridModes] = {0, 0, 0};           // the time measured at triangles_at
};

// Whether meshes of `a` and `b` triangles differ by more than kHybridSurfaceChange times (the
// +1 lets an empty mesh count).
constexpr double kHybridSurfaceChange = 1.25;
inline bool hybrid_surface_changed(std::uint64_t a, std::uint64_t b) {
    const double ratio = (static_cast<double>(a) + 1) / (static_cast<double>(b) + 1);
    return ratio > kHybridSurfaceChange || ratio * kHybridSurfaceChange < 1;
}

// How often a mode other than the quickest is measured again (a recheck), so that a change of
// load or of the data in a volume of the same shape is noticed: a mode `gap` slower than the
// quickest (0.1: 10 % slower) once every gap / kHybridRecheckCost calls, so that its rechecks
// cost about that share of the time on average. Modes as quick as the best one, which the
// noise of a single call can reorder, are measured every few calls; those far slower seldom.
constexpr double kHybridRecheckCost = 0.01;
constexpr std::uint64_t kHybridMinRecheckCalls = 4, kHybridMaxRecheckCalls = 256;
inline std::uint64_t hybrid_recheck_calls(double gap) {
    const double calls = std::ceil(std::max(0.0, gap) / kHybridRecheckCost);
    if (!(calls < static_cast<double>(kHybridMaxRecheckCalls))) return kHybridMaxRecheckCalls;
    return std::max(kHybridMinRecheckCalls, static_cast<std::uint64_t>(calls));
}

// The quickest of the measured modes (the first of equals); call once all are measured.
inline unsigned hybrid_quickest_mode(const HybridModeTimes& t) {
    unsigned best = 0;
    for (unsigned m = 1; m < kHybridModes; ++m)
        if (t.seconds[m] < t.seconds[best]) best = m;
    return best;
}

// The mode for the next call: the split first (its first call builds the device's programs and
// measures the rates later splits are planned by, so its time is not counted), then each mode
// not measured yet, then the quickest, or a recheck that is due (the one closest to the quickest;
// the quickest first where its own time is due, an estimate from another surface). A mode left
// kHybridMaxRecheckCalls calls goes before all: surfaces that take turns call by call kept
// marking the quickest and the next closest due, and the third went unmeasured for good.
inline HybridMode hybrid_choose_mode(const HybridModeTimes& t) {
    if (t.split_calls == 0) return HybridMode::Split;
    for (unsigned m = 0; m < kHybridModes; ++m)
        if (t.seconds[m] <= 0) return static_cast<HybridMode>(m);
    const unsigned best = hybrid_quickest_mode(t);
    unsigned oldest = best;
    for (unsigned m = 0; m < kHybridModes; ++m)
        if (m != best && t.calls - t.measured_at[m] >= kHybridMaxRecheckCalls &&
            (oldest == best || t.measured_at[m] < t.measured_at[oldest]))
            oldest = m;
    if (oldest != best) return static_cast<HybridMode>(oldest);
    if (t.stale[best]) return static_cast<HybridMode>(best);  // an estimate: measured first
    unsigned pick = best;
    for (unsigned m = 0; m < kHybridModes; ++m) {
        if (m == best) continue;
        const bool due = t.stale[m] || t.calls - t.measured_at[m] >= hybrid_recheck_calls(t.seconds[m] / t.seconds[best] - 1);
        if (due && (pick == best || t.seconds[m] < t.seconds[pick])) pick = m;
    }
    return static_cast<HybridMode>(pick);
}

// A call in `mode` took `seconds` end to end and made `triangles`: that is the mode's time now.
// Where the mode was the quickest, the others' times follow its change by the same factor: the
// same shape can hold a sparser or a denser surface than the calls they were timed on (or the
// machine can be busier), and only a call in another mode can say that their order has
// changed. The sides do not scale alike with the surface (a GPU's copies cost the same for any
// surface, the CPU engine's generate grows with it), so where the data changed, the modes up to
// twice as slow as the quickest are measured again in the next calls, closest first. The data
// changed where the mesh's size differs by more than kHybridSurfaceChange from that mode's
// last measurement (exact, unlike times), or the quickest mode's time by more than
// kHybridDataChange (a change that keeps the size, or a busier machine).
//
// A time that follows a change of surface stays between the time measured on the mode's own
// surface and that time grown in proportion to the triangles (a call reads the whole volume
// whatever its surface, and writes each triangle), and one that follows the quickest mode on
// one surface within kHybridLoadBand of that: estimates follow estimates, and where a volume's
// surfaces (or two data sets of one size) took turns call by call, they were scaled again on
// every other call, to 1e291 s, then inf, until a recheck.
//
// A call that was not `settled` (it built device programs or made device buffers, which a GPU
// allocates on first use) timed that set-up too, once, in whichever mode ran then: its mode is
// measured again in the next calls, keeping an earlier time where it has one, and neither that
// time nor the next one scales the others. A second such call in a row counts as settled.
constexpr double kHybridDataChange = 2, kHybridLoadBand = 4;
inline void hybrid_record_mode(HybridModeTimes& t, HybridMode mode, double seconds, std::uint64_t triangles,
                               bool settled = true) {
    if (mode == HybridMode::Split && t.split_calls++ == 0) return;
    const auto m = static_cast<unsigned>(mode);
    // Once: a caller whose every call sets up again (release_memory() between calls) would
    // otherwise have this mode measured again and again, however slow.
    if (!settled && !t.unsettled[m]) {
        if (t.seconds[m] <= 0) {  // no time at all yet: this one, as an upper bound
            t.seconds[m] = t.measured_s[m] = std::max(seconds, 1e-9);
            t.triangles_at[m] = triangles;
            t.measured_at[m] = t.calls++;
        }
        t.unsettled[m] = true;
        t.stale[m] = true;
        return;
    }
    const bool after_set_up = t.unsettled[m];
    t.unsettled[m] = false;
    const double before = t.seconds[m], now = std::max(seconds, 1e-9);
    const bool measured = std::all_of(std::begin(t.seconds), std::end(t.seconds), [](double s) { return s > 0; });
    const bool quickest = measured && before <= t.seconds[hybrid_quickest_mode(t)];
    const std::uint64_t before_triangles = t.triangles_at[m];
    t.seconds[m] = t.measured_s[m] = now;
    t.measured_at[m] = t.calls++;
    t.stale[m] = false;
    t.triangles_at[m] = triangles;
    // The others follow the quickest mode's change; where the surface changed, any mode's, but
    // only those timed on its old surface (one timed on the new surface already is news).
    const bool surface_moved = before > 0 && hybrid_surface_changed(before_triangles, triangles);
    const double change = !after_set_up && (quickest || surface_moved) ? now / before : 1;  // either: before > 0
    const bool time_changed = quickest && (change > kHybridDataChange || change * kHybridDataChange < 1);
    for (unsigned o = 0; o < kHybridModes; ++o) {
        if (o == m || t.seconds[o] <= 0) continue;
        const bool follows = !surface_moved || !hybrid_surface_changed(t.triangles_at[o], before_triangles);
        if (!follows) continue;
        t.seconds[o] *= change;
        // Between the same time and one that grew with the triangles, from where it was
        // measured; on one surface, within kHybridLoadBand of that (a busier or quieter machine).
        const double r = (static_cast<double>(triangles) + 1) / (static_cast<double>(t.triangles_at[o]) + 1);
        const double band = surface_moved ? 1 : kHybridLoadBand;
        t.seconds[o] = std::clamp(t.seconds[o], t.measured_s[o] * std::min(1.0, r) / band,
                                  t.measured_s[o] * std::max(1.0, r) * band);
    }
    if (!measured) return;
    const double quickest_s = t.seconds[hybrid_quickest_mode(t)];
    for (unsigned o = 0; o < kHybridModes; ++o) {
        if (o == m || t.seconds[o] > 2 * quickest_s) continue;
        if (time_changed || hybrid_surface_changed(t.triangles_at[o], triangles)) t.stale[o] = true;
    }
}

// Mode times per volume, within one device, shape and settings: calls that take turns between
// volumes of one shape (several scans of one size, two sculpted objects) each keep their own
// times, since one volume's surface says little about another's, and sharing one record let
// each volume's calls mark the others' times stale. A volume not seen before (a sculpting loop
// that meshes a new array each call, say) starts from the times of the shape's latest call, so
// it is not measured afresh. The volume is known by its samples' address; `Shape` is any
// ordered key.
template <class Shape>
class HybridModeBook {
public:
    static constexpr std::size_t kVolumesPerShape = 8, kMaxEntries = 512;

    HybridMode choose(const Shape& shape, const void* volume) const {
        if (const auto it = entries_.find(key(shape, volume)); it != entries_.end())
            return hybrid_choose_mode(it->second.times);
        const Entry* latest = latest_of(shape);
        return latest ? hybrid_choose_mode(latest->times) : HybridMode::Split;
    }

    void record(const Shape& shape, const void* volume, HybridMode mode, double seconds, std::uint64_t triangles,
                bool settled = true) {
        auto it = entries_.find(key(shape, volume));
        if (it == entries_.end()) {
            const Entry* latest = latest_of(shape);
            const Entry start = latest ? *latest : Entry{};
            forget_for(shape);
            it = entries_.emplace(key(shape, volume), start).first;
        }
        hybrid_record_mode(it->second.times, mode, seconds, triangles, settled);
        it->second.used = ++clock_;
    }

    std::size_t size() const { return entries_.size(); }

private:
    using Key = std::pair<Shape, std::uintptr_t>;  // an address as a number: ordered everywhere
    struct Entry {
        HybridModeTimes times;
        std::uint64_t used = 0;  // clock_ at the latest call
    };

    static Key key(const Shape& shape, const void* volume) { return {shape, reinterpret_cast<std::uintptr_t>(volume)}; }

    // The first entry of `shape` and the one past its last (keys sort by shape, then address).
    auto first_of(const Shape& shape) const { return entries_.lower_bound(Key{shape, 0}); }
    auto end_of(const Shape& shape) const { return entries_.upper_bound(Key{shape, UINTPTR_MAX}); }

    const Entry* latest_of(const Shape& shape) const {
        const Entry* latest = nullptr;
        for (auto it = first_of(shape); it != end_of(shape); ++it)
            if (!latest || it->second.used > latest->used) latest = &it->second;
        return latest;
    }

    // Room for one more volume of `shape`: its least recently meshed volume goes past
    // kVolumesPerShape, everything past kMaxEntries.
    void forget_for(const Shape& shape) {
        if (entries_.size() >= kMaxEntries) entries_.clear();
        std::size_t count = 0;
        auto oldest = entries_.cend();
        for (auto it = first_of(shape); it != end_of(shape); ++it) {
            ++count;
            if (oldest == entries_.cend() || it->second.used < oldest->second.used) oldest = it;
        }
        if (count >= kVolumesPerShape) entries_.erase(oldest);
    }

    std::map<Key, Entry> entries_;
    std::uint64_t clock_ = 0;
};

}  // namespace voxmesh::detail
