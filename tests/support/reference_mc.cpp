#include "support/reference_mc.hpp"

#include "core/case_tables.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

namespace vmtest {

const int kRefCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kRefEdge[12][2] = {{0, 1}, {1, 2}, {3, 2}, {0, 3}, {4, 5}, {5, 6}, {7, 6}, {4, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

namespace {

struct Grid {
    const std::vector<double>& v;
    Dims n;
    std::size_t index(std::size_t x, std::size_t y, std::size_t z) const { return x + n[0] * (y + n[1] * z); }
    double at(std::size_t x, std::size_t y, std::size_t z) const { return v[index(x, y, z)]; }
};

// Grid-edge id of cell edge e of the cell at (x, y, z): the lower corner owns the edge.
std::uint64_t edge_id(const Grid& g, std::size_t x, std::size_t y, std::size_t z, int e) {
    const int* a = kRefCorner[kRefEdge[e][0]];
    const int* b = kRefCorner[kRefEdge[e][1]];
    int axis = -1;
    int lo[3];
    for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(a[d], b[d]);
        if (a[d] != b[d]) axis = d;
    }
    const std::uint64_t sample = g.index(x + lo[0], y + lo[1], z + lo[2]);
    return sample * 3 + static_cast<std::uint64_t>(axis);
}

// Gradient at a sample: central differences inside, one-sided at the border, per unit length.
void gradient(const Grid& g, const std::array<double, 3>& spacing, std::size_t s[3], double out[3]) {
    for (int d = 0; d < 3; ++d) {
        std::size_t lo[3] = {s[0], s[1], s[2]}, hi[3] = {s[0], s[1], s[2]};
        double h = 0;
        if (s[d] > 0) {
            lo[d] -= 1;
            h += 1;
        }
        if (s[d] + 1 < g.n[d]) {
            hi[d] += 1;
            h += 1;
        }
        out[d] = (g.at(hi[0], hi[1], hi[2]) - g.at(lo[0], lo[1], lo[2])) / (h * spacing[d]);
    }
}

}  // namespace

unsigned reference_case(const std::vector<double>& values, const Dims& dims, std::size_t x, std::size_t y,
                        std::size_t z, double iso) {
    const Grid g{values, dims};
    unsigned code = 0;
    for (int c = 0; c < 8; ++c)
        if (g.at(x + kRefCorner[c][0], y + kRefCorner[c][1], z + kRefCorner[c][2]) >= iso) code |= 1u << c;
    return code;
}

RefMesh reference_mc(const std::vector<double>& values, const Dims& dims, const RefOptions& options) {
    if (dims[0] < 2 || dims[1] < 2 || dims[2] < 2) throw std::invalid_argument("reference_mc: dims < 2");
    if (values.size() != dims[0] * dims[1] * dims[2]) throw std::invalid_argument("reference_mc: size mismatch");
    const Grid g{values, dims};
    RefMesh mesh;

    // 1. Triangle soup, one cell at a time, in cell linear order.
    for (std::size_t z = 0; z + 1 < dims[2]; ++z)
        for (std::size_t y = 0; y + 1 < dims[1]; ++y)
            for (std::size_t x = 0; x + 1 < dims[0]; ++x) {
                const unsigned code = reference_case(values, dims, x, y, z, options.iso);
                const auto& entry = voxmesh::detail::kCaseTable[code];
                for (unsigned t = 0; t < entry.count; ++t) {
                    std::array<std::uint64_t, 3> tri;
                    for (int k = 0; k < 3; ++k) tri[k] = edge_id(g, x, y, z, entry.edges[3 * t + k]);
                    if (options.inside_below) std::swap(tri[1], tri[2]);
                    mesh.soup.push_back(tri);
                    mesh.cells.push_back(x + (dims[0] - 1) * (y + (dims[1] - 1) * z));
                }
            }

    // 2. Weld: distinct edge ids, ascending, are the vertices.
    for (const auto& tri : mesh.soup) mesh.edge_ids.insert(mesh.edge_ids.end(), tri.begin(), tri.end());
    std::sort(mesh.edge_ids.begin(), mesh.edge_ids.end());
    mesh.edge_ids.erase(std::unique(mesh.edge_ids.begin(), mesh.edge_ids.end()), mesh.edge_ids.end());
    for (const auto& tri : mesh.soup)
        for (std::uint64_t id : tri)
            mesh.indices.push_back(static_cast<std::uint32_t>(
                std::lower_bound(mesh.edge_ids.begin(), mesh.edge_ids.end(), id) - mesh.edge_ids.begin()));

    // 3. Vertex positions and normals, each from its own edge.
    const double sign = options.inside_below ? 1.0 : -1.0;
    for (std::uint64_t id : mesh.edge_ids) {
        const int axis = static_cast<int>(id % 3);
        std::uint64_t sample = id / 3;
        std::size_t s0[3];
        s0[0] = sample % dims[0];
        sample /= dims[0];
        s0[1] = sample % dims[1];
        s0[2] = sample / dims[1];
        std::size_t s1[3] = {s0[0], s0[1], s0[2]};
        s1[axis] += 1;
        const double v0 = g.at(s0[0], s0[1], s0[2]), v1 = g.at(s1[0], s1[1], s1[2]);
        if ((v0 >= options.iso) == (v1 >= options.iso)) throw std::logic_error("reference_mc: vertex on an uncrossed edge");
        const double t = (options.iso - v0) / (v1 - v0);
        for (int d = 0; d < 3; ++d)
            mesh.positions.push_back(options.origin[d] +
                                     (static_cast<double>(s0[d]) + (d == axis ? t : 0.0)) * options.spacing[d]);
        double g0[3], g1[3], n[3], len = 0;
        gradient(g, options.spacing, s0, g0);
        gradient(g, options.spacing, s1, g1);
        for (int d = 0; d < 3; ++d) {
            n[d] = sign * ((1 - t) * g0[d] + t * g1[d]);
            len += n[d] * n[d];
        }
        len = std::sqrt(len);
        for (int d = 0; d < 3; ++d) mesh.normals.push_back(len > 0 ? n[d] / len : 0.0);
    }
    return mesh;
}

}  // namespace vmtest

namespace vmtest {

namespace {

// Matches each engine vertex to the oracle vertex nearest in position (within a tolerance)
// and returns, per engine vertex, a cluster id: the smallest oracle index at that oracle
// position rounded to float. UINT64_MAX when nothing is near.
std::vector<std::uint64_t> match_by_position(const voxmesh::Mesh& mesh, const RefMesh& ref,
                                             std::vector<std::uint64_t>& ref_cluster) {
    using Key = std::array<long long, 3>;
    const double cell = 0.25;
    auto bucket = [cell](const double p[3]) {
        return Key{static_cast<long long>(std::floor(p[0] / cell)), static_cast<long long>(std::floor(p[1] / cell)),
                   static_cast<long long>(std::floor(p[2] / cell))};
    };
    std::map<Key, std::vector<std::uint32_t>> grid;
    // Vertices that coincide once stored as float (samples equal to iso, or t within a
    // float ulp of 0 or 1) form one cluster: the engine stores floats, so they are the same
    // point there.
    std::map<std::array<float, 3>, std::uint64_t> exact;
    ref_cluster.resize(ref.vertex_count());
    for (std::uint32_t i = 0; i < ref.vertex_count(); ++i) {
        const double* p = &ref.positions[3 * static_cast<std::size_t>(i)];
        grid[bucket(p)].push_back(i);
        const std::array<float, 3> key{static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
        ref_cluster[i] = exact.emplace(key, i).first->second;
    }
    std::vector<std::uint64_t> out(mesh.vertex_count(), std::numeric_limits<std::uint64_t>::max());
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
        const double p[3] = {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]};
        const Key k = bucket(p);
        double best = std::numeric_limits<double>::infinity();
        for (long long dz = -1; dz <= 1; ++dz)
            for (long long dy = -1; dy <= 1; ++dy)
                for (long long dx = -1; dx <= 1; ++dx) {
                    const auto it = grid.find(Key{k[0] + dx, k[1] + dy, k[2] + dz});
                    if (it == grid.end()) continue;
                    for (std::uint32_t i : it->second) {
                        const double* q = &ref.positions[3 * static_cast<std::size_t>(i)];
                        const double d = std::fabs(p[0] - q[0]) + std::fabs(p[1] - q[1]) + std::fabs(p[2] - q[2]);
                        const double tol = 1e-5 * (1 + std::fabs(q[0]) + std::fabs(q[1]) + std::fabs(q[2]));
                        if (d <= tol && d < best) {
                            best = d;
                            out[v] = ref_cluster[i];
                        }
                    }
                }
    }
    return out;
}

}  // namespace

Comparison compare_with_reference(const voxmesh::Mesh& mesh, const RefMesh& ref) {
    Comparison c;
    auto note = [&c](const std::string& s) {
        if (c.first_problem.empty()) c.first_problem = s;
    };
    const std::string structure = structural_problem(mesh);
    if (!structure.empty()) {
        note("engine mesh: " + structure);
        return c;
    }
    c.same_counts = mesh.vertex_count() == ref.vertex_count() && mesh.triangle_count() == ref.triangle_count();
    if (!c.same_counts)
        note("counts: engine " + std::to_string(mesh.vertex_count()) + " vertices / " +
             std::to_string(mesh.triangle_count()) + " triangles, oracle " + std::to_string(ref.vertex_count()) + " / " +
             std::to_string(ref.triangle_count()));

    std::vector<std::uint64_t> ref_cluster;
    const std::vector<std::uint64_t> engine_keys = match_by_position(mesh, ref, ref_cluster);
    for (std::size_t v = 0; v < engine_keys.size(); ++v)
        if (engine_keys[v] == std::numeric_limits<std::uint64_t>::max()) {
            note("engine vertex " + std::to_string(v) + " has no oracle vertex at its position");
            break;
        }
    c.same_triangle_set = triangle_set(mesh.indices, engine_keys, true) == triangle_set(ref.indices, ref_cluster, true);
    if (!c.same_triangle_set) note("oriented triangle sets differ");

    c.same_indices = mesh.indices == ref.indices;
    if (!c.same_indices) {
        for (std::size_t i = 0; i < std::min(mesh.indices.size(), ref.indices.size()); ++i)
            if (mesh.indices[i] != ref.indices[i]) {
                note("index buffers differ first at triangle " + std::to_string(i / 3) + ": engine " +
                     std::to_string(mesh.indices[i]) + ", oracle " + std::to_string(ref.indices[i]));
                break;
            }
        note("index buffers differ in length");
    }
    if (mesh.vertex_count() == ref.vertex_count()) {
        for (std::size_t i = 0; i < ref.positions.size(); ++i) {
            const double e = std::fabs(mesh.positions[i] - ref.positions[i]) / (1 + std::fabs(ref.positions[i]));
            c.max_position_error = std::max(c.max_position_error, e);
        }
        if (mesh.normals.size() == ref.normals.size()) {
            for (std::size_t v = 0; v < ref.vertex_count(); ++v) {
                const double* r = &ref.normals[3 * v];
                const float* n = &mesh.normals[3 * v];
                if (r[0] == 0 && r[1] == 0 && r[2] == 0) {
                    // Vanishing gradient: any unit vector will do.
                    const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
                    c.max_normal_error = std::max(c.max_normal_error, std::fabs(len - 1));
                    continue;
                }
                for (int d = 0; d < 3; ++d) c.max_normal_error = std::max(c.max_normal_error, std::fabs(n[d] - r[d]));
            }
        } else if (!mesh.normals.empty()) {
            note("normals size differs");
            c.max_normal_error = std::numeric_limits<double>::infinity();
        }
    } else {
        c.max_position_error = std::numeric_limits<double>::infinity();
    }
    return c;
}

}  // namespace vmtest
