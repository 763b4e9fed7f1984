// Triangle mesh -> volume: surface and interior, threaded over rows.
//
// Grid: the longest side of the mesh's bounding box gets `resolution` cubic voxels (spacing
// h = longest side / resolution) with one sample at each voxel centre; the other axes get
// as many voxels as cover their side, centred on the box. `padding` samples are added on
// every side. origin and spacing of the result are set so that meshing it back
// (voxmesh::extract) lands in the model's own coordinates.
//
// Inside test: the crossings of a ray along +x, by VoxelizeOptions::fill.
//  - FillRule::EvenOdd (default): inside after an odd number of crossings. Does not depend
//    on the triangles' orientation, so inconsistently wound meshes voxelize correctly; but
//    where closed shells overlap (several intersecting CAD bodies in one STL) the overlap is
//    outside, and a shell inside another (both closed) leaves a hollow between them.
//  - FillRule::NonZero: inside where the winding number is non-zero, each crossing counted
//    +1 or -1 by its triangle's orientation: the union of the closed shells (overlaps and
//    nested shells are filled solid; an inside-out shell, all normals inward, has winding -1
//    and is filled too; an inward shell inside an outward one cancels it: a cavity, as solids
//    with voids are modelled). Needs consistent winding: every edge used as often in one
//    direction as in the other by its triangles (an edge used twice the same way is rejected
//    with Error).
// The mesh is snapped to a fixed-point lattice of 2^-16 voxel (vertices move by at most
// 2^-17 voxel) and crossings, and their signs, are decided with exact integer predicates
// and symbolic perturbation of the ray, so rays that pass exactly through vertices or along
// edges count every surface crossing exactly once: no streaks.
//
// Input rules: the mesh is welded by exact position first (unwelded STL soup is fine);
// triangles with a repeated vertex are ignored; coincident triangles (the same three corners)
// cancel as their crossings do: any two under EvenOdd, two wound opposite ways under NonZero
// (a face two bodies share is such a pair, so it is not a surface inside the union). Then the
// surface must be closed: every edge in an even number of triangles, two or, where bodies
// share an edge, four or more (NonZero: as many using it one way as the other). Holes (an edge
// in one triangle) and walls or fins (three or more, an odd number) are rejected with
// voxmesh::Error.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstddef>

namespace voxmesh {

enum class VoxelField {
    Occupancy,  // u8: 255 where the sample is inside, 0 outside; mesh it back at iso 127.5
    Distance,   // f32 signed Euclidean distance in model units, positive inside, negative
                // outside; mesh it back at iso 0 (the default inside = value >= iso gives
                // outward normals). Exact within `band` voxels of the surface, clamped to
                // +-band*h farther away, and to +-FLT_MAX (models spanning most of the float range).
                // The sign follows `fill`; the magnitude is the distance to the nearest
                // triangle, buried ones included: under NonZero a sample inside an overlap
                // (or between nested shells) measures to the nearest buried surface, so there
                // it can be less than the distance to the union's surface. Samples outside
                // are exact (the union's surface is nearer than anything it encloses), and
                // the sign changes only across the union's surface, so meshing at iso 0
                // gives the union's surface alone, its vertices within a voxel.
};

enum class FillRule {
    EvenOdd,  // inside after an odd number of crossings (any winding)
    NonZero,  // inside where the winding number is non-zero: the union of closed shells
};

struct VoxelizeOptions {
    std::size_t resolution = 128;  // voxels along the longest side of the bounding box (2..4096)
    std::size_t padding = 2;       // extra samples outside the box on every side (0..256); 0 lets
                                   // the surface touch the border, so its mesh is open there
    VoxelField field = VoxelField::Distance;
    FillRule fill = FillRule::EvenOdd;  // NonZero for overlapping or nested shells (CAD bodies)
    double band = 3;               // Distance: exact within this many voxels (2..1000)
    unsigned threads = 0;          // 0 = all cores; the result does not depend on it
};

// `mesh` must be closed (every edge in an even number of triangles once coincident ones cancel:
// two, or four or more where bodies share an edge), and for FillRule::NonZero consistently wound
// (each edge used as often in one direction as in the other); open input, walls or fins,
// an empty mesh, non-finite positions or out-of-range indices are rejected with Error. So
// are, before anything large is allocated, a grid whose bytes exceed the memory available
// (MemAvailable in /proc/meminfo, else physical memory, as the volume readers check), a grid
// with samples beyond the range of float (a model near +-3.4e38 plus padding), which
// extract() could not mesh, and triangle row lists (each triangle once per z row it spans)
// that would not fit beside the grid. A model with no sample inside it (flat, or thinner
// than a voxel everywhere) is an Error too: its volume would mesh back to nothing.
Volume voxelize(const Mesh& mesh, const VoxelizeOptions& options);

}  // namespace voxmesh
