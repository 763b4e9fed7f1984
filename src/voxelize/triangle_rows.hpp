// The voxelizer's distance pass, one triangle and one row of samples at a time.
//
// Along a row (y = j, z = k) every term of a sample's distance to a triangle is linear in
// the sample's x: its side of each edge, its height over the plane, its position along each
// edge; and their constant parts are linear in j within a z plane. A plane computes what
// depends on k once, a row what depends on j, and the samples then need a few multiplies
// each and no branch, so the loop runs four samples a step with AVX2. A fan of slivers (a
// cone of 20000 segments) puts a sample within the band of hundreds of triangles, each of
// which must be measured, in rows of some six samples: both the rows and the samples must
// be cheap.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

namespace voxmesh::detail {

using Vec3 = std::array<double, 3>;

inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// The whole numbers in [lo, hi] (finite), clipped to [0, n): [first, past). Truncation instead
// of std::ceil and std::floor, which are calls on x86-64 without SSE4.1: a fanned model asks
// this for tens of millions of rows.
inline void whole_range(double lo, double hi, std::size_t n, std::size_t& first, std::size_t& past) {
    const double l = std::clamp(lo, -1.0, double(n)), h = std::clamp(hi, -1.0, double(n));
    auto i = static_cast<std::int64_t>(l), k = static_cast<std::int64_t>(h);  // towards zero
    if (double(i) < l) ++i;
    if (double(k) > h) --k;
    first = static_cast<std::size_t>(std::clamp<std::int64_t>(i, 0, std::int64_t(n)));
    past = static_cast<std::size_t>(std::clamp<std::int64_t>(k + 1, 0, std::int64_t(n)));
}

// A triangle in grid coordinates, with what every row near it uses.
struct GridTriangle {
    std::array<Vec3, 3> v{};     // corners a, b, c
    Vec3 n{};                    // (b - a) x (c - a)
    double n2 = 0;               // |n|^2; n and n2 are 0 for a triangle measured as one with
                                 // no area (collinear corners, or nearly: grid_triangle)
    std::array<Vec3, 3> edge{};  // b - a, c - b, a - c: edge e starts at v[e]
    std::array<Vec3, 3> out{};   // n x edge: its dot with p - v[e] is negative beyond edge e
    std::array<double, 3> inv_len2{};  // 1 / |edge|^2 (0 for an edge of no length)
    std::array<double, 3> out_len{};   // |out| = |n| |edge|
    // 1 / out[e][0] and 1 / n[0], for the x where a row meets a side; 0 where the side is
    // parallel to x.
    std::array<double, 3> inv_out_x{};
    double inv_n_x = 0;
};

GridTriangle grid_triangle(const Vec3& a, const Vec3& b, const Vec3& c);

// One triangle's rows in the z plane k: their samples' squared distances to it.
class TrianglePlane {
public:
    // `reach`: how far from the triangle a sample must be measured (the band, a little over).
    TrianglePlane(const GridTriangle& t, double k, double reach);

    // What a row's samples use, per edge e (starting at corner v):
    //   side  = out_x (x - x0) + out_y (j - v.y) + out_z (k - v.z)   (< 0: beyond the edge)
    //   along = edge . (p - v) / |edge|^2, clamped to [0, 1]
    // and the plane's height n . (p - a): their parts that do not depend on x.
    struct Row {
        std::array<double, 3> fy, side_yz, along_yz;
        double plane_yz;
    };

    // Sets `row` up for row j and narrows [xa, xb) to its samples that can lie within reach
    // of the triangle (within reach of its plane and of each edge's side): a superset, so
    // narrowing changes no distance. False where none can.
    bool narrow(double j, std::size_t nx, std::size_t& xa, std::size_t& xb, Row& row) const;

    // samples[i] = min(samples[i], squared distance from (i, j, k) to the triangle) for i in
    // [xa, xb), and maybe for other i < nx: any sample may take a triangle's exact distance,
    // and one outside what `narrow` leaves is farther than `reach`, so it changes nothing
    // there; the AVX2 copy runs whole steps of four samples.
    void lower(const Row& row, std::size_t xa, std::size_t xb, std::size_t nx, float* samples) const;

    struct Edge {
        double x0, y0, fz;                     // the edge's start x and y; k from its start z
        double out_x, out_y, out_z_part;       // out_z_part = out_z * fz
        double ex, ey, ez, ez_part, inv_len2;  // ez_part = ez * fz
    };

private:
    std::array<Edge, 3> e_{};
    double n_x_ = 0, n_y_ = 0, plane_z_part_ = 0, inv_n2_ = 0;
    // The x bounds: side e >= -reach |out_e| bounds x from below where out_x > 0, from above
    // where out_x < 0 (bound = x0 + (least - side_yz) / out_x); |height| <= reach |n| both.
    std::array<double, 3> least_{}, inv_out_x_{};
    double most_ = 0, inv_n_x_ = 0, a_x_ = 0, a_y_ = 0;
    bool flat_ = false;
};

}  // namespace voxmesh::detail
