// Marching cubes over one z-chunk on packed bit rows, the CPU engine's layout on the device:
//   classify_pack       samples -> inside bits, 32 to a word (the only pass over every sample)
//   classify_rows       per row: crossed edges it owns, triangles of the cell row it starts
//   (scan.cl)           exclusive prefix sums over rows: every vertex and triangle its index
//   generate_vertices   per row with crossings: its vertices, in x then axis order
//   generate_triangles  per cell row with triangles: its triangles, a cell's edge ids by popcounts
// No per-sample bytes are stored: later passes re-derive edges and cases from the bits.
//
// The host builds it behind edge_vertex.cl (types, build options, the vertex formula).
//
// Index spaces (chunk-local, uint; the host keeps the data below 2^31 samples):
//   row r = j + ny * p is sample row (y = j, z = begin + p); the chunk's meta rows are planes
//   p in [0, meta) = [begin, min(end+1, nz)): its own planes plus plane `end`, whose vertex
//   ids the chunk's last cell plane refers to. The bits cover planes [begin, zhi) with
//   zhi = min(end+2, nz) (the edges of plane `end` look one plane up); the samples cover
//   [zlo, zhi) with zlo = max(begin,1)-1 (gradients look one plane down).
//   bits[r * words + q] bit b is sample x = 32 q + b of row r; bits past nx are 0.
//
// "Inside" is sample >= thr, with thr made by the host exactly as the CPU engine makes it,
// so every case index is identical. The one table this file's kernels read comes from the
// host's single copy (src/core/case_tables.cpp) as a __constant buffer:
//   pair_corners: 16 bytes per row-pair index (cell_pairs), the case's triangle count then
//                 each corner's edge as dx | dy << 1 | dz << 2 | axis << 3 (the host builds
//                 it from its case, cell-edge and row-pair tables; sculpt_blocks.cl reads the
//                 same by case index, case_corners).

#define CAT2(a, b) a##b
#define CAT(a, b) CAT2(a, b)
typedef CAT(VOXEL_T, 8) voxel8;
typedef CAT(VOXEL_T, 16) voxel16;

#ifdef VOXEL_INTEGER
#define NONFINITE(v) 0
#else
#define NONFINITE(v) (!isfinite(v)) /* NaN or infinite: refused like the CPU engine */
#endif

// A cache hint for CPU devices (the host defines CPU_PREFETCH there): the kernels read a
// few samples or ids per crossing, too sparse for the hardware prefetcher, and each row's
// first reads of the planes ahead go to memory. Never faults; nothing on other devices.
#if defined(CPU_PREFETCH) && defined(__has_builtin)
#if __has_builtin(__builtin_prefetch)
#define PREFETCH(p) __builtin_prefetch(p)
#endif
#endif
#ifndef PREFETCH
#define PREFETCH(p) ((void)(p)) /* uses the address, so its computation is not an unused variable */
#endif

// Bits of word q that stand for x < limit.
inline uint bits_below(uint q, uint limit) {
    const uint first = 32 * q;
    if (limit >= first + 32) return 0xffffffffu;
    if (limit <= first) return 0u;
    return (1u << (limit - first)) - 1u;
}

// Index of the lowest set bit of w != 0 (ctz is OpenCL 2.0).
inline uint lowest_bit(uint w) { return 31u - clz(w & (0u - w)); }

// Inside bits of the 8 samples of v: each compare lane as one byte 0 or 1 of a ulong, then
// one multiply moves byte i's bit to bit 56 + i (the partial products never overlap, so
// nothing carries). OpenCL has no movemask, and the or-reduction of lane masks this
// replaces stalled on a store-to-vector-load through the stack under PoCL.
inline uint pack8(const voxel8 v, const voxel thr) {
    const char8 inside = convert_char8(v >= (voxel8)(thr)) & (char8)(1);
    return (uint)((as_ulong(inside) * 0x0102040810204080ul) >> 56);
}

// On an x86 CPU device (PoCL's compiler is clang), the lanes' sign bits in one instruction
// (pmovmskb): 16 samples in a few instructions where pack8 takes a multiply chain per 8,
// the whole of classify_pack's time on a u8 volume.
#if defined(CPU_PREFETCH) && defined(__has_builtin)
#if __has_builtin(__builtin_ia32_pmovmskb128)
#define HAVE_MOVEMASK 1
typedef char byte_lanes16 __attribute__((vector_size(16)));
#endif
#endif

inline uint pack16(const voxel16 v, const voxel thr) {
#ifdef HAVE_MOVEMASK
    return (uint)__builtin_ia32_pmovmskb128((byte_lanes16)convert_char16(v >= (voxel16)(thr))) & 0xffffu;
#else
    return pack8(v.lo, thr) | pack8(v.hi, thr) << 8;
#endif
}

// Inside bits of the 32 samples at s, and in *finite whether they are all finite.
inline uint pack_word(__global const voxel* s, const voxel thr, int* finite) {
    uint w = 0;
#ifndef VOXEL_INTEGER
    int16 ok = (int16)(-1);
#endif
    for (uint k = 0; k < 2; ++k) {
        const voxel16 v = vload16(k, s);
        w |= pack16(v, thr) << (16 * k);
#ifndef VOXEL_INTEGER
        ok &= convert_int16(isfinite(v));
#endif
    }
#ifndef VOXEL_INTEGER
    if (!all(ok)) *finite = 0;
#endif
    return w;
}

// What a packed row holds: all outside, all inside, or both (row_state, classify_rows' skip).
#define ROW_OUTSIDE 0
#define ROW_INSIDE 1
#define ROW_MIXED 2

// A row's nx samples at s into `words` words at out; 0 when a sample is not finite. *state:
// the row's ROW_ kind.
inline int pack_row(__global const voxel* s, const voxel thr, const uint nx, const uint words, __global uint* out,
                    uint* state) {
    int finite = 1;
    const uint full = nx / 32;
    uint any = 0, all = ~0u;
    for (uint q = 0; q < full; ++q) {
        const uint w = pack_word(s + 32 * q, thr, &finite);
        out[q] = w;
        any |= w;
        all &= w;
    }
    if (full < words) {
        uint w = 0;
        for (uint x = 32 * full; x < nx; ++x) {
            const voxel v = s[x];
            if (NONFINITE(v)) finite = 0;
            w |= (uint)(v >= thr) << (x - 32 * full);
        }
        out[full] = w;
        any |= w;
        all &= w | ~bits_below(full, nx);
    }
    *state = !any ? ROW_OUTSIDE : all == ~0u ? ROW_INSIDE : ROW_MIXED;
    return finite;
}

// On CPU devices the packing kernels ask for the lines of the row rows_ahead(nx) rows (about
// 8 KiB) after their own, which a work-item a little later packs (a work-group's items run
// in order), as the CPU engine's packer does: the packs' loads otherwise waited on memory
// (perf, sphere u8 512³: three quarters of classify_pack's samples on its compare).
// Nothing on other devices.
#ifdef CPU_PREFETCH
inline uint rows_ahead(const uint nx) { return max(1u, 8192u / (nx * (uint)sizeof(voxel))); }

inline void prefetch_row(__global const voxel* row, const uint nx) {
    __global const uchar* line = (__global const uchar*)row;
    for (uint b = 0; b < nx * (uint)sizeof(voxel); b += 64) PREFETCH(line + b);
}
#endif

// One work-item per bit row: its nx samples into `words` words, and its ROW_ kind.
__kernel void classify_pack(__global const voxel* data, const voxel thr, const uint nx, const uint ny, const uint words,
                            const uint begin, const uint first_sample, const uint rows, __global uint* bits,
                            __global uchar* row_state, __global int* nan_plane) {
    const uint r = (uint)get_global_id(0);
    if (r >= rows) return;
    uint state;
#ifdef CPU_PREFETCH
    const uint ahead = r + rows_ahead(nx);
    if (ahead < rows) prefetch_row(data + first_sample + ahead * nx, nx);
#endif
    if (!pack_row(data + first_sample + r * nx, thr, nx, words, bits + r * words, &state))
        atomic_min(nan_plane, (int)(begin + r / ny));
    row_state[r] = (uchar)state;
}

// Bit k of the result is bit k+1 of the row: the neighbour in +x.
inline uint next_x(__global const uint* row, uint q, uint words) {
    return row[q] >> 1 | (q + 1 < words ? row[q + 1] << 31 : 0u);
}

// Crossed owned edges of word q of a row (sample x owns x->x+1, y->y+1, z->z+1); ny_row /
// nz_row are the neighbouring rows, or null at the volume's border.
typedef struct {
    uint x, y, z;
} EdgeMasks;

inline EdgeMasks edge_masks(__global const uint* row, __global const uint* ny_row, __global const uint* nz_row,
                            uint q, uint words, uint nx) {
    EdgeMasks m;
    const uint w = row[q];
    m.x = (w ^ next_x(row, q, words)) & bits_below(q, nx - 1);
    m.y = ny_row ? w ^ ny_row[q] : 0u;
    m.z = nz_row ? w ^ nz_row[q] : 0u;
    return m;
}

inline uint edge_count(EdgeMasks m) { return popcount(m.x) + popcount(m.y) + popcount(m.z); }

// The eight corner masks of word q of the cell row spanned by rows a = (y, z), b = (y+1, z),
// c = (y, z+1), d = (y+1, z+1), in case-bit order. Named scalars, not an array: PoCL kept
// an array on the stack and reloaded it as a vector, a store-forwarding stall per word.
typedef struct {
    uint k0, k1, k2, k3, k4, k5, k6, k7;
} CellWord;

inline CellWord cell_word(__global const uint* a, __global const uint* b, __global const uint* c,
                          __global const uint* d, uint q, uint words) {
    CellWord w;
    w.k0 = a[q];
    w.k1 = next_x(a, q, words);
    w.k2 = next_x(b, q, words);
    w.k3 = b[q];
    w.k4 = c[q];
    w.k5 = next_x(c, q, words);
    w.k6 = next_x(d, q, words);
    w.k7 = d[q];
    return w;
}

// Cells whose corners are neither all inside nor all outside.
inline uint nonuniform(CellWord w, uint q, uint nx) {
    const uint any = w.k0 | w.k1 | w.k2 | w.k3 | w.k4 | w.k5 | w.k6 | w.k7;
    const uint all = w.k0 & w.k1 & w.k2 & w.k3 & w.k4 & w.k5 & w.k6 & w.k7;
    return (any & ~all) & bits_below(q, nx - 1);
}

// The cell at bit b as its four rows' 2-bit pairs (bits b and b + 1 of rows a, b, c, d), the
// index of pair_corners: below bit 31 both bits lie in the rows' own words.
inline uint cell_pairs(CellWord w, uint b) {
    if (b < 31) return (w.k0 >> b & 3u) | (w.k3 >> b & 3u) << 2 | (w.k4 >> b & 3u) << 4 | (w.k7 >> b & 3u) << 6;
    return (w.k0 >> b & 1u) | (w.k1 >> b & 1u) << 1 | (w.k3 >> b & 1u) << 2 | (w.k2 >> b & 1u) << 3 |
           (w.k4 >> b & 1u) << 4 | (w.k5 >> b & 1u) << 5 | (w.k7 >> b & 1u) << 6 | (w.k6 >> b & 1u) << 7;
}

// Row r's neighbours in +y and +z among the bit rows, or null at the volume's border.
inline __global const uint* row_y(__global const uint* bits, uint r, uint j, uint ny, uint words) {
    return j + 1 < ny ? bits + (r + 1) * words : 0;
}
inline __global const uint* row_z(__global const uint* bits, uint r, uint z, uint ny, uint nz, uint words) {
    return z + 1 < nz ? bits + (r + ny) * words : 0;
}

// A row's word groups: bit g of a 64-bit mask stands for words [g * group, (g + 1) * group),
// group = ceil(words / 64) (one word per bit up to nx = 2048).
inline uint word_group(uint words) { return (words + 63u) / 64u; }
inline uint lowest_bit64(ulong w) { return 63u - (uint)clz(w & (0ul - w)); }

// One work-item per meta row: the vertices it owns, the triangles of the cell row it starts
// (cell planes below cell_end, y < ny - 1) and which word groups of that cell row hold a
// non-uniform cell (cell_groups: the words generate_triangles visits; on a sphere a crossed
// row has two clusters of crossings and uniform words between them). A cell that is not
// uniform has a crossed edge among row a's edges and row b's x- and z-edges (they join all
// 8 corners), so cell rows without one are skipped. Where row a and its neighbours are all
// inside or all outside alike (row_state; half a sphere's rows), no edge crosses and none of
// the words is read.
__kernel void classify_rows(__global const uint* bits, __global const uchar* row_state, const uint nx, const uint ny,
                            const uint nz, const uint words, const uint begin, const uint cell_end, const uint rows,
                            __constant uchar* pair_corners, __global uint* vcount, __global uint* tcount,
                            __global ulong* cell_groups) {
    const uint r = (uint)get_global_id(0);
    if (r >= rows) return;
    const uint p = r / ny;
    const uint j = r - p * ny;
    const uint z = begin + p;
    __global const uint* a = bits + r * words;
    __global const uint* b = row_y(bits, r, j, ny, words);
    __global const uint* c = row_z(bits, r, z, ny, nz, words);
    const int cells_here = b && z < cell_end;
    __global const uint* d = cells_here ? c + words : 0;
    const uint state = row_state[r];
    if (state != ROW_MIXED && (!b || row_state[r + 1] == state) && (!c || row_state[r + ny] == state) &&
        (!cells_here || row_state[r + ny + 1] == state)) {
        vcount[r] = 0;
        tcount[r] = 0;
        cell_groups[r] = 0;
        return;
    }
    uint v = 0, crossed = 0;
    for (uint q = 0; q < words; ++q) {
        const EdgeMasks m = edge_masks(a, b, c, q, words, nx);
        v += edge_count(m);
        crossed |= m.x | m.y | m.z;
        if (cells_here) {
            const EdgeMasks mb = edge_masks(b, 0, d, q, words, nx);  // b's y-edges leave the cell row
            crossed |= mb.x | mb.z;
        }
    }
    uint t = 0;
    ulong groups = 0;
    if (cells_here && crossed) {
        const uint group = word_group(words);
        for (uint q = 0; q < words; ++q) {
            const CellWord w = cell_word(a, b, c, d, q, words);
            const uint cells = nonuniform(w, q, nx);
            groups |= (ulong)(cells != 0u) << (q / group);
            for (uint left = cells; left; left &= left - 1)
                t += pair_corners[16 * cell_pairs(w, lowest_bit(left))];
        }
    }
    vcount[r] = v;
    tcount[r] = t;
    cell_groups[r] = groups;
}

// Row r's count from an exclusive scan `base` over `rows` rows whose total is `end`.
inline uint scanned_count(__global const uint* base, uint r, uint rows, uint end) {
    return (r + 1 < rows ? base[r + 1] : end) - base[r];
}

// Whether classify_repack packs bit row r: a row past the meta rows, or one that owns a
// crossed edge (the others are filled from their first sample).
inline bool repacks_row(uint r, uint meta_rows, __global const uint* vbase, uint vend) {
    return r >= meta_rows || scanned_count(vbase, r, meta_rows, vend) != 0;
}

// classify_pack again, for a chunk already counted (its samples are known to be finite): a
// meta row that owns no crossed edge has no crossed x-edge, so its samples are all inside or
// all outside, and its words are filled from its first sample instead of packing them (on a
// sphere half the rows: their samples are not read again). Bit rows past the meta rows
// (plane end + 1) are packed.
__kernel void classify_repack(__global const voxel* data, const voxel thr, const uint nx, const uint words,
                              const uint first_sample, const uint rows, const uint meta_rows, const uint vend,
                              __global const uint* vbase, __global uint* bits) {
    const uint r = (uint)get_global_id(0);
    if (r >= rows) return;
    __global const voxel* s = data + first_sample + r * nx;
    __global uint* out = bits + r * words;
#ifdef CPU_PREFETCH
    const uint ahead = r + rows_ahead(nx);  // only a row that will be packed
    if (ahead < rows && repacks_row(ahead, meta_rows, vbase, vend)) prefetch_row(data + first_sample + ahead * nx, nx);
#endif
    if (repacks_row(r, meta_rows, vbase, vend)) {
        uint state;
        pack_row(s, thr, nx, words, out, &state);
        return;
    }
    const uint fill = s[0] >= thr ? ~0u : 0u;
    const uint full = nx / 32;
    for (uint q = 0; q < full; ++q) out[q] = fill;
    if (full < words) out[full] = fill & ((1u << (nx - 32 * full)) - 1u);
}

// One work-item per meta row with crossings: the vertex id of the first edge of each of its
// words, counted from the row's first vertex vbase[r], into wbase (what the triangles look
// up; word_id is ushort, set by the host, where a row has at most 683 words, else uint),
// and for owned rows its vertices at ids vbase[r]... (vend: the total after the last meta
// row, for the last row's span). Rows without crossings leave wbase unwritten: no triangle
// refers to them.
__kernel void generate_vertices(__global const voxel* data, __global const uint* bits, const voxel thr, const real iso,
                                const long iso_int, const float iso_frac, const real ox, const real oy, const real oz,
                                const real sx, const real sy, const real sz, const real ix, const real iy,
                                const real iz, const uint nx, const uint ny, const uint nz, const uint words,
                                const uint begin, const uint first_sample, const uint owned_rows, const uint rows,
                                const uint vend, __global const uint* vbase, const int inside_below,
                                const int want_normals, __global float* positions, __global float* normals,
                                __global word_id* wbase) {
    const uint r = (uint)get_global_id(0);
    if (r >= rows || scanned_count(vbase, r, rows, vend) == 0) return;
    const uint row_first = vbase[r];
    // A row's vertices stay in its share even where samples packed again (classify_repack)
    // differ from those counted: the caller wrote to the volume during the call.
    const uint row_end = row_first + scanned_count(vbase, r, rows, vend);
    uint id = row_first;
    const uint p = r / ny;
    const uint j = r - p * ny;
    const uint z = begin + p;
    const uint plane = nx * ny;
    __global const uint* row = bits + r * words;
    __global const uint* ry = row_y(bits, r, j, ny, words);
    __global const uint* rz = row_z(bits, r, z, ny, nz, words);
    __global word_id* word_base = wbase + r * words;
    const int owned = r < owned_rows;  // plane `end`: ids only, its vertices belong to the next chunk
    const uint row_sample = first_sample + r * nx;
    for (uint q = 0; q < words; ++q) {
        word_base[q] = (word_id)(id - row_first);
        const EdgeMasks m = edge_masks(row, ry, rz, q, words, nx);
        if (!owned) {
            id += edge_count(m);
            continue;
        }
        const uint any_crossed = m.x | m.y | m.z;
        if (id + edge_count(m) > row_end) return;  // once a word, not once a sample
        if (any_crossed) {  // the next row's lines that its gradients touch first (see PREFETCH)
            __global const voxel* s = data + row_sample + nx + 32 * q + lowest_bit(any_crossed);
            PREFETCH(s + 2 * plane);
            PREFETCH(s + plane + nx);
            PREFETCH(s + 2 * nx);
        }
        for (uint any = any_crossed; any; any &= any - 1) {
            const uint b = lowest_bit(any);
            const uint x = 32 * q + b;
            const uint axes = (m.x >> b & 1u) | (m.y >> b & 1u) << 1 | (m.z >> b & 1u) << 2;
            sample_vertices(data, row_sample + x, x, j, z, axes, nx, plane, nx, ny, nz, thr, iso, iso_int, iso_frac, ox,
                            oy, oz, sx, sy, sz, ix, iy, iz, inside_below, want_normals, positions + 3 * (ulong)id,
                            normals + 3 * (ulong)id);  // 3 * id wraps in uint past 1431655765 vertices
            id += popcount(axes);
        }
    }
}

// One work-item per cell row with triangles. Cell row (y, z) is spanned by sample rows
// (y + dy, z + dz), indexed k = dy + 2 dz; a triangle corner on the edge from sample
// x = 32 q + b + dx of row k has the id of its word's first vertex plus the crossed edges
// before it in that word. Only the word groups classify_rows marked are visited, and words
// without a non-uniform cell there are skipped. pair_corners: per cell_pairs index the
// triangle count, then each corner as dx | k << 1 | axis << 3 (the host's
// pair_corner_table). Ids are the chunk's plus vertex_offset, its first vertex's id in the
// mesh.
__kernel void generate_triangles(__global const uint* bits, const uint nx, const uint ny, const uint nz,
                                 const uint words, const uint begin, const uint cell_rows, const uint rows,
                                 const uint tend, __global const uint* tbase, __global const uint* vbase,
                                 const uint vertex_offset, __global const word_id* wbase, __global const ulong* cell_groups,
                                 __constant uchar* pair_corners, const int inside_below, __global uint* indices) {
    const uint r = (uint)get_global_id(0);
    if (r >= cell_rows || scanned_count(tbase, r, rows, tend) == 0) return;
    uint t = tbase[r];
    const uint p = r / ny;
    const uint j = r - p * ny;
    const uint z = begin + p;
    __global const uint* row[4];
    __global const uint* ry[4];
    __global const uint* rz[4];
    __global const word_id* word_base[4];  // word q of row k's first vertex id: row_first[k] + word_base[k][q]
    uint row_first[4];
    for (uint k = 0; k < 4; ++k) {
        const uint rk = r + (k & 1u) + (k >> 1) * ny;
        row[k] = bits + rk * words;
        ry[k] = row_y(bits, rk, j + (k & 1u), ny, words);
        rz[k] = row_z(bits, rk, z + (k >> 1), ny, nz, words);
        word_base[k] = wbase + rk * words;
        row_first[k] = vertex_offset + vbase[rk];
    }
    // Offsets in ulong: 3 * t wraps in uint past 1431655765 triangles (a piece may hold more).
    __global uint* out = indices + 3 * (ulong)t;
    __global const uint* const out_end = out + 3 * (ulong)scanned_count(tbase, r, rows, tend);  // as row_end above
    const uint group = word_group(words);
    for (ulong g = cell_groups[r]; g; g &= g - 1) {
        const uint first = lowest_bit64(g) * group;
        const uint last = min(first + group, words);
        for (uint q = first; q < last; ++q) {
            const CellWord w = cell_word(row[0], row[1], row[2], row[3], q, words);
            uint cells = nonuniform(w, q, nx);
            if (!cells) continue;
            // Per row, the word's edge masks and first id: loaded once per word, not once per
            // corner (a load chain each). Three arrays, not one of EdgeMasks: PoCL read a
            // corner's x and y masks as one 8-byte load of two 4-byte stores made just before,
            // a store-forwarding stall (-3 % generate, PoCL, u8 and f32, sphere and gyroid).
            uint mx[4], my[4], mz[4];
            uint word_first[4];
            for (uint k = 0; k < 4; ++k) {
                const EdgeMasks m = edge_masks(row[k], ry[k], rz[k], q, words, nx);
                mx[k] = m.x;
                my[k] = m.y;
                mz[k] = m.z;
                word_first[k] = row_first[k] + word_base[k][q];
            }
            for (; cells; cells &= cells - 1) {
                const uint b = lowest_bit(cells);
                __constant uchar* corners = pair_corners + 16 * cell_pairs(w, b);
                const uint n = corners[0];
                if (out + 3 * n > out_end) return;
                // The ids of the cell's 12 edges, by corner code (dx | k << 1 | axis << 3):
                // a row's edges at sample b start after those before it in the word, its
                // edges at b + 1 after those at b. Once per cell, not per corner. Only the
                // codes of cell edges are set: x-edges of all four rows at b, y-edges of
                // rows 0 and 2 and z-edges of rows 0 and 1 at b and b + 1.
                uint id_of[20];
                const uint below = (1u << b) - 1u;
                // at: each row's first edge at b; bx, by: its x- and y-edge bits at b, nx1,
                // ny1 at b + 1 (rows 0 to 2: row 3 has only its x-edge in the cell).
                uint at[4], bx[3], by[3], nx1[3], ny1[3];
                for (uint k = 0; k < 4; ++k)
                    at[k] = word_first[k] + popcount(mx[k] & below) + popcount(my[k] & below) +
                            popcount(mz[k] & below);
                for (uint k = 0; k < 3; ++k) {
                    bx[k] = mx[k] >> b & 1u;
                    by[k] = my[k] >> b & 1u;
                    if (b < 31) {
                        nx1[k] = mx[k] >> (b + 1) & 1u;
                        ny1[k] = my[k] >> (b + 1) & 1u;
                    } else {  // the first sample of the next word
                        const EdgeMasks next = edge_masks(row[k], ry[k], rz[k], q + 1, words, nx);
                        nx1[k] = next.x & 1u;
                        ny1[k] = next.y & 1u;
                    }
                }
                id_of[0] = at[0];
                id_of[2] = at[1];
                id_of[4] = at[2];
                id_of[6] = at[3];
                const uint after0 = at[0] + bx[0] + by[0] + (mz[0] >> b & 1u);
                const uint after1 = at[1] + bx[1] + by[1] + (mz[1] >> b & 1u);
                const uint after2 = at[2] + bx[2] + by[2] + (mz[2] >> b & 1u);
                id_of[8] = at[0] + bx[0];
                id_of[9] = after0 + nx1[0];
                id_of[12] = at[2] + bx[2];
                id_of[13] = after2 + nx1[2];
                id_of[16] = at[0] + bx[0] + by[0];
                id_of[17] = after0 + nx1[0] + ny1[0];
                id_of[18] = at[1] + bx[1] + by[1];
                id_of[19] = after1 + nx1[1] + ny1[1];
                for (uint tri = 0; tri < n; ++tri) {
                    __constant uchar* code = corners + 1 + 3 * tri;
                    const uint i0 = id_of[code[0]], i1 = id_of[code[1]], i2 = id_of[code[2]];
                    out[0] = i0;
                    out[1] = inside_below ? i2 : i1;
                    out[2] = inside_below ? i1 : i2;
                    out += 3;
                }
            }
        }
    }
}
