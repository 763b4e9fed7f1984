// What every marching-cubes kernel shares: the sample and arithmetic types, and the vertex
// of a crossed edge, computed with the formula of src/core/edge_vertex.hpp. The host puts
// this file in front of marching_cubes.cl and sculpt_blocks.cl when it builds them.
//
// Build options chosen by the host:
//   -DVOXEL_T=<uchar|char|ushort|short|uint|int|float|double>  the sample type
//   -DVOXEL_INTEGER   integer samples (differences taken exactly in long)
//   -DUSE_FP64        the device has cl_khr_fp64: interpolate in double like the CPU engine

#pragma OPENCL FP_CONTRACT OFF

#ifdef USE_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
#else
typedef float real;
#endif

typedef VOXEL_T voxel;

#ifdef VOXEL_INTEGER
#define DIFF(hi, lo) ((real)((long)(hi) - (long)(lo)))
#else
#define DIFF(hi, lo) ((real)(hi) - (real)(lo))
#endif

// iso - v0. Without fp64, integer samples subtract from iso's integer part exactly and add
// its fraction, so that large integers keep their precision.
#if defined(USE_FP64) || !defined(VOXEL_INTEGER)
#define ISO_MINUS(v) (iso - (real)(v))
#else
#define ISO_MINUS(v) ((float)(iso_int - (long)(v)) + iso_frac)
#endif

// Central differences, one-sided at the volume border, divided by spacing (as the CPU).
// pos: the global coordinate on this axis, idx: the data index, stride: the data's stride.
inline real axis_diff(__global const voxel* data, uint idx, uint pos, uint n, uint stride, real inv) {
    const voxel hi = data[pos + 1 < n ? idx + stride : idx];
    const voxel lo = data[pos > 0 ? idx - stride : idx];
    const real step = (pos > 0 && pos + 1 < n) ? (real)0.5 : (real)1.0;
    return DIFF(hi, lo) * step * inv;
}

// The vertex of the edge from global sample (x, y, z), at data index idx, along `axis`:
// position into position[0..2] and, when want_normals, the normal into normal[0..2].
// stride_y / stride_z: the data's strides; nx, ny, nz: the whole volume's dimensions.
inline void edge_vertex(__global const voxel* data, const uint idx, const uint x, const uint y, const uint z,
                        const uint axis, const uint stride_y, const uint stride_z, const uint nx, const uint ny,
                        const uint nz, const voxel thr, const real iso, const long iso_int, const float iso_frac,
                        const real ox, const real oy, const real oz, const real sx, const real sy, const real sz,
                        const real ix, const real iy, const real iz, const int inside_below,
                        const int want_normals, __global float* position, __global float* normal) {
    const uint stride = axis == 0 ? 1u : axis == 1 ? stride_y : stride_z;
    const uint idx1 = idx + stride;
    const voxel v0 = data[idx];
    const voxel v1 = data[idx1];
    const real t = ISO_MINUS(v0) / DIFF(v1, v0);
    position[0] = (float)(ox + ((real)x + (axis == 0 ? t : (real)0)) * sx);
    position[1] = (float)(oy + ((real)y + (axis == 1 ? t : (real)0)) * sy);
    position[2] = (float)(oz + ((real)z + (axis == 2 ? t : (real)0)) * sz);
    if (!want_normals) return;

    const uint x1 = x + (axis == 0), y1 = y + (axis == 1), z1 = z + (axis == 2);
    real g0x, g0y, g0z, g1x, g1y, g1z;
    // Most vertices lie away from the border: there both gradients are plain central
    // differences, taken without the per-axis border tests (the same arithmetic).
    if (x - 1 < nx - 2 && y - 1 < ny - 2 && z - 1 < nz - 2 && x1 + 1 < nx && y1 + 1 < ny && z1 + 1 < nz) {
        g0x = DIFF(data[idx + 1], data[idx - 1]) * (real)0.5 * ix;
        g1x = DIFF(data[idx1 + 1], data[idx1 - 1]) * (real)0.5 * ix;
        g0y = DIFF(data[idx + stride_y], data[idx - stride_y]) * (real)0.5 * iy;
        g1y = DIFF(data[idx1 + stride_y], data[idx1 - stride_y]) * (real)0.5 * iy;
        g0z = DIFF(data[idx + stride_z], data[idx - stride_z]) * (real)0.5 * iz;
        g1z = DIFF(data[idx1 + stride_z], data[idx1 - stride_z]) * (real)0.5 * iz;
    } else {
        g0x = axis_diff(data, idx, x, nx, 1, ix);
        g1x = axis_diff(data, idx1, x1, nx, 1, ix);
        g0y = axis_diff(data, idx, y, ny, stride_y, iy);
        g1y = axis_diff(data, idx1, y1, ny, stride_y, iy);
        g0z = axis_diff(data, idx, z, nz, stride_z, iz);
        g1z = axis_diff(data, idx1, z1, nz, stride_z, iz);
    }
    // Outward is toward decreasing values: the negated gradient (flipped for inside_below).
    const real sign = inside_below ? (real)1 : (real)-1;
    const real n0 = sign * (g0x + t * (g1x - g0x));
    const real n1 = sign * (g0y + t * (g1y - g0y));
    const real n2 = sign * (g0z + t * (g1z - g0z));
    const real len2 = n0 * n0 + n1 * n1 + n2 * n2;
    if (len2 > 0 && isfinite(len2)) {
        const real inv = (real)1 / sqrt(len2);
        normal[0] = (float)(n0 * inv);
        normal[1] = (float)(n1 * inv);
        normal[2] = (float)(n2 * inv);
    } else {
        // Flat gradient: along the edge, from its inside end to its outside end.
        const float s = ((v0 >= thr) != (inside_below != 0)) ? 1.f : -1.f;
        normal[0] = axis == 0 ? s : 0.f;
        normal[1] = axis == 1 ? s : 0.f;
        normal[2] = axis == 2 ? s : 0.f;
    }
}
