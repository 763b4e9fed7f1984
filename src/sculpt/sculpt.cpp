// voxmesh::Sculpt: the editable volume, brushes, dirty tracking, block re-meshing and the
// welded assembly of the whole mesh.
//
// Block size 32 (default). Trade-offs measured/estimated for a surface mesh:
//  - Vertices on the faces between blocks are stored by both blocks. About 2/B of all
//    crossed edges lie on a block face plane, so B = 32 stores ~6 % extra vertices, which
//    is ~3 % of the mesh bytes (a vertex is 24 bytes, a triangle 12, with ~2 triangles per
//    vertex); B = 16 would double that and break the "+10 %" memory budget once vector
//    slack and bookkeeping are added; B = 64 halves it but re-meshes 8x the volume.
//  - A brush of radius 8..16 samples changes a box of 17..33 samples; with the one-sample
//    margin it touches 2..3 blocks per axis at B = 32, i.e. 8..27 blocks of 33³ samples:
//    ~0.3..1 M samples classified and a few thousand vertices per update, a few ms.
//  - 512³ has 16³ = 4096 blocks: the block table is negligible.
#include <voxmesh/sculpt.hpp>

#include "block_mesher.hpp"
#include "device_blocks.hpp"
#include "sculpt_options.hpp"
#include "core/cpu_engine.hpp"
#include "core/dims_text.hpp"
#include "core/out_of_memory.hpp"
#include "core/parallel.hpp"
#include "core/threshold.hpp"

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>

namespace voxmesh {

namespace detail::sculpt {
struct BlockStore {  // one block's self-contained mesh
    std::vector<float> positions, normals;
    std::vector<std::uint32_t> indices;
};
}  // namespace detail::sculpt

namespace {

using namespace detail::sculpt;
using Clock = std::chrono::steady_clock;

template <class F>
decltype(auto) dispatch_sculpt_type(ScalarType type, F&& f) {
    switch (type) {
        case ScalarType::U8: return f(std::uint8_t{});
        case ScalarType::U16: return f(std::uint16_t{});
        case ScalarType::F32: return f(float{});
        default: break;
    }
    throw Error(std::string("sculpting needs a u8, u16 or f32 volume, not ") + scalar_name(type) +
                "; convert the samples first");
}

// A double converted to the sample type: rounded and clamped for integers, clamped to the
// finite float range for f32.
template <class T>
T store_value(double v) {
    if constexpr (std::is_integral_v<T>) {
        const double r = std::nearbyint(v);
        if (!(r > 0)) return 0;
        if (r >= static_cast<double>(std::numeric_limits<T>::max())) return std::numeric_limits<T>::max();
        return static_cast<T>(r);
    } else {
        const double m = static_cast<double>(std::numeric_limits<float>::max());
        return static_cast<float>(std::clamp(v, -m, m));
    }
}

void check_finite(double v, const char* what) {
    if (!std::isfinite(v)) throw Error(std::string("sculpt: ") + what + " must be finite");
}

// Inclusive range of samples [lo, hi] on one axis, or empty.
struct Span {
    std::size_t lo = 1, hi = 0;
    bool empty() const { return lo > hi; }
};

// Grows the box `changed` to hold sample (x, y, z).
void include_sample(std::array<Span, 3>& changed, std::size_t x, std::size_t y, std::size_t z) {
    const std::size_t p[3] = {x, y, z};
    for (int d = 0; d < 3; ++d) {
        if (changed[d].empty()) {
            changed[d].lo = changed[d].hi = p[d];
        } else {
            changed[d].lo = std::min(changed[d].lo, p[d]);
            changed[d].hi = std::max(changed[d].hi, p[d]);
        }
    }
}

// Samples with a <= coordinate <= b, clipped to [0, n-1].
Span clip_span(double a, double b, std::size_t n) {
    Span s;
    const double lo = std::ceil(a), hi = std::floor(b);
    if (!(lo <= hi) || hi < 0 || lo > static_cast<double>(n - 1)) return s;
    s.lo = lo <= 0 ? 0 : static_cast<std::size_t>(lo);
    s.hi = hi >= static_cast<double>(n - 1) ? n - 1 : static_cast<std::size_t>(hi);
    return s;
}

// Sets v to n elements: exact on the first fill, with ~3 % headroom when a block grows again
// (so a growing stroke does not reallocate every frame), shrunk when slack exceeds 1/8, so
// block storage stays within a few percent of its contents.
template <class V>
void fit(V& v, std::size_t n) {
    if (n > v.capacity()) {
        const bool first = v.capacity() == 0;
        v.clear();
        v.reserve(first ? n : n + n / 32);
    } else if (v.capacity() > n + n / 8 + 64) {
        V fresh;
        fresh.reserve(n);
        v.swap(fresh);
    }
    v.resize(n);
}

}  // namespace

const char* brush_op_name(BrushOp op) {
    switch (op) {
        case BrushOp::Add: return "add";
        case BrushOp::Subtract: return "subtract";
        case BrushOp::Smooth: return "smooth";
        case BrushOp::Set: return "set";
    }
    return "?";
}

BrushOp parse_brush_op(const std::string& name) {
    if (name == "add") return BrushOp::Add;
    if (name == "subtract") return BrushOp::Subtract;
    if (name == "smooth") return BrushOp::Smooth;
    if (name == "set") return BrushOp::Set;
    throw Error("unknown brush op '" + name + "' (expected add, subtract, smooth or set)");
}

// ---------------------------------------------------------------- Impl

struct Sculpt::Impl {
    SculptOptions options;
    Volume volume;
    std::array<std::size_t, 3> n{0, 0, 0};
    std::array<std::size_t, 3> nb{0, 0, 0};
    std::size_t bs = 32;
    unsigned threads = 1;
    bool no_surface = false;  // iso outside the type's range: nothing is ever inside/outside

    std::vector<BlockStore> blocks;
    std::vector<std::uint8_t> dirty_flag;
    std::vector<std::uint32_t> dirty_list;
    // Per block: non-empty after the last update() that completed, which is what a caller
    // redrawing each UpdateResult::changed shows. Not read from the block's store: an update
    // that fails (out of memory) may leave dirty blocks' stores half re-meshed.
    std::vector<std::uint8_t> shown_nonempty;
    std::vector<Scratch> scratch;            // per worker
    std::vector<double> plane_prev, plane_cur;  // smoothing: old values of planes z-1 and z
    std::unique_ptr<DeviceBlockMesher> device;  // set: update() re-meshes on this OpenCL device
    std::vector<BlockBox> device_boxes;         // the dirty blocks' boxes, for the device

    void warn(const std::string& message) const {
        if (options.log) options.log(message);
    }

    std::size_t block_index(std::size_t bx, std::size_t by, std::size_t bz) const { return bx + nb[0] * (by + nb[1] * bz); }
    std::array<std::size_t, 3> block_coord(std::size_t index) const {
        return {index % nb[0], index / nb[0] % nb[1], index / (nb[0] * nb[1])};
    }
    BlockBox box_of(std::size_t index) const {
        const auto c = block_coord(index);
        BlockBox box;
        for (int d = 0; d < 3; ++d) {
            box.c0[d] = c[d] * bs;
            box.samples[d] = std::min(box.c0[d] + bs, n[d] - 1) - box.c0[d] + 1;
        }
        return box;
    }

    void mark(std::size_t index) {
        if (dirty_flag[index]) return;
        dirty_flag[index] = 1;
        dirty_list.push_back(static_cast<std::uint32_t>(index));
    }

    // Every block whose sample range [c0-1, c1+1] meets the changed samples.
    void mark_changed(const std::array<Span, 3>& changed) {
        std::array<std::size_t, 3> lo{}, hi{};
        for (int d = 0; d < 3; ++d) {
            if (changed[d].empty()) return;
            // block b (cells [bB, (b+1)B)) reads samples [bB - 1, (b+1)B + 1]
            const std::size_t s_lo = changed[d].lo, s_hi = changed[d].hi;
            lo[d] = s_lo < 2 ? 0 : (s_lo - 1 + bs - 1) / bs - 1;
            hi[d] = std::min(nb[d] - 1, (s_hi + 1) / bs);
        }
        for (std::size_t z = lo[2]; z <= hi[2]; ++z)
            for (std::size_t y = lo[1]; y <= hi[1]; ++y)
                for (std::size_t x = lo[0]; x <= hi[0]; ++x) mark(block_index(x, y, z));
    }

    void mark_all() {
        for (std::size_t i = 0; i < blocks.size(); ++i) mark(i);
    }

    VolumeView view() const { return volume.view(); }

    std::array<double, 3> to_samples(std::array<double, 3> p) const {
        for (int d = 0; d < 3; ++d) p[d] = (p[d] - volume.origin[d]) / volume.spacing[d];
        return p;
    }
    std::array<double, 3> radii(double r, Units units) const {
        if (units == Units::Samples) return {r, r, r};
        return {r / volume.spacing[0], r / volume.spacing[1], r / volume.spacing[2]};
    }

    // ---------------------------------------------------------------- edits

    template <class T>
    void brush(BrushOp op, std::array<double, 3> c, std::array<double, 3> r, double strength) {
        std::array<Span, 3> box;
        for (int d = 0; d < 3; ++d) {
            box[d] = clip_span(c[d] - r[d], c[d] + r[d], n[d]);
            if (box[d].empty()) return;
        }
        T* data = static_cast<T*>(volume.data);
        const std::size_t sy = n[0], sz = n[0] * n[1];
        std::array<Span, 3> changed;
        // Capped: 1 / r overflows for a radius below about 1e-308 samples, and 0 * inf at the
        // centre would write NaN. Such a brush touches only a sample it sits exactly on.
        const auto inverse = [](double radius) { return std::min(1 / radius, DBL_MAX); };
        const double inv[3] = {inverse(r[0]), inverse(r[1]), inverse(r[2])};

        // Smoothing reads the old values only (Jacobi), so the result does not depend on the
        // visiting order. Planes are done in increasing z: plane z+1 is still untouched in the
        // volume, and the old planes z-1 and z are kept in two plane buffers (the box's x-y
        // extent grown by one sample), so memory stays O(plane) for any brush size.
        Span px, py;
        std::size_t pnx = 0;
        if (op == BrushOp::Smooth) {
            strength = std::clamp(strength, 0.0, 1.0);
            px = {box[0].lo > 0 ? box[0].lo - 1 : 0, std::min(box[0].hi + 1, n[0] - 1)};
            py = {box[1].lo > 0 ? box[1].lo - 1 : 0, std::min(box[1].hi + 1, n[1] - 1)};
            pnx = px.hi - px.lo + 1;
            const std::size_t size = pnx * (py.hi - py.lo + 1);
            // The brush's only allocation, made before any sample changes: out of memory is an
            // Error like everywhere else (it let std::bad_alloc out of smooth()).
            detail::out_of_memory_as_error(
                [&] {
                    return "sculpt: out of memory for the smooth brush's planes of " + std::to_string(size) + " samples";
                },
                [&] {
                    plane_prev.resize(size);
                    plane_cur.resize(size);
                });
        }
        auto load_plane = [&](std::vector<double>& plane, std::size_t z) {
            std::size_t i = 0;
            for (std::size_t y = py.lo; y <= py.hi; ++y)
                for (std::size_t x = px.lo; x <= px.hi; ++x) plane[i++] = static_cast<double>(data[x + y * sy + z * sz]);
        };
        auto old_at = [&](const std::vector<double>& plane, std::size_t x, std::size_t y) {
            return plane[(x - px.lo) + pnx * (y - py.lo)];
        };

        // Finite whatever strength and scale are (inf times a falloff that underflows to 0 is
        // NaN); the sum saturates in store_value like any large strength.
        const double scaled = std::clamp(strength * options.strength_scale, -DBL_MAX, DBL_MAX);
        const double amount = op == BrushOp::Subtract ? -scaled : scaled;
        for (std::size_t z = box[2].lo; z <= box[2].hi; ++z) {
            const bool has_below = z > 0, has_above = z + 1 < n[2];
            if (op == BrushOp::Smooth) {
                if (z == box[2].lo) {
                    if (has_below) load_plane(plane_prev, z - 1);
                } else {
                    std::swap(plane_prev, plane_cur);  // old plane z-1
                }
                load_plane(plane_cur, z);
            }
            const double dz = (static_cast<double>(z) - c[2]) * inv[2];
            for (std::size_t y = box[1].lo; y <= box[1].hi; ++y) {
                const double dy = (static_cast<double>(y) - c[1]) * inv[1];
                const double yz = dy * dy + dz * dz;
                if (yz >= 1) continue;
                for (std::size_t x = box[0].lo; x <= box[0].hi; ++x) {
                    const double dx = (static_cast<double>(x) - c[0]) * inv[0];
                    const double s2 = dx * dx + yz;
                    if (s2 >= 1) continue;
                    const double f = 1 - s2, w = f * f * f;
                    T& v = data[x + y * sy + z * sz];
                    const double old = static_cast<double>(v);
                    double next;
                    if (op == BrushOp::Smooth) {
                        // Neighbours beyond the volume's border are the sample itself.
                        const std::size_t xm = x > 0 ? x - 1 : x, xp = x + 1 < n[0] ? x + 1 : x;
                        const std::size_t ym = y > 0 ? y - 1 : y, yp = y + 1 < n[1] ? y + 1 : y;
                        const double below = has_below ? old_at(plane_prev, x, y) : old;
                        const double above = has_above ? static_cast<double>(data[x + y * sy + (z + 1) * sz]) : old;
                        const double mean = (old_at(plane_cur, xm, y) + old_at(plane_cur, xp, y) +
                                             old_at(plane_cur, x, ym) + old_at(plane_cur, x, yp) + below + above) /
                                            6;
                        next = old + strength * w * (mean - old);
                    } else {
                        next = old + amount * w;
                    }
                    const T stored = store_value<T>(next);
                    if (stored != v) {
                        v = stored;
                        include_sample(changed, x, y, z);
                    }
                }
            }
        }
        mark_changed(changed);
    }

    template <class T>
    void set_box(std::array<double, 3> lo, std::array<double, 3> hi, double value) {
        std::array<Span, 3> box;
        for (int d = 0; d < 3; ++d) {
            box[d] = clip_span(lo[d], hi[d], n[d]);
            if (box[d].empty()) return;
        }
        const T stored = store_value<T>(value);
        T* data = static_cast<T*>(volume.data);
        std::array<Span, 3> changed;
        for (std::size_t z = box[2].lo; z <= box[2].hi; ++z)
            for (std::size_t y = box[1].lo; y <= box[1].hi; ++y) {
                T* row = data + (z * n[1] + y) * n[0];
                for (std::size_t x = box[0].lo; x <= box[0].hi; ++x) {
                    if (row[x] == stored) continue;
                    row[x] = stored;
                    include_sample(changed, x, y, z);
                }
            }
        mark_changed(changed);
    }

    void apply(const Dab& dab, Units units) {
        // brush_op_name's switch names every op (-Wswitch keeps it whole): "?" is a value outside the enum
        if (std::string_view(brush_op_name(dab.op)) == "?")
            throw Error("sculpt: unknown brush op " + std::to_string(static_cast<int>(dab.op)) +
                        " (expected BrushOp::Add, Subtract, Smooth or Set)");
        for (double v : dab.center) check_finite(v, "brush centre");
        check_finite(dab.radius, "brush radius");
        check_finite(dab.strength, "brush strength");
        if (!(dab.radius > 0)) throw Error("sculpt: brush radius must be positive, got " + std::to_string(dab.radius));
        const std::array<double, 3> c = units == Units::World ? to_samples(dab.center) : dab.center;
        const std::array<double, 3> r = radii(dab.radius, units);
        dispatch_sculpt_type(volume.type, [&](auto tag) {
            using T = decltype(tag);
            if (dab.op == BrushOp::Set) {
                set_box<T>({c[0] - r[0], c[1] - r[1], c[2] - r[2]}, {c[0] + r[0], c[1] + r[1], c[2] + r[2]},
                           dab.strength);
            } else {
                brush<T>(dab.op, c, r, dab.strength);
            }
        });
    }

    // ---------------------------------------------------------------- meshing

    template <class T>
    BlockMesher<T> mesher() const {
        const detail::Threshold<T> t = detail::make_threshold<T>(options.iso);
        return BlockMesher<T>(view(), t.value, options.iso, options.inside_below, options.normals);
    }

    template <class T>
    void mesh_block(const BlockMesher<T>& m, std::size_t index, Scratch& s) {
        BlockStore& out = blocks[index];
        const BlockBox box = box_of(index);
        const std::uint32_t vertices = no_surface ? 0 : m.classify(box, s);
        if (vertices == 0) {
            fit(out.positions, 0);
            fit(out.normals, 0);
            fit(out.indices, 0);
            return;
        }
        fit(out.positions, 3 * std::size_t{vertices});
        fit(out.normals, options.normals ? 3 * std::size_t{vertices} : 0);
        m.write_vertices(box, s, out.positions.data(), out.normals.data());
        s.tris.clear();
        m.triangles(box, s, nullptr);
        fit(out.indices, s.tris.size());
        if (!s.tris.empty()) std::memcpy(out.indices.data(), s.tris.data(), s.tris.size() * sizeof(std::uint32_t));
    }

    unsigned workers_for(std::size_t jobs) const {
        return static_cast<unsigned>(std::max<std::size_t>(1, std::min<std::size_t>(threads, jobs)));
    }

    void remesh_on_cpu() {
        const std::size_t jobs = dirty_list.size();
        const unsigned workers = workers_for(jobs);
        if (scratch.size() < workers) scratch.resize(workers);
        dispatch_sculpt_type(volume.type, [&](auto tag) {
            using T = decltype(tag);
            const BlockMesher<T> m = mesher<T>();
            std::atomic<std::size_t> next{0};
            detail::run_workers(workers, [&](unsigned w) {
                Scratch& s = scratch[w];
                s.reserve_for(bs);
                for (std::size_t i; (i = next.fetch_add(1, std::memory_order_relaxed)) < jobs;)
                    mesh_block(m, dirty_list[i], s);
            });
        });
    }

    // In a child forked after the device was opened, the CPU re-meshes from then on: the
    // device's objects are the parent's runtime's, and even releasing them would not return.
    void drop_device_left_in_parent() {
        if (!device || !device->left_in_parent()) return;
        warn(device->device_name() + " was opened before this process was forked and cannot be used in the child; "
             "sculpt re-meshes on the CPU from now on");
        (void)device.release();  // deliberately leaked (see DeviceBlockMesher::left_in_parent)
    }

    ~Impl() {
        if (device && device->left_in_parent()) (void)device.release();
    }

    // False after an OpenCL failure: the device is dropped (with a warning) and the caller
    // re-meshes on the CPU, now and from then on.
    bool remesh_on_device() {
        device_boxes.resize(dirty_list.size());
        for (std::size_t i = 0; i < dirty_list.size(); ++i) device_boxes[i] = box_of(dirty_list[i]);
        try {
            device->mesh(device_boxes, [&](std::size_t i, const DeviceBlockMesh& m) {
                BlockStore& out = blocks[dirty_list[i]];
                copy_into(out.positions, m.positions);
                copy_into(out.normals, m.normals);
                copy_into(out.indices, m.indices);
            });
        } catch (const Error& e) {
            warn(std::string(e.what()) + "; sculpt re-meshes on the CPU from now on");
            device.reset();
            return false;
        }
        return true;
    }

    template <class V, class S>
    static void copy_into(V& v, S from) {
        fit(v, from.size());
        if (!from.empty()) std::memcpy(v.data(), from.data(), from.size_bytes());
    }

    UpdateResult update() {
        const auto t0 = Clock::now();
        UpdateResult result;
        const std::size_t jobs = dirty_list.size();
        if (jobs > 0) {
            // Before any dirty flag is cleared below: a push_back that ran out of memory there
            // left blocks still in the dirty list with their flags cleared, and the next edit
            // listed them twice.
            result.changed.reserve(jobs);
            drop_device_left_in_parent();
            if (!device || no_surface || !remesh_on_device()) remesh_on_cpu();
            for (std::size_t i = 0; i < jobs; ++i) {
                const std::uint32_t b = dirty_list[i];
                dirty_flag[b] = 0;
                const bool nonempty = !blocks[b].indices.empty();
                if (shown_nonempty[b] || nonempty) result.changed.push_back(b);
                shown_nonempty[b] = nonempty;
            }
            std::sort(result.changed.begin(), result.changed.end());
            result.remeshed = jobs;
            dirty_list.clear();
        }
        result.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        return result;
    }

    // ---------------------------------------------------------------- assembly

    // What mesh() learns about one non-empty block: its vertices' global edge keys (recomputed
    // from the volume, not stored between updates) and how its vertices and triangles fall
    // into global rows.
    struct Assembly {
        std::vector<std::uint64_t> owned_keys;       // sample linear index * 3 + axis, ascending
        std::vector<std::uint32_t> owned_gid;        // global id of each owned vertex
        std::vector<std::uint32_t> local_owned;      // per local vertex: owned index or kForeign
        std::vector<std::uint64_t> foreign_keys;     // keys of the others, in local order
        std::vector<std::uint32_t> owned_row_count;  // per owned sample row of the block
        std::vector<std::uint32_t> tri_row_count;    // per cell row
        std::vector<std::uint32_t> local_gid;        // per local vertex: global id
        std::size_t owned_rows_y = 0;
        std::size_t vertex_cursor = 0, tri_cursor = 0;
    };
    static constexpr std::uint32_t kForeign = std::numeric_limits<std::uint32_t>::max();

    // The block owning sample coordinate s on axis d (the last block also owns n-1).
    std::size_t owner_block(std::size_t s, int d) const { return std::min(s / bs, nb[d] - 1); }

    template <class T>
    Mesh assemble() {
        Mesh mesh;
        if (no_surface) return mesh;
        const std::size_t count = blocks.size();
        std::vector<Assembly> asm_(count);
        std::vector<std::uint32_t> nonempty;
        for (std::size_t i = 0; i < count; ++i)
            if (!blocks[i].indices.empty()) nonempty.push_back(static_cast<std::uint32_t>(i));
        const unsigned workers = workers_for(nonempty.size());
        if (scratch.size() < workers) scratch.resize(workers);
        const BlockMesher<T> m = mesher<T>();

        // 1. Per block: edge keys, ownership, row counts (parallel).
        {
            std::atomic<std::size_t> next{0};
            detail::run_workers(workers, [&](unsigned w) {
                Scratch& s = scratch[w];
                s.reserve_for(bs);
                for (std::size_t j; (j = next.fetch_add(1, std::memory_order_relaxed)) < nonempty.size();) {
                    const std::size_t b = nonempty[j];
                    Assembly& a = asm_[b];
                    const BlockBox box = box_of(b);
                    const auto bc = block_coord(b);
                    const std::uint32_t vertices = m.classify(box, s);
                    if (vertices * std::size_t{3} != blocks[b].positions.size())
                        throw Error("sculpt: a block mesh is out of date with the volume (after writing through data(), "
                                    "call invalidate_all())");
                    // Owned samples: local [0, samples-1) per axis, plus the last one in the last block.
                    std::array<std::size_t, 3> owned{};
                    for (int d = 0; d < 3; ++d)
                        owned[d] = box.samples[d] - (bc[d] + 1 == nb[d] ? 0 : 1);
                    a.owned_rows_y = owned[1];
                    a.owned_row_count.assign(owned[1] * owned[2], 0);
                    a.local_owned.resize(vertices);
                    a.owned_keys.clear();
                    a.foreign_keys.clear();
                    std::size_t v = 0;
                    m.for_each_vertex(box, s, [&](std::size_t, std::size_t x, std::size_t y, std::size_t z,
                                                  unsigned axis) {
                        const std::uint64_t key =
                            ((box.c0[0] + x) + n[0] * ((box.c0[1] + y) + n[1] * (box.c0[2] + z))) * 3 + axis;
                        if (x < owned[0] && y < owned[1] && z < owned[2]) {
                            a.local_owned[v] = static_cast<std::uint32_t>(a.owned_keys.size());
                            a.owned_keys.push_back(key);
                            ++a.owned_row_count[z * owned[1] + y];
                        } else {
                            a.local_owned[v] = kForeign;
                            a.foreign_keys.push_back(key);
                        }
                        ++v;
                    });
                    a.tri_row_count.assign((box.samples[1] - 1) * (box.samples[2] - 1), 0);
                    s.tris.clear();
                    m.triangles(box, s, a.tri_row_count.data());
                    if (s.tris.size() != blocks[b].indices.size())
                        throw Error("sculpt: a block mesh is out of date with the volume (after writing through data(), "
                                    "call invalidate_all())");
                    a.owned_gid.resize(a.owned_keys.size());
                }
            });
        }

        // 2. Global vertex ids in canonical order: walk sample rows (y, z), blocks along x.
        std::uint64_t total_vertices = 0;
        for (std::size_t z = 0; z < n[2]; ++z) {
            const std::size_t bz = owner_block(z, 2), lz = z - bz * bs;
            for (std::size_t y = 0; y < n[1]; ++y) {
                const std::size_t by = owner_block(y, 1), ly = y - by * bs;
                for (std::size_t bx = 0; bx < nb[0]; ++bx) {
                    Assembly& a = asm_[block_index(bx, by, bz)];
                    if (a.owned_row_count.empty()) continue;
                    const std::uint32_t cnt = a.owned_row_count[lz * a.owned_rows_y + ly];
                    for (std::uint32_t i = 0; i < cnt; ++i) {
                        detail::check_vertex_count(total_vertices + 1);
                        a.owned_gid[a.vertex_cursor++] = static_cast<std::uint32_t>(total_vertices++);
                    }
                }
            }
        }
        mesh.positions.resize(3 * total_vertices);
        if (options.normals) mesh.normals.resize(3 * total_vertices);

        // 3. Local -> global ids (foreign vertices: looked up in their owner block), and the
        //    owned vertices' data copied into place (parallel).
        {
            std::atomic<std::size_t> next{0};
            detail::run_workers(workers, [&](unsigned) {
                for (std::size_t j; (j = next.fetch_add(1, std::memory_order_relaxed)) < nonempty.size();) {
                    const std::size_t b = nonempty[j];
                    Assembly& a = asm_[b];
                    const BlockStore& store = blocks[b];
                    a.local_gid.resize(a.local_owned.size());
                    std::size_t f = 0;
                    for (std::size_t v = 0; v < a.local_owned.size(); ++v) {
                        std::uint32_t gid;
                        if (a.local_owned[v] != kForeign) {
                            gid = a.owned_gid[a.local_owned[v]];
                            std::memcpy(&mesh.positions[3 * std::size_t{gid}], &store.positions[3 * v], 12);
                            if (options.normals)
                                std::memcpy(&mesh.normals[3 * std::size_t{gid}], &store.normals[3 * v], 12);
                        } else {
                            const std::uint64_t key = a.foreign_keys[f++];
                            const std::uint64_t sample = key / 3;
                            const std::size_t x = sample % n[0], y = sample / n[0] % n[1], z = sample / (n[0] * n[1]);
                            const Assembly& o =
                                asm_[block_index(owner_block(x, 0), owner_block(y, 1), owner_block(z, 2))];
                            const auto it = std::lower_bound(o.owned_keys.begin(), o.owned_keys.end(), key);
                            if (it == o.owned_keys.end() || *it != key)
                                throw Error("sculpt: internal error: a block-face vertex has no owner");
                            gid = o.owned_gid[static_cast<std::size_t>(it - o.owned_keys.begin())];
                        }
                        a.local_gid[v] = gid;
                    }
                }
            });
        }

        // 4. Triangles in canonical order: cell rows (y, z), blocks along x.
        std::size_t total_tris = 0;
        for (std::uint32_t b : nonempty) total_tris += blocks[b].indices.size();
        mesh.indices.resize(total_tris);
        std::uint32_t* out = mesh.indices.data();
        for (std::size_t z = 0; z + 1 < n[2]; ++z) {
            const std::size_t bz = z / bs, lz = z - bz * bs;
            for (std::size_t y = 0; y + 1 < n[1]; ++y) {
                const std::size_t by = y / bs, ly = y - by * bs;
                for (std::size_t bx = 0; bx < nb[0]; ++bx) {
                    const std::size_t b = block_index(bx, by, bz);
                    Assembly& a = asm_[b];
                    if (a.tri_row_count.empty()) continue;
                    const std::size_t rows_y = box_of(b).samples[1] - 1;
                    const std::size_t cnt = 3 * std::size_t{a.tri_row_count[lz * rows_y + ly]};
                    const std::uint32_t* src = blocks[b].indices.data() + a.tri_cursor;
                    for (std::size_t i = 0; i < cnt; ++i) *out++ = a.local_gid[src[i]];
                    a.tri_cursor += cnt;
                }
            }
        }
        return mesh;
    }
};

// ---------------------------------------------------------------- Sculpt

Sculpt::Sculpt(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Sculpt::Sculpt(Sculpt&&) noexcept = default;
Sculpt& Sculpt::operator=(Sculpt&&) noexcept = default;
Sculpt::~Sculpt() = default;

namespace {

// adopt: samples to take over (Volume::allocate's, of these dims and type); null: allocate.
std::unique_ptr<Sculpt::Impl> make_impl(std::array<std::size_t, 3> dims, ScalarType type, std::array<double, 3> spacing,
                                        std::array<double, 3> origin, const SculptOptions& options,
                                        Volume* adopt = nullptr);

// extract() refuses NaN and infinite samples; so does the sculpt, which must mesh alike (with
// the engine's own test, naming the first plane holding one).
void check_samples_finite(const Volume& volume) {
    if (const std::size_t z = detail::first_non_finite_plane(volume.view()); z < volume.dims[2])
        throw Error("sculpt: the volume has NaN or infinite samples (first in z-plane " + std::to_string(z) +
                    "); replace them first");
}

}  // namespace

Sculpt::Sculpt(const VolumeView& volume, const SculptOptions& options) {
    detail::validate_volume(volume);
    impl_ = make_impl(volume.dims, volume.type, volume.spacing, volume.origin, options);
    const std::size_t bytes = impl_->volume.byte_size();
    std::memcpy(impl_->volume.data, volume.data, bytes);
    check_samples_finite(impl_->volume);
}

Sculpt Sculpt::adopting(Volume&& volume, const SculptOptions& options) {
    detail::validate_volume(volume.view());
    std::unique_ptr<Impl> impl = make_impl(volume.dims, volume.type, volume.spacing, volume.origin, options, &volume);
    check_samples_finite(impl->volume);
    return Sculpt(std::move(impl));
}

Sculpt Sculpt::from_function(std::array<std::size_t, 3> dims, ScalarType type,
                             const std::function<double(double, double, double)>& f, const SculptOptions& options) {
    if (!f) throw Error("sculpt: from_function needs a function");
    std::unique_ptr<Impl> impl = make_impl(dims, type, {1, 1, 1}, {0, 0, 0}, options);
    Impl& im = *impl;
    dispatch_sculpt_type(type, [&](auto tag) {
        using T = decltype(tag);
        T* data = static_cast<T*>(im.volume.data);
        const unsigned workers = static_cast<unsigned>(std::min<std::size_t>(im.threads, dims[2]));
        std::atomic<bool> nan{false};
        detail::run_workers(workers, [&](unsigned w) {
            const detail::Share planes = detail::share_of(dims[2], w, workers);
            for (std::size_t z = planes.begin; z < planes.end; ++z)
                for (std::size_t y = 0; y < dims[1]; ++y) {
                    T* row = data + (z * dims[1] + y) * dims[0];
                    for (std::size_t x = 0; x < dims[0]; ++x) {
                        const double v = f(static_cast<double>(x), static_cast<double>(y), static_cast<double>(z));
                        if (std::isnan(v)) nan = true;
                        row[x] = store_value<T>(v);
                    }
                }
        });
        if (nan) throw Error("sculpt: the shape function returned NaN");
    });
    return Sculpt(std::move(impl));
}

namespace {

// Opens the OpenCL device update() re-meshes on, when the options ask for one and one exists.
void choose_backend(Sculpt::Impl& im) {
    const SculptOptions& o = im.options;
    if (o.backend == Backend::Cpu) return;
    int index = o.device;
    if (o.backend == Backend::Auto && index < 0) {
        // Auto: a GPU or accelerator re-meshes faster than the CPU's threads; a CPU OpenCL
        // device (PoCL) does not.
        for (const DeviceInfo& d : list_devices())
            if (d.type != DeviceType::Cpu && index < 0) index = d.index;
        if (index < 0) return;
    }
    DeviceBlockSetup setup;
    setup.volume = im.view();
    setup.iso = o.iso;
    setup.inside_below = o.inside_below;
    setup.normals = o.normals;
    std::string why;
    im.device = open_opencl_block_mesher(setup, index, why);
    if (!im.device) im.warn("no usable OpenCL device (" + why + "); sculpt re-meshes on the CPU");
}

}  // namespace

void detail::sculpt::check_options(const SculptOptions& options) {
    if (options.block_size < 2 || options.block_size > 256)
        throw Error("sculpt: block size must be 2..256 cells, got " + std::to_string(options.block_size));
    if (options.device < -1)  // -1 is the documented "choose one"; other negatives are mistakes
        throw Error("sculpt: device must be -1 (choose a GPU/accelerator) or a device index, got " +
                    std::to_string(options.device));
    if (options.backend == Backend::Hybrid)
        throw Error("sculpt: the hybrid backend is not supported; use cpu, opencl or auto");
    if (options.backend != Backend::Cpu && options.device >= 0) {
        const std::size_t count = list_devices().size();
        if (count > 0 && static_cast<std::size_t>(options.device) >= count)
            throw Error("sculpt: OpenCL device index " + std::to_string(options.device) +
                        " does not exist; list_devices() has " + std::to_string(count) + " device(s)");
    }
    check_finite(options.iso, "iso value");
    check_finite(options.strength_scale, "strength scale");
}

namespace {

std::unique_ptr<Sculpt::Impl> make_impl(std::array<std::size_t, 3> dims, ScalarType type, std::array<double, 3> spacing,
                                        std::array<double, 3> origin, const SculptOptions& options, Volume* adopt) {
    dispatch_sculpt_type(type, [](auto) {});  // rejects other types
    detail::sculpt::check_options(options);
    VolumeView probe;
    probe.data = &probe;  // validate_volume only checks that data is set
    probe.type = type;
    probe.dims = dims;
    probe.spacing = spacing;
    probe.origin = origin;
    detail::validate_volume(probe);

    std::array<std::size_t, 3> nb{};
    for (int d = 0; d < 3; ++d) nb[d] = (dims[d] - 1 + options.block_size - 1) / options.block_size;
    const std::size_t count = nb[0] * nb[1] * nb[2];
    if (count > std::numeric_limits<std::uint32_t>::max())
        throw Error("sculpt: too many blocks; use a larger block size");

    // The volume's own bytes are Volume::allocate's Error; the block table is this one's (a
    // small block size makes it as large as the volume).
    auto impl = detail::out_of_memory_as_error(
        [&] {
            return "sculpt: out of memory for a " + detail::dims_text(dims) + " volume in " + std::to_string(count) +
                   " blocks";
        },
        [&] {
            auto made = std::make_unique<Sculpt::Impl>();
            Sculpt::Impl& im = *made;
            im.options = options;
            if (im.options.strength_scale == 0) im.options.strength_scale = 1;
            // Capped as extract() caps them; no block mesh depends on the count.
            im.threads = detail::running_threads(options.threads);
            im.bs = options.block_size;
            im.volume = adopt ? std::move(*adopt) : Volume::allocate(type, dims);
            im.volume.spacing = spacing;
            im.volume.origin = origin;
            im.n = dims;
            im.nb = nb;
            im.blocks.resize(count);
            im.dirty_flag.assign(count, 0);
            im.shown_nonempty.assign(count, 0);
            im.dirty_list.reserve(count);
            dispatch_sculpt_type(type, [&](auto tag) {
                using T = decltype(tag);
                im.no_surface = detail::make_threshold<T>(options.iso).uniform != detail::Uniform::Mixed;
            });
            im.mark_all();
            return made;
        });
    choose_backend(*impl);
    return impl;
}

}  // namespace

void Sculpt::apply(const Dab& dab, Units units) { impl_->apply(dab, units); }

void Sculpt::add(std::array<double, 3> center, double radius, double strength, Units units) {
    impl_->apply(Dab{BrushOp::Add, center, radius, strength}, units);
}
void Sculpt::subtract(std::array<double, 3> center, double radius, double strength, Units units) {
    impl_->apply(Dab{BrushOp::Subtract, center, radius, strength}, units);
}
void Sculpt::smooth(std::array<double, 3> center, double radius, double strength, Units units) {
    impl_->apply(Dab{BrushOp::Smooth, center, radius, strength}, units);
}

void Sculpt::set_region(std::array<double, 3> lo, std::array<double, 3> hi, double value, Units units) {
    for (int d = 0; d < 3; ++d) {
        check_finite(lo[d], "region corner");
        check_finite(hi[d], "region corner");
    }
    check_finite(value, "region value");
    if (units == Units::World) {
        lo = impl_->to_samples(lo);
        hi = impl_->to_samples(hi);
    }
    dispatch_sculpt_type(impl_->volume.type, [&](auto tag) { impl_->set_box<decltype(tag)>(lo, hi, value); });
}

void Sculpt::invalidate_all() {
    check_samples_finite(impl_->volume);  // written through data(): the blocks must not mesh NaN
    impl_->mark_all();
}

UpdateResult Sculpt::update() {
    // impl_->update() clears the dirty list only once every block is meshed, so it still
    // counts the blocks when the message is made.
    return detail::out_of_memory_as_error(
        [&] { return "sculpt: out of memory re-meshing " + std::to_string(impl_->dirty_list.size()) + " blocks"; },
        [&] { return impl_->update(); });
}
bool Sculpt::dirty() const { return !impl_->dirty_list.empty(); }
std::size_t Sculpt::block_count() const { return impl_->blocks.size(); }
std::array<std::size_t, 3> Sculpt::block_grid() const { return impl_->nb; }

BlockMesh Sculpt::block(std::size_t index) const {
    const Impl& im = *impl_;
    if (index >= im.blocks.size())
        throw Error("sculpt: block " + std::to_string(index) + " out of range (" + std::to_string(im.blocks.size()) +
                    " blocks)");
    const BlockStore& s = im.blocks[index];
    BlockMesh b;
    b.index = index;
    b.coord = im.block_coord(index);
    const BlockBox box = im.box_of(index);
    for (int d = 0; d < 3; ++d) {
        b.cell_begin[d] = box.c0[d];
        b.cell_end[d] = box.c0[d] + box.samples[d] - 1;
    }
    b.positions = s.positions;
    b.normals = s.normals;
    b.indices = s.indices;
    return b;
}

Mesh Sculpt::mesh() {
    if (dirty()) update();
    return detail::out_of_memory_as_error(
        [] { return std::string("sculpt: out of memory welding the blocks' meshes into one"); },
        [&] {
            return dispatch_sculpt_type(impl_->volume.type, [&](auto tag) { return impl_->assemble<decltype(tag)>(); });
        });
}

VolumeView Sculpt::view() const { return impl_->view(); }
void* Sculpt::data() { return impl_->volume.data; }
const SculptOptions& Sculpt::options() const { return impl_->options; }
Backend Sculpt::backend() const { return impl_->device ? Backend::OpenCL : Backend::Cpu; }
std::string Sculpt::device_name() const { return impl_->device ? impl_->device->device_name() : "cpu"; }
std::array<double, 3> Sculpt::to_samples(std::array<double, 3> world) const { return impl_->to_samples(world); }

SculptMemory Sculpt::memory() const {
    const Impl& im = *impl_;
    SculptMemory m;
    for (const BlockStore& b : im.blocks)
        m.block_meshes += 4 * (b.positions.capacity() + b.normals.capacity() + b.indices.capacity());
    m.block_table = im.blocks.capacity() * sizeof(BlockStore) + im.dirty_flag.capacity() +
                    4 * im.dirty_list.capacity() + im.shown_nonempty.capacity();
    for (const Scratch& s : im.scratch) m.scratch += s.capacity_bytes();
    m.scratch += 8 * (im.plane_prev.capacity() + im.plane_cur.capacity());
    m.volume = im.volume.byte_size();
    return m;
}

}  // namespace voxmesh
