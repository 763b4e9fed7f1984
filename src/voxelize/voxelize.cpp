// Triangle mesh -> volume. See include/voxmesh/voxelize.hpp for the rules.
//
// Two passes over z-slabs, one slab per worker, each writing only its own samples:
//  1. distance (Distance field only): every triangle near the slab updates the squared
//     distance of the samples within `band` voxels of its plane and box;
//  2. inside test: for every row (y, z) the crossings of the ray along +x with the mesh,
//     decided on a fixed-point lattice with exact integer predicates and a symbolic
//     perturbation of the ray, each signed by its triangle's orientation, sorted; a sample
//     is inside after an odd number of them (EvenOdd) or where their signed sum, the
//     winding number, is non-zero (NonZero).
// Every sample is a function of the mesh alone, so the result does not depend on threads.

#include <voxmesh/voxelize.hpp>

#include "core/dims_text.hpp"
#include "core/float_extent.hpp"
#include "core/mesh_arrays.hpp"
#include "core/out_of_memory.hpp"
#include "core/parallel.hpp"
#include "io/input_file.hpp"
#include "voxelize/triangle_rows.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

namespace voxmesh {

namespace {

constexpr int kFixedBits = 16;                  // lattice step 2^-16 voxel
constexpr double kFixedScale = 65536.0;         // 2^kFixedBits
constexpr std::size_t kMaxResolution = 4096;
constexpr std::size_t kMaxPadding = 256;
// Grid coordinates stay below 2^13, lattice coordinates below 2^29, so the 2x2
// determinants below (products of two differences) stay below 2^60: exact in int64.
constexpr std::size_t kMaxDim = std::size_t(1) << 13;

using detail::GridTriangle;
using detail::Vec3;
using detail::whole_range;

// A welded, validated triangle list.
struct Soup {
    std::vector<Vec3> points;                        // model coordinates, welded
    std::vector<std::array<std::uint32_t, 3>> tris;  // non-degenerate (three distinct ids), none cancelled
};

using Triangle = std::array<std::uint32_t, 3>;

// Coincident triangles (the same three corners) cancel as their crossings do: any two under
// EvenOdd (parity), two wound opposite ways under NonZero (winding). A face that two bodies
// share is such a pair: left in, it was a surface inside the union that the distance field
// measured to. What is left keeps the mesh's order, in the same storage (its peak stays the
// edge lists' below).
std::vector<Triangle> cancel_coincident(std::vector<Triangle> tris, FillRule fill) {
    struct Entry {
        Triangle corners;  // smallest id first, then the other two ascending
        int sign;          // +1 where (smallest, next, last) in the triangle's own order ascends
        std::size_t index;
    };
    std::vector<Entry> entries(tris.size());
    for (std::size_t i = 0; i < tris.size(); ++i) {
        const Triangle& t = tris[i];
        const int m = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
        const std::uint32_t b = t[(m + 1) % 3], c = t[(m + 2) % 3];
        entries[i] = {{t[m], std::min(b, c), std::max(b, c)}, b < c ? 1 : -1, i};
    }
    std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
        return x.corners != y.corners ? x.corners < y.corners : x.index < y.index;
    });
    std::vector<char> keep(tris.size(), 0);
    for (std::size_t i = 0; i < entries.size();) {
        std::size_t j = i;
        long net = 0;
        for (; j < entries.size() && entries[j].corners == entries[i].corners; ++j) net += entries[j].sign;
        if (fill == FillRule::EvenOdd) {
            if ((j - i) % 2) keep[entries[i].index] = 1;
        } else {
            const int sign = net > 0 ? 1 : -1;
            for (std::size_t k = i; k < j && net != 0; ++k)
                if (entries[k].sign == sign) keep[entries[k].index] = 1, net -= sign;
        }
        i = j;
    }
    std::size_t kept = 0;
    for (std::size_t i = 0; i < tris.size(); ++i)
        if (keep[i]) tris[kept++] = tris[i];
    tris.resize(kept);
    return tris;
}

Soup weld_and_check(const Mesh& mesh, FillRule fill) {
    detail::check_mesh_arrays(mesh, "voxelize: ");
    const std::size_t nv = mesh.vertex_count();
    if (mesh.indices.empty()) throw Error("voxelize: the mesh has no triangles");
    detail::check_finite_vertices(mesh.positions, "voxelize: ", "coordinate");

    // Weld by exact position: sort vertex ids by coordinates, equal runs share one id.
    std::vector<std::uint32_t> order(nv);
    std::iota(order.begin(), order.end(), 0u);
    const float* p = mesh.positions.data();
    auto key = [p](std::uint32_t v) { return std::array<float, 3>{p[3 * v], p[3 * v + 1], p[3 * v + 2]}; };
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
    Soup soup;
    std::vector<std::uint32_t> remap(nv);
    for (std::size_t i = 0; i < nv; ++i) {
        if (i == 0 || key(order[i]) != key(order[i - 1])) {
            const auto k = key(order[i]);
            soup.points.push_back({double(k[0]), double(k[1]), double(k[2])});
        }
        remap[order[i]] = static_cast<std::uint32_t>(soup.points.size() - 1);
    }

    std::vector<Triangle> tris;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const Triangle tri{remap[mesh.indices[3 * t]], remap[mesh.indices[3 * t + 1]], remap[mesh.indices[3 * t + 2]]};
        if (tri[0] != tri[1] && tri[1] != tri[2] && tri[2] != tri[0]) tris.push_back(tri);  // else no area, no edges
    }
    if (tris.empty()) throw Error("voxelize: every triangle of the mesh is degenerate (no area)");
    soup.tris = cancel_coincident(std::move(tris), fill);
    if (soup.tris.empty())
        throw Error(std::string("voxelize: every triangle of the mesh has a coincident one (the same corners") +
                    (fill == FillRule::NonZero ? ", wound the other way" : "") +
                    ") that cancels it: a two-sided sheet, which encloses nothing");
    if (soup.tris.size() > 0xffffffffull) throw Error("voxelize: the mesh has too many triangles (more than 2^32)");

    std::vector<std::uint64_t> edges, directed;  // directed: only NonZero needs the winding
    edges.reserve(3 * soup.tris.size());
    if (fill == FillRule::NonZero) directed.reserve(3 * soup.tris.size());
    for (const Triangle& tri : soup.tris)
        for (int e = 0; e < 3; ++e) {
            const std::uint64_t a = tri[e], b = tri[(e + 1) % 3];
            edges.push_back(a < b ? (a << 32 | b) : (b << 32 | a));
            if (fill == FillRule::NonZero) directed.push_back(a << 32 | b);
        }
    // The surface must be closed: every edge in an even number of triangles, two or, where
    // bodies share an edge or a face, four or more. An odd number is a hole (one) or a wall or
    // fin meeting the surface (three or more), across which inside and outside are undefined.
    std::sort(edges.begin(), edges.end());
    std::size_t open = 0, odd = 0;
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i == 1) ++open;
        else if ((j - i) % 2) ++odd;
        i = j;
    }
    if (open)
        throw Error("voxelize: the mesh is not closed: " + std::to_string(open) +
                    " edges belong to only one triangle (holes); a watertight mesh is needed to tell inside from outside");
    if (odd)
        throw Error("voxelize: the mesh is not closed: " + std::to_string(odd) +
                    " edges belong to an odd number of triangles, three or more (a wall or a fin meeting the surface); "
                    "a watertight mesh is needed to tell inside from outside");
    if (fill == FillRule::EvenOdd) return soup;
    // NonZero counts signed crossings: every edge must be used as often in one direction as in
    // the other (two triangles that agree on the winding, or two such pairs where bodies meet).
    std::sort(directed.begin(), directed.end());
    const auto uses = [&](std::uint64_t key) {
        const auto run = std::equal_range(directed.begin(), directed.end(), key);
        return static_cast<std::size_t>(run.second - run.first);
    };
    std::size_t unbalanced = 0;
    for (std::size_t i = 0; i < directed.size();) {
        std::size_t j = i;
        while (j < directed.size() && directed[j] == directed[i]) ++j;
        const std::uint64_t a = directed[i] >> 32, b = directed[i] & 0xffffffffu;
        const std::size_t backward = uses(b << 32 | a);
        if ((a < b || backward == 0) && j - i != backward) ++unbalanced;  // each edge counted once
        i = j;
    }
    if (unbalanced)
        throw Error("voxelize: the mesh is not consistently wound: " + std::to_string(unbalanced) +
                    " edges are used more often in one direction than in the other by their triangles, so the NonZero "
                    "fill rule cannot tell inside from outside; fix the winding, or use FillRule::EvenOdd (parity, which "
                    "ignores the winding)");
    return soup;
}

// Sign of orient(a, b, p) for the ray point p perturbed to p + (eps, eps^2) in (y, z).
// Antisymmetric in (a, b), never 0 unless a == b: both triangles at an edge see one answer.
int orient_sos(std::int64_t ay, std::int64_t az, std::int64_t by, std::int64_t bz, std::int64_t py,
               std::int64_t pz, std::int64_t& det) {
    det = (by - ay) * (pz - az) - (bz - az) * (py - ay);
    if (det != 0) return det > 0 ? 1 : -1;
    if (bz != az) return az > bz ? 1 : -1;
    if (by != ay) return by > ay ? 1 : -1;
    return 0;
}

struct Grid {
    std::array<std::size_t, 3> dims{};
    std::array<double, 3> origin{};
    double h = 1;
    Vec3 to_grid(const Vec3& p) const {
        return {(p[0] - origin[0]) / h, (p[1] - origin[1]) / h, (p[2] - origin[2]) / h};
    }
};

Grid make_grid(const Soup& soup, const VoxelizeOptions& options) {
    // The triangles' box: points[0] may be a vertex no triangle uses (a stray PLY vertex).
    Vec3 lo = soup.points[soup.tris[0][0]], hi = lo;
    for (const auto& tri : soup.tris)
        for (std::uint32_t v : tri)
            for (int d = 0; d < 3; ++d) {
                lo[d] = std::min(lo[d], soup.points[v][d]);
                hi[d] = std::max(hi[d], soup.points[v][d]);
            }
    const double longest = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    if (!(longest > 0) || !std::isfinite(longest)) throw Error("voxelize: the mesh has an empty bounding box");
    Grid g;
    const std::size_t n = options.resolution, pad = options.padding;
    g.h = longest / double(n);
    for (int d = 0; d < 3; ++d) {
        const double cells = (hi[d] - lo[d]) / g.h;
        const std::size_t m = std::clamp<std::size_t>(static_cast<std::size_t>(std::ceil(cells - 1e-6)), 1, n);
        g.dims[d] = m + 2 * pad;
        g.origin[d] = 0.5 * (lo[d] + hi[d]) - (0.5 * double(m - 1) + double(pad)) * g.h;
    }
    // Volumes are meshed to float vertices (extract and the readers refuse samples past
    // FLT_MAX): a model near the float limit plus padding must be refused here, not later.
    if (const int d = detail::axis_beyond_float(g.dims, {g.h, g.h, g.h}, g.origin); d >= 0)
        throw Error(std::string("voxelize: with padding ") + std::to_string(pad) + " the grid's samples along " +
                    "xyz"[d] + " reach beyond the range of float coordinates (about 3.4e38); "
                    "move the model nearer the origin or reduce the padding");
    return g;
}

// What the system can give now (MemAvailable, as the volume readers check; physical memory
// where unknown): a grid that fits in physical memory but not beside what else runs would
// swap, or meet the OOM killer, instead of being refused.
using io::available_memory;

std::size_t grid_bytes(const Grid& g, std::size_t sample_bytes) {
    return g.dims[0] * g.dims[1] * g.dims[2] * sample_bytes;  // < 2^41 (kMaxDim^3 * 4)
}

// Refuses a grid that cannot fit in the memory available, before allocating it: the volume
// is written in full, so overcommit would only defer the failure to the OOM killer.
void check_grid_memory(const Grid& g, const VoxelizeOptions& options, std::size_t sample_bytes) {
    const std::size_t bytes = grid_bytes(g, sample_bytes), available = available_memory();
    if (bytes > available)
        throw Error("voxelize: the " + detail::dims_text(g.dims) + " grid (resolution " + std::to_string(options.resolution) +
                    ", padding " + std::to_string(options.padding) + ") needs " + std::to_string(bytes) +
                    " bytes, more than the " + std::to_string(available) +
                    " bytes of memory available; use a lower resolution");
}

using Lattice = std::array<std::int64_t, 3>;

// A crossing of the ray: grid x, and the winding number's change there.
struct Hit {
    double x;
    int step;  // +1 through a triangle whose normal faces the ray (into an outward shell), else -1
    bool operator<(const Hit& o) const { return x < o.x || (x == o.x && step < o.step); }
};

// One row's crossings along +x, sorted.
void row_crossings(const std::vector<Lattice>& q, const std::vector<std::array<std::uint32_t, 3>>& tris,
                   const std::uint32_t* cand, std::size_t ncand, std::int64_t py, std::int64_t pz,
                   std::vector<Hit>& hits) {
    hits.clear();
    for (std::size_t c = 0; c < ncand; ++c) {
        const auto& t = tris[cand[c]];
        const Lattice &a = q[t[0]], &b = q[t[1]], &cc = q[t[2]];
        if (py < std::min({a[1], b[1], cc[1]}) || py > std::max({a[1], b[1], cc[1]})) continue;
        const std::int64_t area = (b[1] - a[1]) * (cc[2] - a[2]) - (b[2] - a[2]) * (cc[1] - a[1]);
        if (area == 0) continue;  // parallel to the ray: no crossing
        const int s = area > 0 ? 1 : -1;
        std::int64_t wc = 0, wa = 0, wb = 0;
        if (orient_sos(a[1], a[2], b[1], b[2], py, pz, wc) != s) continue;
        if (orient_sos(b[1], b[2], cc[1], cc[2], py, pz, wa) != s) continue;
        if (orient_sos(cc[1], cc[2], a[1], a[2], py, pz, wb) != s) continue;
        const double inv = 1.0 / double(area);
        const double x = (double(wa) * double(a[0]) + double(wb) * double(b[0]) + double(wc) * double(cc[0])) * inv;
        // area is the x component of the lattice triangle's normal (b - a) x (c - a), exact:
        // s says which way the triangle faces the ray.
        hits.push_back({x / kFixedScale, -s});
    }
    std::sort(hits.begin(), hits.end());
}

// One z plane's candidates sorted into its y rows. A crossing needs the row's point (py, pz)
// in the closed yz shadow of the triangle (the perturbed point tends to it), so py lies in the
// y range of the triangle's cut by the plane z = pz: each candidate is listed for the rows
// whose py lies in that range, widened to whole rows so rounding cannot drop one. Without
// this every row of a plane tested every triangle spanning the plane (a cone's side: all).
class PlaneRows {
public:
    void build(const std::vector<Lattice>& q, const std::vector<std::array<std::uint32_t, 3>>& tris,
               const std::uint32_t* cand, std::size_t ncand, std::int64_t pz, std::size_t ny) {
        const double step = kFixedScale;
        start_.assign(ny + 1, 0);
        spans_.clear();
        for (std::size_t c = 0; c < ncand; ++c) {
            const auto& t = tris[cand[c]];
            const Lattice &a = q[t[0]], &b = q[t[1]], &cc = q[t[2]];
            if ((b[1] - a[1]) * (cc[2] - a[2]) - (b[2] - a[2]) * (cc[1] - a[1]) == 0) continue;  // no crossing
            double lo = std::numeric_limits<double>::infinity(), hi = -lo;
            const Lattice* v[3] = {&a, &b, &cc};
            for (int e = 0; e < 3; ++e) {
                const Lattice &p = *v[e], &r = *v[(e + 1) % 3];
                if (p[2] == pz) {
                    lo = std::min(lo, double(p[1]));
                    hi = std::max(hi, double(p[1]));
                }
                if ((p[2] < pz && r[2] > pz) || (p[2] > pz && r[2] < pz)) {
                    const double y = double(p[1]) + double(pz - p[2]) * double(r[1] - p[1]) / double(r[2] - p[2]);
                    lo = std::min(lo, y);
                    hi = std::max(hi, y);
                }
            }
            if (!(lo <= hi)) continue;  // the plane misses it
            const double j0 = std::max(std::floor(lo / step), 0.0), j1 = std::min(std::ceil(hi / step), double(ny) - 1);
            if (j0 > j1) continue;
            spans_.push_back({cand[c], static_cast<std::uint32_t>(j0), static_cast<std::uint32_t>(j1)});
            for (auto j = static_cast<std::size_t>(j0); j <= static_cast<std::size_t>(j1); ++j) ++start_[j + 1];
        }
        for (std::size_t j = 0; j < ny; ++j) start_[j + 1] += start_[j];
        listed_.resize(start_[ny]);
        fill_.assign(start_.begin(), start_.end() - 1);
        for (const Span& s : spans_)  // in candidate order, as before
            for (std::size_t j = s.j0; j <= s.j1; ++j) listed_[fill_[j]++] = s.tri;
    }
    const std::uint32_t* row(std::size_t j) const { return listed_.data() + start_[j]; }
    std::size_t row_size(std::size_t j) const { return start_[j + 1] - start_[j]; }

private:
    struct Span {
        std::uint32_t tri, j0, j1;
    };
    std::vector<Span> spans_;
    std::vector<std::size_t> start_, fill_;
    std::vector<std::uint32_t> listed_;
};

// The bounding box (min, max) of the points of t whose coordinate `axis` lies in [lo, hi]:
// its vertices there and its edges' crossings of lo and hi (t is convex). False where none is.
bool box_in_slab(const GridTriangle& t, int axis, double lo, double hi, Vec3& min, Vec3& max) {
    const Vec3* v[3] = {&t.v[0], &t.v[1], &t.v[2]};
    min.fill(std::numeric_limits<double>::infinity());
    max.fill(-std::numeric_limits<double>::infinity());
    const auto take = [&](const Vec3& point) {
        for (int d = 0; d < 3; ++d) {
            min[d] = std::min(min[d], point[d]);
            max[d] = std::max(max[d], point[d]);
        }
    };
    for (int e = 0; e < 3; ++e) {
        const Vec3& p = *v[e];
        const Vec3& q = *v[(e + 1) % 3];
        if (p[axis] >= lo && p[axis] <= hi) take(p);
        for (const double bound : {lo, hi})
            if ((p[axis] - bound) * (q[axis] - bound) < 0) {
                const double s = (bound - p[axis]) / (q[axis] - p[axis]);
                take({p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1]), p[2] + s * (q[2] - p[2])});
            }
    }
    return min[0] <= max[0];
}

Volume voxelize_mesh(const Mesh& mesh, const VoxelizeOptions& options) {
    if (options.resolution < 2 || options.resolution > kMaxResolution)
        throw Error("voxelize: resolution " + std::to_string(options.resolution) + " is out of range (2.." +
                    std::to_string(kMaxResolution) + ")");
    if (options.padding > kMaxPadding)
        throw Error("voxelize: padding " + std::to_string(options.padding) + " is out of range (0.." +
                    std::to_string(kMaxPadding) + ")");
    const bool distance = options.field == VoxelField::Distance;
    if (distance && !(options.band >= 2 && options.band <= 1000))
        throw Error("voxelize: band must be between 2 and 1000 voxels");

    if (options.fill != FillRule::EvenOdd && options.fill != FillRule::NonZero)
        throw Error("voxelize: unknown fill rule " + std::to_string(static_cast<int>(options.fill)));
    const Soup soup = weld_and_check(mesh, options.fill);
    const Grid grid = make_grid(soup, options);
    const std::size_t nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
    static_assert(kMaxResolution + 2 * kMaxPadding <= kMaxDim);

    const ScalarType type = distance ? ScalarType::F32 : ScalarType::U8;
    check_grid_memory(grid, options, scalar_size(type));
    Volume volume = Volume::allocate(type, grid.dims);
    volume.spacing = {grid.h, grid.h, grid.h};
    volume.origin = grid.origin;

    // Grid coordinates (for distances) and lattice coordinates (for the inside test).
    std::vector<Vec3> gp(soup.points.size());
    std::vector<Lattice> q(soup.points.size());
    for (std::size_t i = 0; i < soup.points.size(); ++i) {
        gp[i] = grid.to_grid(soup.points[i]);
        for (int d = 0; d < 3; ++d) q[i][d] = std::llround(gp[i][d] * kFixedScale);
    }

    // Triangles per z row (CSR): those whose lattice z range contains the row's z.
    std::vector<std::size_t> row_start(nz + 1, 0);
    std::vector<std::uint32_t> row_tris;
    auto z_rows = [&](const std::array<std::uint32_t, 3>& t, std::size_t& k0, std::size_t& k1) {
        const std::int64_t zmin = std::min({q[t[0]][2], q[t[1]][2], q[t[2]][2]});
        const std::int64_t zmax = std::max({q[t[0]][2], q[t[1]][2], q[t[2]][2]});
        const std::int64_t step = std::int64_t(1) << kFixedBits;
        const std::int64_t lo = (zmin + step - 1) / step, hi = zmax / step;  // coordinates are >= 0
        k0 = static_cast<std::size_t>(std::max<std::int64_t>(lo, 0));
        k1 = static_cast<std::size_t>(std::min<std::int64_t>(hi + 1, std::int64_t(nz)));
    };
    {
        // Counted as +1 at a triangle's first row and -1 past its last, then summed twice: time
        // in triangles + rows, so that an oversized list is refused before it is built.
        std::vector<std::int64_t> change(nz + 1, 0);
        for (const auto& t : soup.tris) {
            std::size_t k0 = 0, k1 = 0;
            z_rows(t, k0, k1);
            if (k0 >= k1) continue;
            ++change[k0];
            --change[k1];
        }
        std::int64_t in_row = 0;
        for (std::size_t k = 0; k < nz; ++k) {
            in_row += change[k];
            row_start[k + 1] = row_start[k] + static_cast<std::size_t>(in_row);
        }
    }
    // Each triangle is listed once per z row it spans (< 2^32 triangles x kMaxDim rows, no
    // overflow): many tall triangles at a high resolution make that list larger than the grid.
    const std::size_t list_bytes = row_start[nz] * sizeof(std::uint32_t);
    const std::size_t available = available_memory();
    if (list_bytes > available - std::min(available, grid_bytes(grid, scalar_size(type))))
        throw Error("voxelize: the " + std::to_string(soup.tris.size()) + " triangles span " +
                    std::to_string(row_start[nz]) + " z rows in all at resolution " +
                    std::to_string(options.resolution) + "; their row lists (" + std::to_string(list_bytes) +
                    " bytes) and the grid do not fit in the memory available; use a lower resolution");
    row_tris.resize(row_start[nz]);
    {
        std::vector<std::size_t> fill(row_start.begin(), row_start.end() - 1);
        for (std::size_t i = 0; i < soup.tris.size(); ++i) {
            std::size_t k0 = 0, k1 = 0;
            z_rows(soup.tris[i], k0, k1);
            for (std::size_t k = k0; k < k1; ++k) row_tris[fill[k]++] = static_cast<std::uint32_t>(i);
        }
    }

    std::vector<GridTriangle> gtris;
    if (distance) {
        gtris.reserve(soup.tris.size());
        for (const auto& t : soup.tris) gtris.push_back(detail::grid_triangle(gp[t[0]], gp[t[1]], gp[t[2]]));
    }

    const double band = options.band, band2 = band * band;
    const unsigned workers =
        static_cast<unsigned>(std::min<std::size_t>(detail::running_threads(options.threads), nz));
    std::vector<std::size_t> inside_samples(workers, 0);
    detail::run_workers(workers, [&](unsigned w) {
        const auto [z0, z1] = detail::share_of(nz, w, workers);
        const std::size_t plane = nx * ny;
        float* dist = distance ? static_cast<float*>(volume.data) : nullptr;

        // Pass 1: squared distances (grid units) to the nearest triangle, capped at band^2.
        if (distance) {
            std::fill(dist + z0 * plane, dist + z1 * plane, static_cast<float>(band2));
            detail::TrianglePlane::Row terms;
            for (const GridTriangle& t : gtris) {
                const Vec3 &a = t.v[0], &b = t.v[1], &c = t.v[2];
                std::size_t i0, i1, j0, j1, k0, k1;
                whole_range(std::min({a[2], b[2], c[2]}) - band, std::max({a[2], b[2], c[2]}) + band, nz, k0, k1);
                k0 = std::max(k0, z0);
                k1 = std::min(k1, z1);
                if (k0 >= k1) continue;
                whole_range(std::min({a[1], b[1], c[1]}) - band, std::max({a[1], b[1], c[1]}) + band, ny, j0, j1);
                whole_range(std::min({a[0], b[0], c[0]}) - band, std::max({a[0], b[0], c[0]}) + band, nx, i0, i1);
                // A sample within `band` of a point q of the triangle has each coordinate
                // within `band` of q's: so its y and x lie within `band` of the y and x ranges
                // of the triangle's part in the plane's z slab. Without this a long thin
                // triangle lying across the axes (a fan in a cylinder's cap, a cone's side) was
                // scanned over its whole bounding box. TrianglePlane narrows each row further,
                // to within `band` of the plane and of each edge's side. A little beyond
                // `band`, for rounding: a superset of the samples, so the distances do not
                // change.
                const double slack = band + 1e-6;
                const bool flat = !(t.n2 > 0);
                for (std::size_t k = k0; k < k1; ++k) {
                    Vec3 z_min, z_max, y_min, y_max;
                    if (!box_in_slab(t, 2, double(k) - slack, double(k) + slack, z_min, z_max)) continue;
                    const detail::TrianglePlane rows(t, double(k), slack);
                    std::size_t ja = 0, jb = 0, za = 0, zb = 0;
                    whole_range(z_min[1] - slack, z_max[1] + slack, ny, ja, jb);
                    whole_range(z_min[0] - slack, z_max[0] + slack, nx, za, zb);
                    for (std::size_t j = std::max(j0, ja); j < std::min(j1, jb); ++j) {
                        std::size_t xa = std::max(i0, za), xb = std::min(i1, zb);
                        if (flat) {  // no sides to narrow the row by: the y slab's part instead
                            if (!box_in_slab(t, 1, double(j) - slack, double(j) + slack, y_min, y_max)) continue;
                            std::size_t ya = 0, yb = 0;
                            whole_range(y_min[0] - slack, y_max[0] + slack, nx, ya, yb);
                            xa = std::max(xa, ya);
                            xb = std::min(xb, yb);
                        }
                        if (xa >= xb) continue;
                        if (!rows.narrow(double(j), nx, xa, xb, terms)) continue;
                        rows.lower(terms, xa, xb, nx, dist + plane * k + nx * j);
                    }
                }
            }
        }

        // Pass 2: inside test per row, then the final sample values.
        std::vector<Hit> hits;
        PlaneRows rows;
        const bool nonzero = options.fill == FillRule::NonZero;
        std::size_t inside_here = 0;
        std::uint8_t* occ = distance ? nullptr : static_cast<std::uint8_t*>(volume.data);
        for (std::size_t k = z0; k < z1; ++k) {
            const std::int64_t pz = std::int64_t(k) << kFixedBits;
            rows.build(q, soup.tris, row_tris.data() + row_start[k], row_start[k + 1] - row_start[k], pz, ny);
            for (std::size_t j = 0; j < ny; ++j) {
                const std::int64_t py = std::int64_t(j) << kFixedBits;
                row_crossings(q, soup.tris, rows.row(j), rows.row_size(j), py, pz, hits);
                std::size_t passed = 0;
                int winding = 0;
                const std::size_t base = plane * k + nx * j;
                for (std::size_t i = 0; i < nx; ++i) {
                    for (; passed < hits.size() && hits[passed].x < double(i); ++passed) winding += hits[passed].step;
                    const bool inside = nonzero ? winding != 0 : passed % 2 == 1;
                    inside_here += inside;
                    if (distance) {
                        // Clamped: band * h can pass FLT_MAX (a model spanning most of the
                        // float range, a wide band) and double -> float out of range is UB.
                        // Only samples far from the surface reach it; the zero crossing stays.
                        const double d = std::min(std::sqrt(double(dist[base + i])) * grid.h, double(FLT_MAX));
                        dist[base + i] = static_cast<float>(inside ? d : -d);
                    } else {
                        occ[base + i] = inside ? 255 : 0;
                    }
                }
            }
        }
        inside_samples[w] = inside_here;
    });
    // Meshing back needs a sample inside: a flat model, or one thinner than a voxel everywhere,
    // would come back as an empty mesh with no word why.
    if (std::accumulate(inside_samples.begin(), inside_samples.end(), std::size_t{0}) == 0)
        throw Error("voxelize: no sample of the " + detail::dims_text(grid.dims) + " grid lies inside the mesh (it is flat, or thinner than a voxel of " +
                    std::to_string(grid.h) + " everywhere); raise the resolution");
    return volume;
}

}  // namespace

Volume voxelize(const Mesh& mesh, const VoxelizeOptions& options) {
    return detail::out_of_memory_as_error(
        [&] {
            return "voxelize: " + detail::out_of_memory_for(mesh) + " at resolution " +
                   std::to_string(options.resolution);
        },
        [&] { return voxelize_mesh(mesh, options); });
}

}  // namespace voxmesh
