// What every marching-cubes kernel shares: the sample and arithmetic types, and the vertices
// of a sample's crossed edges, computed with the formula of src/core/edge_vertex.hpp. The
// host puts this file in front of marching_cubes.cl and sculpt_blocks.cl when it builds them.
//
// Build options chosen by the host:
//   -DVOXEL_T=<uchar|char|ushort|short|uint|int|float|double>  the sample type
//   -DVOXEL_INTEGER   integer samples (differences taken exactly in long)
//   -DVOXEL_DOUBLE    double samples
//   -DUSE_FP64        the device has cl_khr_fp64: interpolate in double like the CPU engine

#pragma OPENCL FP_CONTRACT OFF

#ifdef USE_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
#define REAL_MIN DBL_MIN
#define REAL_MAX DBL_MAX
#else
typedef float real;
#define REAL_MIN FLT_MIN
#define REAL_MAX FLT_MAX
#endif

typedef VOXEL_T voxel;

#ifdef VOXEL_INTEGER
#define DIFF(hi, lo) ((real)((long)(hi) - (long)(lo)))
#else
#define DIFF(hi, lo) ((real)(hi) - (real)(lo))
#endif

// iso - v0. Without fp64, integer samples subtract from iso's integer part exactly and add
// its fraction, so that large integers keep their precision; float samples subtract from iso
// rounded to float, exactly where v is near it, and add what the rounding left (iso_frac), so
// that an iso between two floats still splits an edge between them where it lies.
#if defined(USE_FP64)
#define ISO_MINUS(v) (iso - (real)(v))
#elif defined(VOXEL_INTEGER)
#define ISO_MINUS(v) ((float)(iso_int - (long)(v)) + iso_frac)
#else
#define ISO_MINUS(v) ((iso - (real)(v)) + iso_frac)
#endif

// t = (iso - v0) / (v1 - v0). The difference can overflow for double samples near ±DBL_MAX,
// or float ones near ±FLT_MAX without fp64, giving inf / inf = NaN: there it is taken on
// halves, as the CPU engine does for double samples. Elsewhere it cannot, and the check
// would cost float volumes 1-2 % of generate on PoCL.
#if defined(VOXEL_INTEGER) || (defined(USE_FP64) && !defined(VOXEL_DOUBLE))
#define EDGE_T(v0, v1) (ISO_MINUS(v0) / DIFF(v1, v0))
#else
#define EDGE_T(v0, v1) edge_t(iso, iso_frac, v0, v1)
inline real edge_t(const real iso, const float iso_frac, const voxel v0, const voxel v1) {
    const real d = DIFF(v1, v0);
    if (isfinite(d)) return ISO_MINUS(v0) / d;
    const real h = (real)0.5;
    return (h * iso - h * (real)v0) / (h * (real)v1 - h * (real)v0);
}
#endif

// Central differences, one-sided at the volume border, divided by spacing (as the CPU).
// pos: the global coordinate on this axis, idx: the data index, stride: the data's stride.
inline real axis_diff(__global const voxel* data, uint idx, uint pos, uint n, uint stride, real inv) {
    const voxel hi = data[pos + 1 < n ? idx + stride : idx];
    const voxel lo = data[pos > 0 ? idx - stride : idx];
    const real step = (pos > 0 && pos + 1 < n) ? (real)0.5 : (real)1.0;
    return DIFF(hi, lo) * (step * inv);  // one rounding, as the CPU's (hi - lo) * (0.5 / spacing)
}

// Central differences at data index idx away from the border, divided by spacing.
inline void central_gradient(__global const voxel* data, uint idx, uint stride_y, uint stride_z, real ix, real iy,
                             real iz, real* g) {
    g[0] = DIFF(data[idx + 1], data[idx - 1]) * ((real)0.5 * ix);
    g[1] = DIFF(data[idx + stride_y], data[idx - stride_y]) * ((real)0.5 * iy);
    g[2] = DIFF(data[idx + stride_z], data[idx - stride_z]) * ((real)0.5 * iz);
}

// The same, one-sided where (x, y, z) lies on the volume's border.
inline void border_gradient(__global const voxel* data, uint idx, uint x, uint y, uint z, uint stride_y,
                            uint stride_z, uint nx, uint ny, uint nz, real ix, real iy, real iz, real* g) {
    g[0] = axis_diff(data, idx, x, nx, 1, ix);
    g[1] = axis_diff(data, idx, y, ny, stride_y, iy);
    g[2] = axis_diff(data, idx, z, nz, stride_z, iz);
}

// PoCL's CPU compiler called sample_vertices out of line, its 29 arguments passed through the
// stack per sample; always_inline is clang's attribute, so it is only asked for on CPU
// devices (GPU compilers inline by default).
#ifdef CPU_PREFETCH
#define VERTEX_INLINE __attribute__((always_inline))
#else
#define VERTEX_INLINE
#endif

// The vertices of the crossed edges global sample (x, y, z), at data index idx, owns: bit a
// of `axes` for the edge along axis a, written in axis order to position[0..] and, when
// want_normals, normal[0..]. The sample's value and gradient are read once for all its
// edges (as the CPU engine does; the arithmetic per edge is the same either way).
// stride_y / stride_z: the data's strides; nx, ny, nz: the whole volume's dimensions.
VERTEX_INLINE inline void sample_vertices(__global const voxel* data, const uint idx, const uint x, const uint y,
                                          const uint z, const uint axes, const uint stride_y, const uint stride_z,
                                          const uint nx, const uint ny, const uint nz, const voxel thr, const real iso,
                                          const long iso_int, const float iso_frac, const real ox, const real oy,
                                          const real oz, const real sx, const real sy, const real sz, const real ix,
                                          const real iy, const real iz, const int inside_below,
                                          const int want_normals, __global float* position, __global float* normal) {
    const voxel v0 = data[idx];
    // Both ends of every edge at least one sample in: plain central differences, without the
    // per-axis border tests.
    const int interior = x >= 1 && x + 3 <= nx && y >= 1 && y + 3 <= ny && z >= 1 && z + 3 <= nz;
    real g0[3] = {0, 0, 0};
    if (want_normals) {
        if (interior) central_gradient(data, idx, stride_y, stride_z, ix, iy, iz, g0);
        else border_gradient(data, idx, x, y, z, stride_y, stride_z, nx, ny, nz, ix, iy, iz, g0);
    }
    const real sign = inside_below ? (real)1 : (real)-1;  // outward: toward decreasing values
    for (uint axis = 0; axis < 3; ++axis) {
        if (!(axes >> axis & 1u)) continue;
        const uint stride = axis == 0 ? 1u : axis == 1 ? stride_y : stride_z;
        const uint idx1 = idx + stride;
        const voxel v1 = data[idx1];
        const real t0 = EDGE_T(v0, v1);
        // On the edge, NaN to 0, as the CPU engine's on_edge: only samples written to since
        // classify (zero-copy host memory) give another t.
        const real t = t0 >= 0 ? (t0 <= 1 ? t0 : (real)1) : (real)0;
        position[0] = (float)(ox + ((real)x + (axis == 0 ? t : (real)0)) * sx);
        position[1] = (float)(oy + ((real)y + (axis == 1 ? t : (real)0)) * sy);
        position[2] = (float)(oz + ((real)z + (axis == 2 ? t : (real)0)) * sz);
        position += 3;
        if (!want_normals) continue;
        real g1[3];
        if (interior) {
            central_gradient(data, idx1, stride_y, stride_z, ix, iy, iz, g1);
        } else {
            border_gradient(data, idx1, x + (axis == 0), y + (axis == 1), z + (axis == 2), stride_y, stride_z, nx, ny,
                            nz, ix, iy, iz, g1);
        }
        const real n0 = sign * (g0[0] + t * (g1[0] - g0[0]));
        const real n1 = sign * (g0[1] + t * (g1[1] - g0[1]));
        const real n2 = sign * (g0[2] + t * (g1[2] - g0[2]));
        // As normalise_normal (src/core/edge_vertex.hpp): where |n|^2 overflows or loses its
        // precision, n scaled by its largest component first.
        const real len2 = n0 * n0 + n1 * n1 + n2 * n2;
        real s0 = n0, s1 = n1, s2 = n2, inv = 0;
        bool unit = len2 >= REAL_MIN && len2 <= REAL_MAX;
        if (unit) {
            inv = (real)1 / sqrt(len2);
        } else {
            const real m = fmax(fabs(n0), fmax(fabs(n1), fabs(n2)));
            if (m > 0 && m <= REAL_MAX) {
                s0 = n0 / m;
                s1 = n1 / m;
                s2 = n2 / m;
                const real scaled2 = s0 * s0 + s1 * s1 + s2 * s2;
                unit = isfinite(scaled2);
                if (unit) inv = (real)1 / sqrt(scaled2);
            }
        }
        if (unit) {
            normal[0] = (float)(s0 * inv);
            normal[1] = (float)(s1 * inv);
            normal[2] = (float)(s2 * inv);
        } else {
            // Flat gradient: along the edge, from its inside end to its outside end.
            const float s = ((v0 >= thr) != (inside_below != 0)) ? 1.f : -1.f;
            normal[0] = axis == 0 ? s : 0.f;
            normal[1] = axis == 1 ? s : 0.f;
            normal[2] = axis == 2 ? s : 0.f;
        }
        normal += 3;
    }
}
