#include "support/mesh_checks.hpp"

#include <algorithm>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <stdexcept>
#include <utility>

namespace vmtest {

namespace {

const float* vertex(const voxmesh::Mesh& mesh, std::uint32_t i) { return &mesh.positions[3 * static_cast<std::size_t>(i)]; }

}  // namespace

Topology topology(const voxmesh::Mesh& mesh) {
    Topology t;
    // Directed edges as (a << 32 | b); sorted, runs of equal values count the uses.
    std::vector<std::uint64_t> directed, undirected;
    directed.reserve(mesh.indices.size());
    undirected.reserve(mesh.indices.size());
    std::vector<char> used(mesh.vertex_count(), 0);
    for (std::size_t f = 0; f < mesh.triangle_count(); ++f) {
        const std::uint32_t v[3] = {mesh.indices[3 * f], mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]};
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) ++t.degenerate_triangles;
        std::uint64_t edges[3];  // this triangle's edges: distinct pairs of distinct corners
        std::size_t edge_count = 0;
        for (int k = 0; k < 3; ++k) {
            const std::uint64_t a = v[k], b = v[(k + 1) % 3];
            if (a < used.size()) used[a] = 1;
            directed.push_back(a << 32 | b);
            const std::uint64_t key = std::min(a, b) << 32 | std::max(a, b);
            if (a != b && std::find(edges, edges + edge_count, key) == edges + edge_count) edges[edge_count++] = key;
        }
        undirected.insert(undirected.end(), edges, edges + edge_count);
    }
    auto runs = [](std::vector<std::uint64_t>& keys, auto&& visit) {
        std::sort(keys.begin(), keys.end());
        std::size_t distinct = 0;
        for (std::size_t i = 0; i < keys.size();) {
            std::size_t j = i;
            while (j < keys.size() && keys[j] == keys[i]) ++j;
            visit(j - i);
            ++distinct;
            i = j;
        }
        return distinct;
    };
    t.edges = runs(undirected, [&](std::size_t count) {
        if (count == 1) ++t.boundary_edges;
        if (count >= 3) ++t.nonmanifold_edges;
    });
    runs(directed, [&](std::size_t count) {
        if (count > 1) ++t.repeated_directed_edges;
    });
    t.vertices_used = static_cast<std::size_t>(std::count(used.begin(), used.end(), 1));
    t.euler = static_cast<long long>(t.vertices_used) - static_cast<long long>(t.edges) +
              static_cast<long long>(mesh.triangle_count());
    return t;
}

double surface_area(const voxmesh::Mesh& mesh) {
    double area = 0;
    for (std::size_t f = 0; f < mesh.triangle_count(); ++f) {
        const float* a = vertex(mesh, mesh.indices[3 * f]);
        const float* b = vertex(mesh, mesh.indices[3 * f + 1]);
        const float* c = vertex(mesh, mesh.indices[3 * f + 2]);
        const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
        const double w[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
        const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        area += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return area;
}

double signed_volume(const voxmesh::Mesh& mesh) {
    double vol = 0;
    for (std::size_t f = 0; f < mesh.triangle_count(); ++f) {
        const float* a = vertex(mesh, mesh.indices[3 * f]);
        const float* b = vertex(mesh, mesh.indices[3 * f + 1]);
        const float* c = vertex(mesh, mesh.indices[3 * f + 2]);
        // a . (b x c) / 6
        const double bc[3] = {double(b[1]) * c[2] - double(b[2]) * c[1], double(b[2]) * c[0] - double(b[0]) * c[2],
                              double(b[0]) * c[1] - double(b[1]) * c[0]};
        vol += (a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2]) / 6.0;
    }
    return vol;
}

double max_normal_length_error(const voxmesh::Mesh& mesh) {
    double worst = 0;
    for (std::size_t i = 0; i + 2 < mesh.normals.size(); i += 3) {
        const double len = std::sqrt(double(mesh.normals[i]) * mesh.normals[i] +
                                     double(mesh.normals[i + 1]) * mesh.normals[i + 1] +
                                     double(mesh.normals[i + 2]) * mesh.normals[i + 2]);
        worst = std::max(worst, std::fabs(len - 1.0));
        if (!std::isfinite(len)) return std::numeric_limits<double>::infinity();
    }
    return worst;
}

std::string structural_problem(const voxmesh::Mesh& mesh) {
    if (mesh.positions.size() % 3) return "positions size is not a multiple of 3";
    if (mesh.indices.size() % 3) return "indices size is not a multiple of 3";
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size()) return "normals size != positions size";
    for (std::size_t i = 0; i < mesh.indices.size(); ++i)
        if (mesh.indices[i] >= mesh.vertex_count())
            return "index " + std::to_string(i) + " = " + std::to_string(mesh.indices[i]) + " out of range";
    for (float p : mesh.positions)
        if (!std::isfinite(p)) return "non-finite position";
    for (float n : mesh.normals)
        if (!std::isfinite(n)) return "non-finite normal";
    return "";
}

TriKey oriented_key(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
    if (b < a && b <= c) return {b, c, a};
    if (c < a && c < b) return {c, a, b};
    return {a, b, c};
}

TriKey unoriented_key(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
    TriKey k{a, b, c};
    std::sort(k.begin(), k.end());
    return k;
}

std::vector<TriKey> triangle_set(const std::vector<std::uint32_t>& indices, const std::vector<std::uint64_t>& vertex_key,
                                 bool oriented) {
    std::vector<TriKey> keys;
    keys.reserve(indices.size() / 3);
    auto key_of = [&](std::uint32_t i) {
        return i < vertex_key.size() ? vertex_key[i] : std::numeric_limits<std::uint64_t>::max();
    };
    for (std::size_t f = 0; f + 2 < indices.size(); f += 3) {
        const std::uint64_t a = key_of(indices[f]), b = key_of(indices[f + 1]), c = key_of(indices[f + 2]);
        keys.push_back(oriented ? oriented_key(a, b, c) : unoriented_key(a, b, c));
    }
    std::sort(keys.begin(), keys.end());
    return keys;
}

std::vector<std::uint64_t> edge_keys_from_positions(const voxmesh::Mesh& mesh, const Dims& dims,
                                                    const std::array<double, 3>& spacing,
                                                    const std::array<double, 3>& origin) {
    std::vector<std::uint64_t> keys(mesh.vertex_count(), std::numeric_limits<std::uint64_t>::max());
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
        double q[3], frac[3];
        int axis = -1;
        double best = 0;
        for (int d = 0; d < 3; ++d) {
            q[d] = (mesh.positions[3 * v + d] - origin[d]) / spacing[d];
            frac[d] = std::fabs(q[d] - std::nearbyint(q[d]));
            if (frac[d] > best) {
                best = frac[d];
                axis = d;
            }
        }
        if (axis < 0 || best < 1e-4) continue;  // on a sample: ambiguous
        bool ok = true;
        std::size_t idx[3];
        for (int d = 0; d < 3; ++d) {
            if (d != axis && frac[d] > 1e-4) ok = false;
            const double base = d == axis ? std::floor(q[d]) : std::nearbyint(q[d]);
            if (base < 0 || base >= static_cast<double>(dims[d])) ok = false;
            idx[d] = ok ? static_cast<std::size_t>(base) : 0;
        }
        if (!ok) continue;
        const std::uint64_t sample = idx[0] + dims[0] * (idx[1] + dims[1] * idx[2]);
        keys[v] = sample * 3 + static_cast<std::uint64_t>(axis);
    }
    return keys;
}

FieldFn sphere(std::array<double, 3> c, double r) {
    return [c, r](double x, double y, double z) {
        return r - std::sqrt((x - c[0]) * (x - c[0]) + (y - c[1]) * (y - c[1]) + (z - c[2]) * (z - c[2]));
    };
}

FieldFn torus(std::array<double, 3> c, double major, double minor) {
    return [c, major, minor](double x, double y, double z) {
        const double dx = x - c[0], dy = y - c[1], dz = z - c[2];
        const double ring = std::sqrt(dx * dx + dy * dy) - major;
        return minor - std::sqrt(ring * ring + dz * dz);
    };
}

FieldFn two_spheres(std::array<double, 3> c0, double r0, std::array<double, 3> c1, double r1) {
    FieldFn a = sphere(c0, r0), b = sphere(c1, r1);
    return [a, b](double x, double y, double z) { return std::max(a(x, y, z), b(x, y, z)); };
}

FieldFn wavy(double k) {
    return [k](double x, double y, double z) {
        return std::sin(k * x) * std::cos(0.7 * k * y) + std::sin(1.3 * k * z + 0.5) + 0.5 * std::cos(k * (x + y - z));
    };
}

std::vector<double> random_doubles(const Dims& dims, std::uint32_t seed, int lo, int hi) {
    std::mt19937 rng(seed);
    // Not std::uniform_int_distribution: its output differs between standard libraries.
    const std::uint32_t span = static_cast<std::uint32_t>(hi - lo + 1);
    std::vector<double> out(dims[0] * dims[1] * dims[2]);
    for (double& v : out) v = lo + static_cast<int>(rng() % span);
    return out;
}

TempDir::TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "voxmesh-test-XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
}

TempDir::~TempDir() {
    std::error_code ec;
    std::filesystem::permissions(path_, std::filesystem::perms::owner_all, std::filesystem::perm_options::add, ec);
    std::filesystem::remove_all(path_, ec);
}

std::vector<std::string> directory_entries(const std::string& dir) {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::vector<std::string> TempDir::entries() const { return directory_entries(path_); }

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

std::vector<std::array<float, 9>> triangle_corners(const voxmesh::Mesh& mesh) {
    std::vector<std::array<float, 9>> out(mesh.triangle_count());
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
        for (std::size_t k = 0; k < 3; ++k)
            for (std::size_t c = 0; c < 3; ++c) out[t][3 * k + c] = mesh.positions[3 * mesh.indices[3 * t + k] + c];
    return out;
}

std::vector<std::size_t> oracle_pieces(const voxmesh::Mesh& m, std::size_t& piece_count) {
    std::vector<std::vector<std::size_t>> triangles_at(m.vertex_count());
    for (std::size_t t = 0; t < m.triangle_count(); ++t)
        for (int k = 0; k < 3; ++k) triangles_at[m.indices[3 * t + k]].push_back(t);
    const std::size_t none = static_cast<std::size_t>(-1);
    std::vector<std::size_t> piece(m.triangle_count(), none);
    piece_count = 0;
    for (std::size_t start = 0; start < m.triangle_count(); ++start) {
        if (piece[start] != none) continue;
        std::vector<std::size_t> todo{start};
        piece[start] = piece_count;
        while (!todo.empty()) {
            const std::size_t t = todo.back();
            todo.pop_back();
            for (int k = 0; k < 3; ++k)
                for (std::size_t u : triangles_at[m.indices[3 * t + k]])
                    if (piece[u] == none) {
                        piece[u] = piece_count;
                        todo.push_back(u);
                    }
        }
        ++piece_count;
    }
    return piece;
}

voxmesh::Mesh oracle_keep_largest(const voxmesh::Mesh& m, std::size_t count) {
    std::size_t pieces = 0;
    const std::vector<std::size_t> piece = oracle_pieces(m, pieces);
    std::vector<std::size_t> size(pieces, 0);
    for (std::size_t p : piece) ++size[p];
    std::vector<bool> keep(pieces, false);
    for (std::size_t kept = 0; kept < count && kept < pieces; ++kept) {
        std::size_t best = 0;  // the largest not kept yet; the lowest-numbered of equals
        while (keep[best]) ++best;
        for (std::size_t p = best + 1; p < pieces; ++p)
            if (!keep[p] && size[p] > size[best]) best = p;
        keep[best] = true;
    }
    std::map<std::uint32_t, std::uint32_t> renumber;  // old vertex -> new, in old order
    for (std::size_t t = 0; t < m.triangle_count(); ++t)
        if (keep[piece[t]])
            for (int k = 0; k < 3; ++k) renumber[m.indices[3 * t + k]] = 0;
    voxmesh::Mesh out;
    std::uint32_t next = 0;
    for (auto& [old, fresh] : renumber) {
        fresh = next++;
        for (int c = 0; c < 3; ++c) {
            out.positions.push_back(m.positions[3 * old + c]);
            if (!m.normals.empty()) out.normals.push_back(m.normals[3 * old + c]);
        }
    }
    for (std::size_t t = 0; t < m.triangle_count(); ++t)
        if (keep[piece[t]])
            for (int k = 0; k < 3; ++k) out.indices.push_back(renumber[m.indices[3 * t + k]]);
    return out;
}

voxmesh::Mesh small_sphere_mesh(bool normals) {
    const Dims dims{17, 15, 13};
    const std::vector<float> values = sample_field<float>(dims, sphere({8.2, 7.1, 6.3}, 5.1));
    voxmesh::Options o;
    o.backend = voxmesh::Backend::Cpu;
    o.normals = normals;
    return voxmesh::extract(view_of(values, dims, {0.5, 0.75, 1.0}, {-2.5, 1.0, 100.0}), o);
}

}  // namespace vmtest
