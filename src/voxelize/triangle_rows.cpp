#include "voxelize/triangle_rows.hpp"

#include "core/row_packer.hpp"  // use_avx2, VOXMESH_X86_DISPATCH

#include <algorithm>
#include <cmath>
#include <limits>

#ifdef VOXMESH_X86_DISPATCH
#include <immintrin.h>
#endif

namespace voxmesh::detail {

namespace {

// 1 / slope, or 0 where the side is parallel to x. A slope however small still counts: a
// cut-off there dropped its term, up to some 1e-9 x the row's length, from the bound.
double inverse_slope(double slope) { return slope != 0 ? 1.0 / slope : 0.0; }

}  // namespace

GridTriangle grid_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    GridTriangle t;
    t.v = {a, b, c};
    t.edge = {sub(b, a), sub(c, b), sub(a, c)};
    std::array<double, 3> len2{};
    for (int e = 0; e < 3; ++e) len2[e] = dot(t.edge[e], t.edge[e]);
    // n = edge[i] x edge[i + 1] for any i; the two edges at the corner facing the longest
    // edge give it with the least rounding (their angle is the triangle's widest).
    const int longest = static_cast<int>(std::max_element(len2.begin(), len2.end()) - len2.begin());
    t.n = cross(t.edge[(longest + 1) % 3], t.edge[(longest + 2) % 3]);
    t.n2 = dot(t.n, t.n);
    // A triangle narrower than 1e-8 of its length (|n| / longest edge is its least height),
    // or so small that 1 / |n|^2 would overflow, is measured by its edges alone, as one with
    // no area: that is off by at most that height, while its normal's direction, rounding
    // noise for corners collinear in the model's floats, could put a sample's height over a
    // plane the triangle does not have anywhere up to the band.
    if (!(t.n2 > 1e-16 * len2[longest] * len2[longest]) || !(t.n2 > 1e-300)) {
        t.n = {0, 0, 0};
        t.n2 = 0;
    }
    for (int e = 0; e < 3; ++e) {
        t.inv_len2[e] = len2[e] > 0 ? 1.0 / len2[e] : 0.0;
        t.out[e] = cross(t.n, t.edge[e]);
        t.out_len[e] = std::sqrt(t.n2) * std::sqrt(len2[e]);  // |n x edge| = |n| |edge|: |out|^2 can underflow
        t.inv_out_x[e] = inverse_slope(t.out[e][0]);
    }
    t.inv_n_x = inverse_slope(t.n[0]);
    return t;
}

TrianglePlane::TrianglePlane(const GridTriangle& t, double k, double reach) : flat_(!(t.n2 > 0)) {
    for (int e = 0; e < 3; ++e) {
        const Vec3 &v = t.v[e], &edge = t.edge[e], &out = t.out[e];
        Edge& r = e_[e];
        r.x0 = v[0];
        r.y0 = v[1];
        r.fz = k - v[2];
        r.ex = edge[0];
        r.ey = edge[1];
        r.ez = edge[2];
        r.ez_part = edge[2] * r.fz;
        r.inv_len2 = t.inv_len2[e];
        if (flat_) {  // no plane, no sides: the nearest point is on an edge, any of the three
            r.out_x = r.out_y = 0;
            r.out_z_part = -1;
            continue;
        }
        r.out_x = out[0];
        r.out_y = out[1];
        r.out_z_part = out[2] * r.fz;
        least_[e] = -reach * t.out_len[e];
        inv_out_x_[e] = t.inv_out_x[e];
    }
    if (flat_) return;
    n_x_ = t.n[0];
    n_y_ = t.n[1];
    plane_z_part_ = t.n[2] * (k - t.v[0][2]);
    inv_n2_ = 1.0 / t.n2;
    most_ = reach * std::sqrt(t.n2);
    inv_n_x_ = t.inv_n_x;
    a_x_ = t.v[0][0];
    a_y_ = t.v[0][1];
}

bool TrianglePlane::narrow(double j, std::size_t nx, std::size_t& xa, std::size_t& xb, Row& row) const {
    for (int e = 0; e < 3; ++e) {
        const Edge& r = e_[e];
        row.fy[e] = j - r.y0;
        row.side_yz[e] = r.out_y * row.fy[e] + r.out_z_part;
        row.along_yz[e] = r.ey * row.fy[e] + r.ez_part;
    }
    row.plane_yz = n_y_ * (j - a_y_) + plane_z_part_;
    if (flat_) return xa < xb;
    double lo = double(xa), hi = double(xb) - 1;
    // A sample within reach of the triangle is within reach of its side of each edge ...
    for (int e = 0; e < 3; ++e) {
        if (inv_out_x_[e] == 0) {
            if (row.side_yz[e] < least_[e]) return false;
            continue;
        }
        const double x = e_[e].x0 + (least_[e] - row.side_yz[e]) * inv_out_x_[e];
        if (e_[e].out_x > 0)
            lo = std::max(lo, x);
        else
            hi = std::min(hi, x);
    }
    // ... and of its plane.
    if (inv_n_x_ == 0) {
        if (std::abs(row.plane_yz) > most_) return false;
    } else {
        const double u = a_x_ + (-most_ - row.plane_yz) * inv_n_x_, w = a_x_ + (most_ - row.plane_yz) * inv_n_x_;
        lo = std::max(lo, std::min(u, w));
        hi = std::min(hi, std::max(u, w));
    }
    if (!(lo <= hi)) return false;
    whole_range(lo, hi, nx, xa, xb);
    return xa < xb;
}

namespace {

using Edge = TrianglePlane::Edge;
using Row = TrianglePlane::Row;

// Every edge's segment distance is computed and kept only where the sample lies beyond that
// edge. Over the triangle (beyond no edge) the distance is the plane's; off it, the nearest
// point is on an edge the sample lies beyond (the nearest boundary point of a convex polygon
// from outside faces the point). The AVX2 copy below does the same operations in the same
// order, lane by lane (no FMA), so both give the same bits.
double beyond_edge(const Edge& e, double fy, double side_yz, double along_yz, double x) {
    const double fx = x - e.x0;
    const double side = e.out_x * fx + side_yz;
    double t = (e.ex * fx + along_yz) * e.inv_len2;
    t = t > 0.0 ? t : 0.0;
    t = t < 1.0 ? t : 1.0;
    const double dx = fx - t * e.ex, dy = fy - t * e.ey, dz = e.fz - t * e.ez;
    const double d2 = dx * dx + dy * dy + dz * dz;
    return side < 0 ? d2 : std::numeric_limits<double>::infinity();
}

struct PlaneTerms {
    double n_x, inv_n2;
};

void lower_portable(const std::array<Edge, 3>& e, PlaneTerms p, const Row& row, std::size_t xa, std::size_t xb,
                    float* samples) {
    for (std::size_t i = xa; i < xb; ++i) {
        const double x = double(i);
        const double d0 = beyond_edge(e[0], row.fy[0], row.side_yz[0], row.along_yz[0], x);
        const double d1 = beyond_edge(e[1], row.fy[1], row.side_yz[1], row.along_yz[1], x);
        const double d2 = beyond_edge(e[2], row.fy[2], row.side_yz[2], row.along_yz[2], x);
        double off = d0 < d1 ? d0 : d1;
        off = off < d2 ? off : d2;
        const double height = p.n_x * (x - e[0].x0) + row.plane_yz;
        const double over = height * height * p.inv_n2;
        const float d = static_cast<float>(off < std::numeric_limits<double>::infinity() ? off : over);
        samples[i] = d < samples[i] ? d : samples[i];
    }
}

#ifdef VOXMESH_X86_DISPATCH
#define VOXMESH_AVX2 __attribute__((target("avx2")))

// One edge's terms in four lanes, set once per row.
struct EdgeLanes {
    __m256d x0, out_x, side_yz, ex, along_yz, inv_len2, fy, ey, fz, ez;
};

VOXMESH_AVX2 inline EdgeLanes edge_lanes(const Edge& e, double fy, double side_yz, double along_yz) {
    return {_mm256_set1_pd(e.x0), _mm256_set1_pd(e.out_x), _mm256_set1_pd(side_yz), _mm256_set1_pd(e.ex),
            _mm256_set1_pd(along_yz), _mm256_set1_pd(e.inv_len2), _mm256_set1_pd(fy), _mm256_set1_pd(e.ey),
            _mm256_set1_pd(e.fz), _mm256_set1_pd(e.ez)};
}

VOXMESH_AVX2 inline __m256d beyond_edge_avx2(const EdgeLanes& e, __m256d x) {
    const __m256d fx = _mm256_sub_pd(x, e.x0);
    const __m256d side = _mm256_add_pd(_mm256_mul_pd(e.out_x, fx), e.side_yz);
    __m256d t = _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(e.ex, fx), e.along_yz), e.inv_len2);
    t = _mm256_max_pd(t, _mm256_setzero_pd());  // t > 0 ? t : 0 (t is finite)
    t = _mm256_min_pd(t, _mm256_set1_pd(1.0));
    const __m256d dx = _mm256_sub_pd(fx, _mm256_mul_pd(t, e.ex));
    const __m256d dy = _mm256_sub_pd(e.fy, _mm256_mul_pd(t, e.ey));
    const __m256d dz = _mm256_sub_pd(e.fz, _mm256_mul_pd(t, e.ez));
    const __m256d d2 =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
    const __m256d beyond = _mm256_cmp_pd(side, _mm256_setzero_pd(), _CMP_LT_OQ);
    return _mm256_blendv_pd(_mm256_set1_pd(std::numeric_limits<double>::infinity()), d2, beyond);
}

// Four samples a step from xa; a step that would pass nx is moved back to end there (the
// samples it repeats take the same minimum again). Rows shorter than four go portable.
VOXMESH_AVX2 void lower_avx2(const std::array<Edge, 3>& e, PlaneTerms p, const Row& row, std::size_t xa,
                             std::size_t xb, std::size_t nx, float* samples) {
    if (nx < 4) return lower_portable(e, p, row, xa, xb, samples);
    const EdgeLanes e0 = edge_lanes(e[0], row.fy[0], row.side_yz[0], row.along_yz[0]);
    const EdgeLanes e1 = edge_lanes(e[1], row.fy[1], row.side_yz[1], row.along_yz[1]);
    const EdgeLanes e2 = edge_lanes(e[2], row.fy[2], row.side_yz[2], row.along_yz[2]);
    const __m256d steps = _mm256_set_pd(3, 2, 1, 0), none = _mm256_set1_pd(std::numeric_limits<double>::infinity());
    const __m256d n_x = _mm256_set1_pd(p.n_x), plane_yz = _mm256_set1_pd(row.plane_yz),
                  inv_n2 = _mm256_set1_pd(p.inv_n2);
    for (std::size_t i = xa; i < xb; i += 4) {
        const std::size_t at = std::min(i, nx - 4);
        const __m256d x = _mm256_add_pd(_mm256_set1_pd(double(at)), steps);
        const __m256d d0 = beyond_edge_avx2(e0, x), d1 = beyond_edge_avx2(e1, x), d2 = beyond_edge_avx2(e2, x);
        const __m256d off = _mm256_min_pd(_mm256_min_pd(d0, d1), d2);  // a < b ? a : b, as above
        const __m256d height = _mm256_add_pd(_mm256_mul_pd(n_x, _mm256_sub_pd(x, e0.x0)), plane_yz);
        const __m256d over = _mm256_mul_pd(_mm256_mul_pd(height, height), inv_n2);
        const __m256d d = _mm256_blendv_pd(over, off, _mm256_cmp_pd(off, none, _CMP_LT_OQ));
        const __m128 old = _mm_loadu_ps(samples + at);
        _mm_storeu_ps(samples + at, _mm_min_ps(_mm256_cvtpd_ps(d), old));
    }
}
#endif

}  // namespace

void TrianglePlane::lower(const Row& row, std::size_t xa, std::size_t xb, std::size_t nx, float* samples) const {
    const PlaneTerms p{n_x_, inv_n2_};
#ifdef VOXMESH_X86_DISPATCH
    static const bool avx2 = use_avx2();
    if (avx2) return lower_avx2(e_, p, row, xa, xb, nx, samples);
#endif
    (void)nx;
    lower_portable(e_, p, row, xa, xb, samples);
}

}  // namespace voxmesh::detail
