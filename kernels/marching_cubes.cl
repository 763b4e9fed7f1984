// Marching cubes over one z-chunk: classify, compact, vertices, triangles.
// (The prefix sums in between are scan.cl.)
//
// The host builds it behind edge_vertex.cl (types, build options, the vertex formula), with
//   -DGROUP=n         meta samples per classify / compact work-item
//
// Index spaces (all chunk-local, uint; the host keeps them below 2^29):
//   meta sample l = x + nx*(y + ny*(z - begin)) for z in [begin, meta_end): the chunk's own
//   planes [begin, end) plus plane `end` when it exists, whose vertex ids the chunk's last
//   cell plane refers to. Cell (x, y, z) shares index l with its corner-0 sample.
//   The sample buffer holds planes [zlo, zhi) = [max(begin,1)-1, min(end+2, nz)).
//
// "Inside" is sample >= thr, with thr made by the host exactly as the CPU engine makes it,
// so every case index is identical. The case tables come from the host's single copy
// (src/core/case_tables.cpp) as __constant buffers:
//   case_table: 16 bytes per case, triangle count then 15 signed edge numbers;
//   cell_edge:  4 bytes per edge (dx, dy, dz, axis);
//   pair_to_case: case index from the column codes at x and x+1 (kColumnPairToCase).
// Samples are classified in groups of GROUP (-DGROUP=n) consecutive meta samples; the scans
// run over per-group counts.

#ifdef VOXEL_INTEGER
#define IS_NAN(v) 0
#else
#define IS_NAN(v) (!isfinite(v)) /* NaN or infinite: refused like the CPU engine */
#endif

// Inside bits of rows (y, z), (y+1, z), (y, z+1), (y+1, z+1) at one x, in bits 0..3 (the
// CPU engine's column code); bits of rows outside the volume are 0.
inline uint column(__global const voxel* data, uint idx, uint y, uint z, uint nx, uint ny, uint nz, uint plane,
                   voxel thr) {
    uint c = (uint)(data[idx] >= thr);
    if (y + 1 < ny) c |= (uint)(data[idx + nx] >= thr) << 1;
    if (z + 1 < nz) {
        c |= (uint)(data[idx + plane] >= thr) << 2;
        if (y + 1 < ny) c |= (uint)(data[idx + plane + nx] >= thr) << 3;
    }
    return c;
}

// One work-item per GROUP consecutive meta samples: their edge codes and cell cases, and the
// group's vertex and triangle counts (what the scans sum).
__kernel void classify(__global const voxel* data, const voxel thr, const uint nx, const uint ny, const uint nz,
                       const uint begin, const uint cell_end, const uint zlo, const uint count, const uint groups,
                       __constant uchar* pair_to_case, __constant uchar* case_table, __global uchar* codes,
                       __global uchar* cases, __global uint* vcount, __global uint* tcount,
                       __global int* nan_plane) {
    const uint g = (uint)get_global_id(0);
    if (g >= groups) return;
    const uint plane = nx * ny;
    const uint l0 = g * GROUP;
    const uint zl = l0 / plane;
    const uint rest = l0 - zl * plane;
    uint y = rest / nx;
    uint x = rest - y * nx;
    uint z = begin + zl;
    uint idx = l0 + (begin - zlo) * plane;
    uint vsum = 0, tsum = 0, col = 0, next = 0;
    for (uint k = 0; k < GROUP; ++k) {
        const uint l = l0 + k;
        if (l >= count) break;
        const voxel v = data[idx];
        if (IS_NAN(v)) atomic_min(nan_plane, (int)z);
        col = (k == 0 || x == 0) ? column(data, idx, y, z, nx, ny, nz, plane, thr) : next;
        next = x + 1 < nx ? column(data, idx + 1, y, z, nx, ny, nz, plane, thr) : 0u;
        uint code = 0;
        if (x + 1 < nx) code |= (col ^ next) & 1;
        if (y + 1 < ny) code |= ((col ^ (col >> 1)) & 1) << 1;
        if (z + 1 < nz) code |= ((col ^ (col >> 2)) & 1) << 2;
        codes[l] = (uchar)code;
        vsum += popcount(code);
        uint c = 0;
        if (x + 1 < nx && y + 1 < ny && z < cell_end) c = pair_to_case[col | next << 4];
        cases[l] = (uchar)c;
        tsum += case_table[16 * c];
        ++idx;
        if (++x == nx) {
            x = 0;
            if (++y == ny) {
                y = 0;
                ++z;
            }
        }
    }
    vcount[g] = vsum;
    tcount[g] = tsum;
}

// Compaction: after the scans, every crossed edge and every triangle learns its slot, and
// each slot records its owner (sample << 2 | axis, cell << 3 | triangle), so the generate
// kernels run over exactly the vertices and triangles there are.
__kernel void compact(__global const uchar* codes, __global const uchar* cases, __global const uint* vbase,
                      __global const uint* tbase, const uint count, const uint owned, const uint groups,
                      __constant uchar* case_table, __global uint* vowner, __global uint* towner) {
    const uint g = (uint)get_global_id(0);
    if (g >= groups) return;
    uint vslot = vbase[g], tslot = tbase[g];
    for (uint l = g * GROUP; l < (g + 1) * GROUP && l < count; ++l) {
        if (l < owned) {
            const uint code = codes[l];
            for (uint axis = 0; axis < 3; ++axis)
                if (code >> axis & 1) vowner[vslot++] = l << 2 | axis;
        }
        const uint n = case_table[16 * cases[l]];
        for (uint q = 0; q < n; ++q) towner[tslot++] = l << 3 | q;
    }
}

__kernel void vertices(__global const voxel* data, const voxel thr, const real iso, const long iso_int,
                       const float iso_frac, const uint nx, const uint ny, const uint nz, const uint begin,
                       const uint zlo, const uint count, __global const uint* vowner, const real ox,
                       const real oy, const real oz, const real sx, const real sy, const real sz,
                       const real ix, const real iy, const real iz, const int inside_below,
                       const int want_normals, __global float* positions, __global float* normals) {
    const uint v = (uint)get_global_id(0);
    if (v >= count) return;
    const uint owner = vowner[v];
    const uint l = owner >> 2;
    const uint axis = owner & 3;
    const uint plane = nx * ny;
    const uint zl = l / plane;
    const uint rest = l - zl * plane;
    const uint y = rest / nx;
    const uint x = rest - y * nx;
    const uint z = begin + zl;
    const uint idx = l + (begin - zlo) * plane;
    edge_vertex(data, idx, x, y, z, axis, nx, plane, nx, ny, nz, thr, iso, iso_int, iso_frac, ox, oy, oz, sx, sy, sz,
                ix, iy, iz, inside_below, want_normals, positions + 3 * v, normals + 3 * v);
}

__kernel void triangles(__global const uchar* codes, __global const uchar* cases, __global const uint* vbase,
                        __global const uint* towner, const uint count, const uint nx, const uint plane,
                        __constant uchar* case_table, __constant uchar* cell_edge, const int inside_below,
                        __global uint* indices) {
    const uint t = (uint)get_global_id(0);
    if (t >= count) return;
    const uint owner = towner[t];
    const uint l = owner >> 3;
    const uint q = owner & 7;
    const uint c = cases[l];
    uint id[3];
    for (uint e = 0; e < 3; ++e) {
        const uint edge = case_table[16 * c + 1 + 3 * q + e];
        __constant uchar* ce = cell_edge + 4 * edge;
        const uint s = l + ce[0] + nx * ce[1] + plane * ce[2];
        const uint code = codes[s];
        const uint axis = ce[3];
        uint vid = vbase[s / GROUP];  // the group's first vertex, then the samples before s
        for (uint p = s - s % GROUP; p < s; ++p) vid += popcount((uint)codes[p]);
        id[e] = vid + (axis == 0 ? 0u : axis == 1 ? (code & 1) : (code & 1) + (code >> 1 & 1));
    }
    indices[3 * t + 0] = id[0];
    indices[3 * t + 1] = inside_below ? id[2] : id[1];
    indices[3 * t + 2] = inside_below ? id[1] : id[2];
}
