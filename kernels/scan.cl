// Work-efficient exclusive prefix sum of uints (Blelloch), for any length n.
//
// scan_blocks: each work-group scans one block of get_local_size(0) * SCAN_ITEMS elements in
// place: every work-item first sums its SCAN_ITEMS consecutive elements serially, the
// work-group then runs the up-sweep / down-sweep tree over those partial sums in local
// memory (local size must be a power of two), and every work-item writes its elements'
// exclusive prefixes. The block's total goes to block_sums[group].
// scan_add: adds the (already scanned) block offset to every element of its block.
// The host scans block_sums recursively until one block remains.

#ifndef SCAN_ITEMS
#define SCAN_ITEMS 8
#endif

__kernel void scan_blocks(__global uint* data, const uint n, __global uint* block_sums, __local uint* tree) {
    const uint ls = (uint)get_local_size(0);
    const uint lid = (uint)get_local_id(0);
    const uint group = (uint)get_group_id(0);
    const uint first = (group * ls + lid) * SCAN_ITEMS;

    uint values[SCAN_ITEMS];
    uint sum = 0;
    for (uint r = 0; r < SCAN_ITEMS; ++r) {
        const uint i = first + r;
        values[r] = i < n ? data[i] : 0u;
        sum += values[r];
    }
    tree[lid] = sum;

    // Up-sweep: partial sums at the right end of ever larger power-of-two spans.
    for (uint offset = 1; offset < ls; offset <<= 1) {
        barrier(CLK_LOCAL_MEM_FENCE);
        const uint right = (lid + 1) * offset * 2 - 1;
        if (right < ls) tree[right] += tree[right - offset];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid == 0) {
        block_sums[group] = tree[ls - 1];
        tree[ls - 1] = 0;
    }
    // Down-sweep: turn the tree into exclusive prefixes of the work-items' sums.
    for (uint offset = ls >> 1; offset >= 1; offset >>= 1) {
        barrier(CLK_LOCAL_MEM_FENCE);
        const uint right = (lid + 1) * offset * 2 - 1;
        if (right < ls) {
            const uint left = tree[right - offset];
            tree[right - offset] = tree[right];
            tree[right] += left;
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);

    uint running = tree[lid];
    for (uint r = 0; r < SCAN_ITEMS; ++r) {
        const uint i = first + r;
        if (i < n) data[i] = running;
        running += values[r];
    }
}

__kernel void scan_add(__global uint* data, const uint n, __global const uint* block_offsets) {
    const uint ls = (uint)get_local_size(0);
    const uint group = (uint)get_group_id(0);
    const uint first = (group * ls + (uint)get_local_id(0)) * SCAN_ITEMS;
    const uint offset = block_offsets[group];
    for (uint r = 0; r < SCAN_ITEMS; ++r) {
        const uint i = first + r;
        if (i < n) data[i] += offset;
    }
}
