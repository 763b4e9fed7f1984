// Sculpting: marching cubes over a batch of blocks at once, each block's mesh self-contained
// and identical to the CPU block mesher's (src/sculpt/block_mesher.hpp): vertices in local
// sample order then axis, triangles in local cell order then table order, vertex ids local
// to the block.
//
// The host (src/cl/cl_blocks.cpp) builds it behind edge_vertex.cl (types, build options,
// the vertex formula) with -DVOXEL_T=<uchar|ushort|float>; with -DUSE_FP64 vertices are
// computed in double, bit-identical to the CPU's EdgeVertex.
//
// Staging: the host copies each block's samples plus a one-sample margin (clamped at the
// volume border: what central-difference normals read) into one buffer. Block b is
// described by kMetaWords uints in `meta` (layout below, written by the host).
// Work: one work-item per (local sample row (y, z), block): get_global_id(0) = y + ly*z,
// get_global_id(1) = the block's place in the batch. Rows of all blocks are numbered
// contiguously (row_base), so one scan over per-row counts gives every block's vertices and
// triangles a contiguous range, in canonical order.

// meta words of one block
#define M_STAGE 0       // first staged sample
#define M_SX 1          // staged extent x, y (z is not needed)
#define M_SY 2
#define M_OX 3          // local sample (0,0,0) within the staged box: 1 where a margin exists
#define M_OY 4
#define M_OZ 5
#define M_C0X 6         // the block's first sample, global
#define M_C0Y 7
#define M_C0Z 8
#define M_LX 9          // samples of the block's box per axis (cells + 1)
#define M_LY 10
#define M_LZ 11
#define M_ROW 12        // first row in the batch's row numbering
#define M_SAMPLE 13     // first sample in the batch's per-sample arrays (codes, vid)
#define M_WORDS 16

typedef struct {
    uint stage, sx, splane, lx, ly, lz, row, sample;
    uint ox, oy, oz, c0x, c0y, c0z;
} Block;

inline Block load_block(__global const uint* meta, uint b) {
    __global const uint* m = meta + M_WORDS * b;
    Block k;
    k.stage = m[M_STAGE];
    k.sx = m[M_SX];
    k.splane = m[M_SX] * m[M_SY];
    k.ox = m[M_OX];
    k.oy = m[M_OY];
    k.oz = m[M_OZ];
    k.c0x = m[M_C0X];
    k.c0y = m[M_C0Y];
    k.c0z = m[M_C0Z];
    k.lx = m[M_LX];
    k.ly = m[M_LY];
    k.lz = m[M_LZ];
    k.row = m[M_ROW];
    k.sample = m[M_SAMPLE];
    return k;
}

// Staged index of local sample (x, y, z).
inline uint staged(const Block* k, uint x, uint y, uint z) {
    return k->stage + (x + k->ox) + k->sx * (y + k->oy) + k->splane * (z + k->oz);
}

// Inside bits of local rows (y, z), (y+1, z), (y, z+1), (y+1, z+1) at x, in bits 0..3 (the
// CPU's column code); rows outside the block's box give 0.
inline uint column(__global const voxel* data, const Block* k, uint x, uint y, uint z, voxel thr) {
    const uint i = staged(k, x, y, z);
    uint c = (uint)(data[i] >= thr);
    if (y + 1 < k->ly) c |= (uint)(data[i + k->sx] >= thr) << 1;
    if (z + 1 < k->lz) {
        c |= (uint)(data[i + k->splane] >= thr) << 2;
        if (y + 1 < k->ly) c |= (uint)(data[i + k->splane + k->sx] >= thr) << 3;
    }
    return c;
}

// Edge codes of the row's samples (bit = axis of a crossed edge inside the box), the row's
// vertex count and its cell row's triangle count.
__kernel void block_classify(__global const voxel* data, __global const uint* meta, const voxel thr,
                             __constant uchar* pair_to_case, __constant uchar* case_table, __global uchar* codes,
                             __global uint* vcount, __global uint* tcount) {
    const uint b = (uint)get_global_id(1);
    const Block k = load_block(meta, b);
    const uint r = (uint)get_global_id(0);
    if (r >= k.ly * k.lz) return;
    const uint y = r % k.ly, z = r / k.ly;
    const int cells = y + 1 < k.ly && z + 1 < k.lz;
    __global uchar* code_row = codes + k.sample + r * k.lx;
    uint vsum = 0, tsum = 0;
    uint col = column(data, &k, 0, y, z, thr);
    for (uint x = 0; x < k.lx; ++x) {
        const uint next = x + 1 < k.lx ? column(data, &k, x + 1, y, z, thr) : 0u;
        uint code = 0;
        if (x + 1 < k.lx) code |= (col ^ next) & 1;
        if (y + 1 < k.ly) code |= ((col ^ (col >> 1)) & 1) << 1;
        if (z + 1 < k.lz) code |= ((col ^ (col >> 2)) & 1) << 2;
        code_row[x] = (uchar)code;
        vsum += popcount(code);
        if (cells && x + 1 < k.lx) tsum += case_table[16 * pair_to_case[col | next << 4]];
        col = next;
    }
    vcount[k.row + r] = vsum;
    tcount[k.row + r] = tsum;
}

// After the scans (vbase: exclusive sums of vcount): each sample's first vertex id (batch-
// global) into vid, and the row's vertex positions and normals.
__kernel void block_vertices(__global const voxel* data, __global const uint* meta, const voxel thr,
                             const real iso, const long iso_int, const float iso_frac, const real ox,
                             const real oy, const real oz, const real sx, const real sy, const real sz,
                             const real ix, const real iy, const real iz, const uint nx, const uint ny,
                             const uint nz, const int inside_below, const int want_normals,
                             __global const uchar* codes, __global const uint* vbase, __global uint* vid,
                             __global float* positions, __global float* normals) {
    const uint b = (uint)get_global_id(1);
    const Block k = load_block(meta, b);
    const uint r = (uint)get_global_id(0);
    if (r >= k.ly * k.lz) return;
    const uint y = r % k.ly, z = r / k.ly;
    const uint gy = k.c0y + y, gz = k.c0z + z;
    const uint first = k.sample + r * k.lx;
    uint v = vbase[k.row + r];
    for (uint x = 0; x < k.lx; ++x) {
        const uint code = codes[first + x];
        vid[first + x] = v;
        if (code == 0) continue;
        const uint gx = k.c0x + x;
        const uint idx = staged(&k, x, y, z);
        const uint axes = code & 7u;
        sample_vertices(data, idx, gx, gy, gz, axes, k.sx, k.splane, nx, ny, nz, thr, iso, iso_int, iso_frac, ox, oy, oz,
                        sx, sy, sz, ix, iy, iz, inside_below, want_normals, positions + 3 * v, normals + 3 * v);
        v += popcount(axes);
    }
}

// The triangles of the cell row (y, z), at tbase's slot, with block-local vertex ids.
__kernel void block_triangles(__global const voxel* data, __global const uint* meta, const voxel thr,
                              __constant uchar* pair_to_case, __constant uchar* case_corners,
                              const int inside_below, __global const uchar* codes,
                              __global const uint* vid, __global const uint* vbase, __global const uint* tbase,
                              __global uint* indices) {
    const uint b = (uint)get_global_id(1);
    const Block k = load_block(meta, b);
    const uint r = (uint)get_global_id(0);
    if (r >= k.ly * k.lz) return;
    const uint y = r % k.ly, z = r / k.ly;
    if (y + 1 >= k.ly || z + 1 >= k.lz) return;
    const uint block_first_vertex = vbase[k.row];
    const uint plane = k.lx * k.ly;
    uint out = 3 * tbase[k.row + r];
    uint col = column(data, &k, 0, y, z, thr);
    for (uint x = 0; x + 1 < k.lx; ++x) {
        const uint next = column(data, &k, x + 1, y, z, thr);
        const uint c = pair_to_case[col | next << 4];
        col = next;
        __constant uchar* corners = case_corners + 16 * c;
        const uint count = corners[0];
        for (uint q = 0; q < count; ++q) {
            uint id[3];
            for (uint e = 0; e < 3; ++e) {
                const uint corner = corners[1 + 3 * q + e];  // dx | dy << 1 | dz << 2 | axis << 3
                const uint s = k.sample + (x + (corner & 1u)) + k.lx * (y + (corner >> 1 & 1u)) +
                               plane * (z + (corner >> 2 & 1u));
                const uint code = codes[s];
                const uint axis = corner >> 3;
                id[e] = vid[s] - block_first_vertex +
                        (axis == 0 ? 0u : axis == 1 ? (code & 1) : (code & 1) + (code >> 1 & 1));
            }
            indices[out + 0] = id[0];
            indices[out + 1] = inside_below ? id[2] : id[1];
            indices[out + 2] = inside_below ? id[1] : id[2];
            out += 3;
        }
    }
}
