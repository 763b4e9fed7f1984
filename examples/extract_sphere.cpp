// The library example: mesh a 256^3 float sphere with voxmesh::extract on 1 and 2 threads,
// check that both give the same canonical mesh and that it is closed, and optionally write
// it as PLY.
//
//   extract_sphere [out.ply]
#include <voxmesh/voxmesh.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <vector>

int main(int argc, char** argv) {
    try {
        // 1. A volume: x-fastest float samples, high inside (value >= iso is inside).
        const std::size_t n = 256;
        const double c = (n - 1) / 2.0, radius = 0.4 * n;
        std::vector<float> samples(n * n * n);
        for (std::size_t z = 0; z < n; ++z)
            for (std::size_t y = 0; y < n; ++y)
                for (std::size_t x = 0; x < n; ++x) {
                    const double dx = x - c, dy = y - c, dz = z - c;
                    samples[x + n * (y + n * z)] = static_cast<float>(radius - std::sqrt(dx * dx + dy * dy + dz * dz));
                }

        // 2. A non-owning view of it: type, dims, and (optionally) spacing and origin.
        voxmesh::VolumeView volume;
        volume.data = samples.data();
        volume.type = voxmesh::ScalarType::F32;
        volume.dims = {n, n, n};
        volume.spacing = {1.0, 1.0, 1.0};

        // 3. Mesh it on the CPU engine with 1 and with 2 threads.
        voxmesh::Options options;
        options.iso = 0.0;
        options.backend = voxmesh::Backend::Cpu;
        voxmesh::Mesh meshes[2];
        for (unsigned threads : {1u, 2u}) {
            options.threads = threads;
            voxmesh::Stats stats;
            const auto t0 = std::chrono::steady_clock::now();
            meshes[threads - 1] = voxmesh::extract(volume, options, stats);
            const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            std::printf("%u thread%s: %zu vertices, %zu triangles in %.1f ms "
                        "(classify %.1f, scan %.1f, generate %.1f ms)\n",
                        threads, threads == 1 ? " " : "s", meshes[threads - 1].vertex_count(),
                        meshes[threads - 1].triangle_count(), ms, 1e3 * stats.times.classify, 1e3 * stats.times.scan,
                        1e3 * stats.times.generate);
        }

        // 4. The canonical mesh does not depend on the thread count.
        const voxmesh::Mesh& mesh = meshes[0];
        const bool same_indices = meshes[0].indices == meshes[1].indices;
        const bool same_positions =
            meshes[0].positions.size() == meshes[1].positions.size() &&
            std::memcmp(meshes[0].positions.data(), meshes[1].positions.data(),
                        meshes[0].positions.size() * sizeof(float)) == 0;
        const voxmesh::MeshTopology topology = voxmesh::analyze_topology(mesh);
        std::printf("index buffers identical: %s, positions identical: %s\n", same_indices ? "yes" : "NO",
                    same_positions ? "yes" : "NO");
        std::printf("closed: %s (boundary edges %zu, non-manifold edges %zu), Euler characteristic %lld, %zu piece%s\n",
                    topology.closed() ? "yes" : "NO", topology.boundary_edges, topology.nonmanifold_edges,
                    topology.euler, topology.components, topology.components == 1 ? "" : "s");
        // One piece: keeping the largest keeps it all (a CT's surface would shed its noise here).
        const bool one_piece = topology.components == 1 &&
                               voxmesh::keep_largest_components(mesh).indices == mesh.indices;

        // 5. Optionally write it (.ply, .stl or .obj by extension).
        if (argc > 1) {
            voxmesh::write_mesh(argv[1], mesh);
            std::printf("wrote %s\n", argv[1]);
        }
        const bool ok = same_indices && same_positions && topology.closed() && topology.euler == 2 && one_piece &&
                        mesh.triangle_count() > 0;
        std::printf("%s\n", ok ? "OK" : "FAILED");
        return ok ? 0 : 1;
    } catch (const voxmesh::Error& e) {
        std::fprintf(stderr, "voxmesh error: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
}
