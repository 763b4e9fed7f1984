// Test-side mesh checks and field generators, written independently of the engine.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace vmtest {

using Dims = std::array<std::size_t, 3>;

// ------------------------------------------------------------------ topology and geometry

struct Topology {
    std::size_t vertices_used = 0;   // vertices referenced by at least one triangle
    std::size_t edges = 0;           // undirected edges
    std::size_t boundary_edges = 0;  // in exactly one triangle
    std::size_t nonmanifold_edges = 0;  // in three or more triangles
    std::size_t degenerate_triangles = 0;  // a repeated vertex index
    std::size_t repeated_directed_edges = 0;  // a directed edge used by two or more triangles
    long long euler = 0;                      // V - E + F
    bool closed() const { return boundary_edges == 0 && nonmanifold_edges == 0; }
    // Every directed edge at most once: neighbouring triangles agree on orientation.
    bool consistently_oriented() const { return repeated_directed_edges == 0; }
};
Topology topology(const voxmesh::Mesh& mesh);

double surface_area(const voxmesh::Mesh& mesh);
// Sum of signed tetrahedra (origin, a, b, c): positive for a closed, outward-wound surface.
double signed_volume(const voxmesh::Mesh& mesh);

// Largest |len - 1| over all normals.
double max_normal_length_error(const voxmesh::Mesh& mesh);

// Index buffer out of range, array sizes not multiples of 3, normals size mismatch.
std::string structural_problem(const voxmesh::Mesh& mesh);

// Bit-for-bit equality of float arrays (-0 is not +0), for round trips through a file.
bool same_bits(const std::vector<float>& a, const std::vector<float>& b);
// Each triangle as its three corner positions, in the mesh's order and winding: what a mesh
// is whatever its vertex numbering (an STL round trip welds, and so renumbers). Compared as
// floats, -0 equals +0.
std::vector<std::array<float, 9>> triangle_corners(const voxmesh::Mesh& mesh);

// ------------------------------------------------------------------ connected pieces

// The oracle for keep_largest_components and MeshTopology::components, deliberately simple: a
// breadth-first walk over triangles sharing a vertex numbers each triangle's piece (pieces in
// order of their first triangle); `piece_count` receives how many there are.
std::vector<std::size_t> oracle_pieces(const voxmesh::Mesh& mesh, std::size_t& piece_count);
// The `count` pieces with the most triangles (the lowest-numbered of equals), kept triangles
// and their vertices in the mesh's order, normals carried along.
voxmesh::Mesh oracle_keep_largest(const voxmesh::Mesh& mesh, std::size_t count);

// ------------------------------------------------------------------ triangle sets

using TriKey = std::array<std::uint64_t, 3>;

// Oriented key: rotated so the smallest id is first (cyclic order kept).
TriKey oriented_key(std::uint64_t a, std::uint64_t b, std::uint64_t c);
// Unoriented key: sorted.
TriKey unoriented_key(std::uint64_t a, std::uint64_t b, std::uint64_t c);

// The triangles of `indices` with each vertex index mapped through `vertex_key`, as a sorted
// multiset of oriented (or unoriented) keys.
std::vector<TriKey> triangle_set(const std::vector<std::uint32_t>& indices, const std::vector<std::uint64_t>& vertex_key,
                                 bool oriented);

// Vertex keys from positions: the vertex's grid edge, found from its position (two
// coordinates on grid lines, the third between two samples). Only unambiguous when no
// vertex sits exactly on a sample (iso never equal to a sample value).
std::vector<std::uint64_t> edge_keys_from_positions(const voxmesh::Mesh& mesh, const Dims& dims,
                                                    const std::array<double, 3>& spacing,
                                                    const std::array<double, 3>& origin);

// ------------------------------------------------------------------ scalar types

template <class T>
constexpr voxmesh::ScalarType scalar_type_of() {
    if constexpr (std::is_same_v<T, std::uint8_t>) return voxmesh::ScalarType::U8;
    else if constexpr (std::is_same_v<T, std::int8_t>) return voxmesh::ScalarType::I8;
    else if constexpr (std::is_same_v<T, std::uint16_t>) return voxmesh::ScalarType::U16;
    else if constexpr (std::is_same_v<T, std::int16_t>) return voxmesh::ScalarType::I16;
    else if constexpr (std::is_same_v<T, std::uint32_t>) return voxmesh::ScalarType::U32;
    else if constexpr (std::is_same_v<T, std::int32_t>) return voxmesh::ScalarType::I32;
    else if constexpr (std::is_same_v<T, float>) return voxmesh::ScalarType::F32;
    else {
        static_assert(std::is_same_v<T, double>, "unsupported scalar type");
        return voxmesh::ScalarType::F64;
    }
}

template <class T>
voxmesh::VolumeView view_of(const std::vector<T>& data, const Dims& dims, std::array<double, 3> spacing = {1, 1, 1},
                            std::array<double, 3> origin = {0, 0, 0}) {
    voxmesh::VolumeView v;
    v.data = data.data();
    v.type = scalar_type_of<T>();
    v.dims = dims;
    v.spacing = spacing;
    v.origin = origin;
    return v;
}

// Options for the CPU engine at `iso` on `threads` threads (0: all cores).
inline voxmesh::Options cpu_options(double iso, unsigned threads) {
    voxmesh::Options o;
    o.iso = iso;
    o.backend = voxmesh::Backend::Cpu;
    o.threads = threads;
    return o;
}

// Converts a double to T: rounded and clamped for integer types.
template <class T>
T to_scalar(double v) {
    if constexpr (std::is_integral_v<T>) {
        const double lo = static_cast<double>(std::numeric_limits<T>::lowest());
        const double hi = static_cast<double>(std::numeric_limits<T>::max());
        double r = std::nearbyint(v);
        if (r < lo) r = lo;
        if (r > hi) r = hi;
        return static_cast<T>(r);
    } else {
        return static_cast<T>(v);
    }
}

// ------------------------------------------------------------------ fields

using FieldFn = std::function<double(double, double, double)>;  // sample coordinates (index space)

// f(x, y, z) at every sample, x fastest, stored as T; `scale` multiplies the value first.
template <class T>
std::vector<T> sample_field(const Dims& dims, const FieldFn& f, double scale = 1.0) {
    std::vector<T> out(dims[0] * dims[1] * dims[2]);
    std::size_t i = 0;
    for (std::size_t z = 0; z < dims[2]; ++z)
        for (std::size_t y = 0; y < dims[1]; ++y)
            for (std::size_t x = 0; x < dims[0]; ++x)
                out[i++] = to_scalar<T>(scale * f(static_cast<double>(x), static_cast<double>(y), static_cast<double>(z)));
    return out;
}

// High inside (value >= iso = 0 inside): radius - distance.
FieldFn sphere(std::array<double, 3> center, double radius);
// Torus around the z axis through `center`: minor radius - distance to the core circle.
FieldFn torus(std::array<double, 3> center, double major, double minor);
// Max of two spheres (disjoint when the centres are far enough apart).
FieldFn two_spheres(std::array<double, 3> c0, double r0, std::array<double, 3> c1, double r1);
// Smooth, surface-rich field (sum of sines), values in about [-3, 3].
FieldFn wavy(double frequency);

// Uniform random integers in [lo, hi] (inclusive) stored as T.
template <class T>
std::vector<T> random_field(const Dims& dims, std::uint32_t seed, int lo, int hi);
std::vector<double> random_doubles(const Dims& dims, std::uint32_t seed, int lo, int hi);

template <class T>
std::vector<T> random_field(const Dims& dims, std::uint32_t seed, int lo, int hi) {
    const std::vector<double> d = random_doubles(dims, seed, lo, hi);
    std::vector<T> out(d.size());
    for (std::size_t i = 0; i < d.size(); ++i) out[i] = to_scalar<T>(d[i]);
    return out;
}

template <class T>
std::vector<double> to_doubles(const std::vector<T>& v) {
    return std::vector<double>(v.begin(), v.end());
}

// ------------------------------------------------------------------ files

// The names in a directory, sorted.
std::vector<std::string> directory_entries(const std::string& dir);

// A fresh empty directory under the system temp dir, removed (recursively) on destruction.
class TempDir {
public:
    TempDir();
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::string& path() const { return path_; }
    std::string file(const std::string& name) const { return path_ + "/" + name; }
    std::vector<std::string> entries() const;  // directory_entries(path())

private:
    std::string path_;
};

// A small sphere (a few hundred triangles) meshed on the CPU engine, placed with spacing and
// origin that are not 1 and 0: what the mesh readers' round-trip tests write and read back.
voxmesh::Mesh small_sphere_mesh(bool normals);

}  // namespace vmtest
