#include "cpu_engine.hpp"

#include "case_tables.hpp"
#include "edge_vertex.hpp"
#include "parallel.hpp"
#include "scalar_dispatch.hpp"
#include "threshold.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>

namespace voxmesh::detail {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ---------------------------------------------------------------- inside bits

template <class T>
bool compute_bits(const T* values, std::size_t n, T threshold, std::uint8_t* bits) {
    if constexpr (std::is_floating_point_v<T>) {
        unsigned nan = 0;
        for (std::size_t i = 0; i < n; ++i) {
            bits[i] = values[i] >= threshold;
            nan |= values[i] != values[i];
        }
        return nan != 0;
    } else {
        for (std::size_t i = 0; i < n; ++i) bits[i] = values[i] >= threshold;
        return false;
    }
}

[[noreturn]] void throw_nan(std::size_t z) {
    throw Error("volume has NaN samples (first seen in z-plane " + std::to_string(z) +
                "); replace them before meshing");
}

// ---------------------------------------------------------------- classify

// Counts the crossed +x/+y/+z edges a row owns and finds the x-span where they lie.
// next_y / next_z are the rows one step up in y / z, or null at the border.
void classify_row(const std::uint8_t* row, const std::uint8_t* next_y, const std::uint8_t* next_z, std::size_t nx,
                  RowInfo& info) {
    std::uint32_t count = 0;
    for (std::size_t i = 0; i + 1 < nx; ++i) count += row[i] ^ row[i + 1];
    if (next_y)
        for (std::size_t i = 0; i < nx; ++i) count += row[i] ^ next_y[i];
    if (next_z)
        for (std::size_t i = 0; i < nx; ++i) count += row[i] ^ next_z[i];
    info.vertices = count;
    if (count == 0) {
        info.first = kEmptyRow;
        info.uniform_bit = row[0];
        return;
    }
    auto crosses = [&](std::size_t i) {
        return (i + 1 < nx && row[i] != row[i + 1]) || (next_y && row[i] != next_y[i]) ||
               (next_z && row[i] != next_z[i]);
    };
    std::size_t first = 0, last = nx - 1;
    while (!crosses(first)) ++first;
    while (!crosses(last)) --last;
    info.first = static_cast<std::uint32_t>(first);
    info.last = static_cast<std::uint32_t>(last);
}

// A cell whose corners differ has a crossed edge owned by sample x or x+1 of rows (y, z) or
// (y+1, z) (those edges connect all 8 corners), so such cells lie in [first-1, last] of
// the two rows. Returns false when the cell row has none.
bool cell_span(const RowInfo& a, const RowInfo& b, std::size_t nx, std::size_t& begin, std::size_t& end) {
    const std::uint32_t lo = std::min(a.first, b.first);
    if (lo == kEmptyRow) return false;
    const std::uint32_t hi = std::max(a.first == kEmptyRow ? 0u : a.last, b.first == kEmptyRow ? 0u : b.last);
    begin = lo > 0 ? lo - 1 : 0;
    end = std::min<std::size_t>(hi, nx - 2) + 1;
    return true;
}

inline unsigned column_code(const std::uint8_t* a, const std::uint8_t* b, const std::uint8_t* c, const std::uint8_t* d,
                            std::size_t i) {
    return a[i] | b[i] << 1 | c[i] << 2 | d[i] << 3;
}

inline std::uint64_t load8(const std::uint8_t* p) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    return w;
}

// Inside the surface and far outside it, long stretches of a row are one value. These
// tests let the loops over a row's span step 8 samples at a time through such stretches.
constexpr std::uint64_t kAllOnes = 0x0101010101010101ull;

// Bytes [i, i+9) of rows a..d all equal row a's byte i: cells i..i+7 are trivial.
inline bool eight_trivial_cells(const std::uint8_t* a, const std::uint8_t* b, const std::uint8_t* c,
                                const std::uint8_t* d, std::size_t i) {
    const std::uint64_t v = a[i] ? kAllOnes : 0;
    return ((load8(a + i) ^ v) | (load8(a + i + 1) ^ v) | (load8(b + i) ^ v) | (load8(b + i + 1) ^ v) |
            (load8(c + i) ^ v) | (load8(c + i + 1) ^ v) | (load8(d + i) ^ v) | (load8(d + i + 1) ^ v)) == 0;
}

// Bits of a plane: in the planes that have RowInfo, a row without crossings is uniform and
// is filled without reading the volume.
template <class T>
void fill_plane_bits(const T* plane, const RowInfo* rows, std::size_t nx, std::size_t ny, T threshold,
                     std::uint8_t* bits) {
    for (std::size_t j = 0; j < ny; ++j) {
        if (rows && rows[j].first == kEmptyRow)
            std::memset(bits + j * nx, rows[j].uniform_bit, nx);
        else
            compute_bits(plane + j * nx, nx, threshold, bits + j * nx);
    }
}

// Contiguous split of [0, n) into `parts` ranges with about equal sums of cost.
std::vector<std::size_t> balanced_split(const std::vector<double>& cost, unsigned parts) {
    double total = 0;
    for (double c : cost) total += c;
    std::vector<std::size_t> cuts{0};
    double acc = 0;
    std::size_t i = 0;
    for (unsigned p = 1; p < parts; ++p) {
        const double target = total * p / parts;
        while (i < cost.size() && acc + cost[i] / 2 < target) acc += cost[i++];
        cuts.push_back(std::max(i, cuts.back()));
    }
    cuts.push_back(cost.size());
    return cuts;
}

// ---------------------------------------------------------------- generate

struct EdgePlane {  // per sample of one plane: crossed-edge code and first local vertex id
    std::vector<std::uint8_t> code;
    std::vector<std::uint32_t> id;
};

constexpr std::uint8_t kCodeCount[8] = {0, 1, 1, 2, 1, 2, 2, 3};

inline std::uint32_t edge_id(const EdgePlane& plane, std::size_t sample, unsigned axis) {
    const unsigned code = plane.code[sample];
    const unsigned offset = axis == 0 ? 0 : axis == 1 ? (code & 1) : (code & 1) + (code >> 1 & 1);
    return plane.id[sample] + offset;
}

template <class T>
class Generator {
public:
    Generator(const CpuChunkPlan& plan, const VolumeView& volume, const Options& options, const MeshOut& out,
              T threshold)
        : plan_(plan),
          options_(options),
          out_(out),
          threshold_(threshold),
          data_(static_cast<const T*>(volume.data)),
          vertex_(volume, options.iso, options.inside_below) {
        nx_ = volume.dims[0];
        ny_ = volume.dims[1];
        nz_ = volume.dims[2];
        const std::size_t plane = nx_ * ny_;
        for (auto& b : bits_) b.resize(plane);
        for (auto& e : edges_) {
            e.code.resize(plane);
            e.id.resize(plane);
        }
    }

    // Meshes planes [a, b) of the range: vertices of sample planes a..b-1 and triangles of
    // cell planes a..b-1, reading ids of plane b as well.
    void run(std::size_t a, std::size_t b) {
        fill_bits(a, 0);
        if (a + 1 < nz_) fill_bits(a + 1, 1);
        if (a + 2 < nz_) fill_bits(a + 2, 2);
        build_edges(a, bits_[0].data(), a + 1 < nz_ ? bits_[1].data() : nullptr, edges_[0], true);
        for (std::size_t k = a; k < b; ++k) {
            const bool has_next = k + 1 < nz_;
            if (has_next) {
                build_edges(k + 1, bits_[1].data(), k + 2 < nz_ ? bits_[2].data() : nullptr, edges_[1], k + 1 < b);
                emit_triangles(k);
            }
            std::swap(edges_[0], edges_[1]);
            std::rotate(bits_, bits_ + 1, bits_ + 3);
            if (k + 3 < nz_ && k + 1 < b) fill_bits(k + 3, 2);
        }
    }

private:
    const RowInfo* meta_rows(std::size_t z) const {
        const std::size_t p = z - plan_.range.begin;
        return p < plan_.meta_planes ? plan_.rows.data() + p * ny_ : nullptr;
    }

    void fill_bits(std::size_t z, int slot) {
        fill_plane_bits(data_ + z * nx_ * ny_, meta_rows(z), nx_, ny_, threshold_, bits_[slot].data());
    }

    void build_edges(std::size_t z, const std::uint8_t* bits, const std::uint8_t* bits_up, EdgePlane& edges,
                     bool write_vertices) {
        const RowInfo* rows = meta_rows(z);
        const std::uint32_t* bases = plan_.vertex_base.data() + (z - plan_.range.begin) * ny_;
        for (std::size_t j = 0; j < ny_; ++j) {
            const RowInfo& info = rows[j];
            if (info.first == kEmptyRow) continue;
            const std::uint8_t* row = bits + j * nx_;
            const std::uint8_t* next_y = j + 1 < ny_ ? row + nx_ : nullptr;
            const std::uint8_t* next_z = bits_up ? bits_up + j * nx_ : nullptr;
            std::uint8_t* code = edges.code.data() + j * nx_;
            std::uint32_t* id = edges.id.data() + j * nx_;
            std::uint32_t next_id = bases[j];
            for (std::size_t i = info.first; i <= info.last; ++i) {
                if (i + 9 <= info.last && next_y && next_z && eight_trivial_cells(row, row, next_y, next_z, i)) {
                    std::memset(code + i, 0, 8);  // ids of samples without crossings are never read
                    i += 7;
                    continue;
                }
                unsigned c = i + 1 < nx_ ? row[i] ^ row[i + 1] : 0;
                if (next_y) c |= (row[i] ^ next_y[i]) << 1;
                if (next_z) c |= (row[i] ^ next_z[i]) << 2;
                code[i] = static_cast<std::uint8_t>(c);
                id[i] = next_id;
                next_id += kCodeCount[c];
            }
            if (!write_vertices) continue;
            for (std::size_t i = info.first; i <= info.last; ++i) {
                const unsigned c = code[i];
                if (c == 0) continue;
                for (unsigned axis = 0; axis < 3; ++axis)
                    if (c >> axis & 1) write_vertex(i, j, z, axis, edge_id(edges, j * nx_ + i, axis));
            }
        }
    }

    void write_vertex(std::size_t i, std::size_t j, std::size_t k, unsigned axis, std::uint32_t id) {
        const std::size_t at = 3 * static_cast<std::size_t>(id);
        vertex_(i, j, k, axis, out_.positions + at, out_.normals ? out_.normals + at : nullptr);
    }

    void emit_triangles(std::size_t k) {
        const RowInfo* rows = meta_rows(k);
        const std::uint64_t* tri_base = plan_.triangle_base.data() + (k - plan_.range.begin) * ny_;
        const std::uint8_t* plane0 = bits_[0].data();
        const std::uint8_t* plane1 = bits_[1].data();
        const bool flip = options_.inside_below;
        for (std::size_t j = 0; j + 1 < ny_; ++j) {
            std::size_t begin, end;
            if (!cell_span(rows[j], rows[j + 1], nx_, begin, end)) continue;
            const std::uint8_t *a = plane0 + j * nx_, *b = a + nx_, *c = plane1 + j * nx_, *d = c + nx_;
            std::uint32_t* out = out_.indices + 3 * tri_base[j];
            for (std::size_t i = begin; i < end; ++i) {
                if (i + 9 <= end && eight_trivial_cells(a, b, c, d, i)) {
                    i += 7;
                    continue;
                }
                const unsigned pair = column_code(a, b, c, d, i) | column_code(a, b, c, d, i + 1) << 4;
                const CaseEntry& entry = kCaseTable[kColumnPairToCase[pair]];
                for (unsigned t = 0; t < entry.count; ++t) {
                    std::uint32_t v[3];
                    for (unsigned e = 0; e < 3; ++e) {
                        const CellEdge& edge = kCellEdge[entry.edges[3 * t + e]];
                        const EdgePlane& plane = edge.dz ? edges_[1] : edges_[0];
                        v[e] = out_.vertex_base + edge_id(plane, (j + edge.dy) * nx_ + i + edge.dx, edge.axis);
                    }
                    out[0] = v[0];
                    out[1] = flip ? v[2] : v[1];
                    out[2] = flip ? v[1] : v[2];
                    out += 3;
                }
            }
        }
    }

    const CpuChunkPlan& plan_;
    const Options& options_;
    MeshOut out_;
    T threshold_;
    const T* data_;
    EdgeVertex<T> vertex_;
    std::size_t nx_, ny_, nz_;
    std::vector<std::uint8_t> bits_[3];
    EdgePlane edges_[2];
};

template <class T>
void classify_planes(const CpuChunkPlan& plan, RowInfo* rows, const VolumeView& volume, T threshold,
                     std::size_t a, std::size_t b) {
    const std::size_t nx = volume.dims[0], ny = volume.dims[1], nz = volume.dims[2], plane = nx * ny;
    const T* data = static_cast<const T*>(volume.data);
    std::vector<std::uint8_t> here(plane), up(plane);
    if (compute_bits(data + a * plane, plane, threshold, here.data())) throw_nan(a);
    for (std::size_t k = a; k < b; ++k) {
        const bool has_up = k + 1 < nz;
        if (has_up && compute_bits(data + (k + 1) * plane, plane, threshold, up.data())) throw_nan(k + 1);
        RowInfo* row_info = rows + (k - plan.range.begin) * ny;
        for (std::size_t j = 0; j < ny; ++j)
            classify_row(here.data() + j * nx, j + 1 < ny ? here.data() + (j + 1) * nx : nullptr,
                         has_up ? up.data() + j * nx : nullptr, nx, row_info[j]);
        if (has_up && k < plan.range.end) {
            for (std::size_t j = 0; j + 1 < ny; ++j) {
                std::size_t begin, end;
                if (!cell_span(row_info[j], row_info[j + 1], nx, begin, end)) continue;
                const std::uint8_t *ra = here.data() + j * nx, *rb = ra + nx, *rc = up.data() + j * nx, *rd = rc + nx;
                std::uint32_t count = 0;
                for (std::size_t i = begin; i < end; ++i) {
                    if (i + 9 <= end && eight_trivial_cells(ra, rb, rc, rd, i)) {
                        i += 7;
                        continue;
                    }
                    const unsigned pair = column_code(ra, rb, rc, rd, i) | column_code(ra, rb, rc, rd, i + 1) << 4;
                    count += kCaseTable[kColumnPairToCase[pair]].count;
                }
                row_info[j].triangles = count;
            }
        }
        std::swap(here, up);
    }
}

std::vector<std::size_t> even_split(std::size_t n, unsigned parts) {
    std::vector<std::size_t> cuts(parts + 1);
    for (unsigned p = 0; p <= parts; ++p) cuts[p] = n * p / parts;
    return cuts;
}

}  // namespace

void validate_volume(const VolumeView& volume) {
    for (int d = 0; d < 3; ++d)
        if (volume.dims[d] < 2)
            throw Error("volume dimension " + std::string(1, "xyz"[d]) + " is " + std::to_string(volume.dims[d]) +
                        "; marching cubes needs at least 2 samples along every axis");
    checked_volume_bytes(volume.dims, volume.type);
    if (!volume.data) throw Error("volume has no data");
    for (int d = 0; d < 3; ++d)
        if (!(volume.spacing[d] > 0) || !std::isfinite(volume.spacing[d]) || !std::isfinite(volume.origin[d]))
            throw Error("volume spacing must be positive and finite, origin finite");
}

CpuChunkPlan cpu_classify(const VolumeView& volume, const Options& options, ZRange range, unsigned threads) {
    const auto t0 = Clock::now();
    CpuChunkPlan plan;
    plan.range = range;
    const std::size_t ny = volume.dims[1], nz = volume.dims[2];
    dispatch_scalar(volume.type, [&](auto tag) {
        using T = decltype(tag);
        const Threshold<T> threshold = make_threshold<T>(options.iso);
        if (threshold.uniform != Uniform::Mixed) {
            plan.uniform = true;
            return;
        }
        plan.meta_planes = std::min(range.end + 1, nz) - range.begin;
        plan.rows.assign(plan.meta_planes * ny, RowInfo{});
        const unsigned workers = static_cast<unsigned>(std::min<std::size_t>(std::max(threads, 1u), plan.meta_planes));
        const auto cuts = even_split(plan.meta_planes, workers);
        run_workers(workers, [&](unsigned w) {
            classify_planes<T>(plan, plan.rows.data(), volume, threshold.value, range.begin + cuts[w],
                               range.begin + cuts[w + 1]);
        });
    });
    if (plan.uniform) return plan;
    const auto t1 = Clock::now();
    plan.classify_seconds = std::chrono::duration<double>(t1 - t0).count();

    // Scan: exclusive prefix sums of the row counts give every vertex and triangle its index.
    plan.vertex_base.resize(plan.rows.size());
    plan.triangle_base.resize(plan.rows.size());
    std::uint64_t vertices = 0, triangles = 0;
    const std::size_t owned_rows = (range.end - range.begin) * ny;
    for (std::size_t r = 0; r < plan.rows.size(); ++r) {
        if (r == owned_rows) plan.vertices = vertices;
        if (vertices > std::numeric_limits<std::uint32_t>::max())
            throw Error("the mesh would have more than 2^32-1 vertices; 32-bit indices cannot address it "
                        "(mesh a sub-volume or a coarser volume)");
        plan.vertex_base[r] = static_cast<std::uint32_t>(vertices);
        plan.triangle_base[r] = triangles;
        vertices += plan.rows[r].vertices;
        triangles += plan.rows[r].triangles;
    }
    if (owned_rows == plan.rows.size()) plan.vertices = vertices;
    if (vertices > std::numeric_limits<std::uint32_t>::max())
        throw Error("the mesh would have more than 2^32-1 vertices; 32-bit indices cannot address it "
                    "(mesh a sub-volume or a coarser volume)");
    plan.triangles = triangles;
    plan.scan_seconds = seconds_since(t1);
    return plan;
}

void cpu_generate(const CpuChunkPlan& plan, const VolumeView& volume, const Options& options, unsigned threads,
                  const MeshOut& out) {
    if (plan.uniform || plan.triangles == 0) return;
    const std::size_t ny = volume.dims[1], planes = plan.range.end - plan.range.begin;
    // Balance by work, not planes: a plane costs its bits plus its vertices and triangles.
    std::vector<double> cost(planes, 0.0);
    for (std::size_t p = 0; p < planes; ++p) {
        double c = static_cast<double>(volume.dims[0] * ny) / 16;
        for (std::size_t j = 0; j < ny; ++j) {
            const RowInfo& r = plan.rows[p * ny + j];
            c += 24.0 * r.vertices + 4.0 * r.triangles + (r.first == kEmptyRow ? 0 : volume.dims[0] / 8.0);
        }
        cost[p] = c;
    }
    const unsigned workers = static_cast<unsigned>(std::min<std::size_t>(std::max(threads, 1u), planes));
    const auto cuts = balanced_split(cost, workers);
    dispatch_scalar(volume.type, [&](auto tag) {
        using T = decltype(tag);
        const T threshold = make_threshold<T>(options.iso).value;
        run_workers(workers, [&](unsigned w) {
            if (cuts[w] == cuts[w + 1]) return;
            Generator<T> generator(plan, volume, options, out, threshold);
            generator.run(plan.range.begin + cuts[w], plan.range.begin + cuts[w + 1]);
        });
    });
}

Mesh cpu_extract(const VolumeView& volume, const Options& options, Stats& stats) {
    const auto t0 = Clock::now();
    validate_volume(volume);
    const unsigned threads = resolve_threads(options.threads);
    stats.backend = Backend::Cpu;
    stats.threads = threads;

    CpuChunkPlan plan = cpu_classify(volume, options, ZRange{0, volume.dims[2]}, threads);
    stats.times.classify = plan.classify_seconds;
    stats.times.scan = plan.scan_seconds;

    // Output allocation counts toward generate: it is the first write of the output.
    const auto t = Clock::now();
    Mesh mesh;
    mesh.positions.resize(3 * plan.vertices);
    if (options.normals) mesh.normals.resize(3 * plan.vertices);
    mesh.indices.resize(3 * plan.triangles);

    cpu_generate(plan, volume, options, threads,
                 MeshOut{mesh.positions.data(), options.normals ? mesh.normals.data() : nullptr, mesh.indices.data(), 0});
    stats.times.generate = seconds_since(t);
    stats.times.total = seconds_since(t0);

    DeviceStats cpu;
    cpu.name = "cpu";
    cpu.chunks = 1;
    cpu.voxels = volume.dims[0] * volume.dims[1] * volume.dims[2];
    cpu.wall_s = stats.times.total;
    stats.devices.push_back(cpu);
    return mesh;
}

unsigned resolve_threads(unsigned requested) {
    if (requested > 0) return requested;
    const unsigned hw = std::thread::hardware_concurrency();
    return hw > 0 ? hw : 1;
}

}  // namespace voxmesh::detail
