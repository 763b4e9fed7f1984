// The library example for a service: bytes in, bytes out, no files. A volume file's bytes (as
// downloaded, or taken from a database) are read from memory, meshed, and the mesh returned as
// STL bytes (to send or store). Without an argument it makes those bytes itself: a NRRD of a
// 96^3 u8 ball, written to memory.
//
//   mesh_bytes [volume.nrrd|.nhdr|.mha|.nii|.nii.gz] [iso]
#include <voxmesh/io.hpp>
#include <voxmesh/voxmesh.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

// What a service would have been sent: here a file's bytes, or a NRRD made in memory.
std::vector<unsigned char> volume_bytes(int argc, char** argv, std::string& name) {
    if (argc > 1) {
        name = argv[1];
        std::ifstream in(name, std::ios::binary);
        if (!in) throw std::runtime_error("cannot open " + name);
        return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    }
    const std::size_t n = 96;
    std::vector<unsigned char> samples(n * n * n);
    for (std::size_t z = 0; z < n; ++z)
        for (std::size_t y = 0; y < n; ++y)
            for (std::size_t x = 0; x < n; ++x) {
                const double d = std::sqrt((x - 47.5) * (x - 47.5) + (y - 47.5) * (y - 47.5) + (z - 47.5) * (z - 47.5));
                samples[x + n * (y + n * z)] = d < 36 ? 200 : 20;  // a ball, 200 inside
            }
    voxmesh::VolumeView view;
    view.data = samples.data();
    view.type = voxmesh::ScalarType::U8;
    view.dims = {n, n, n};
    view.spacing = {0.5, 0.5, 0.5};
    name = "ball.nrrd";
    return voxmesh::write_nrrd_to_memory(view, name, {{"made by", "mesh_bytes"}});
}

}  // namespace

int main(int argc, char** argv) {
    try {
        std::string name;
        const std::vector<unsigned char> input = volume_bytes(argc, argv, name);

        // 1. Read from memory: the name's extension picks the format, errors start with it.
        voxmesh::VolumeInfo info;
        const voxmesh::Volume volume = voxmesh::read_volume_from_memory(input.data(), input.size(), name, info);
        std::printf("%s: %zu bytes of %s, %zux%zux%zu %s samples\n", name.c_str(), input.size(), info.format.c_str(),
                    volume.dims[0], volume.dims[1], volume.dims[2], voxmesh::scalar_name(volume.type));

        // 2. Mesh it.
        voxmesh::Options options;
        options.iso = argc > 2 ? std::stod(argv[2]) : 110;
        const voxmesh::Mesh mesh = voxmesh::extract(volume.view(), options);

        // 3. The mesh as STL bytes, and read back as a client would.
        const std::vector<unsigned char> stl = voxmesh::write_mesh_to_memory(mesh, "mesh.stl");
        const voxmesh::Mesh back = voxmesh::read_mesh_from_memory(stl.data(), stl.size(), "mesh.stl");
        const voxmesh::MeshTopology topology = voxmesh::analyze_topology(back);
        const std::string shape = topology.closed() ? "closed, euler " + std::to_string(topology.euler) : "open";
        std::printf("iso %g: %zu triangles, %zu bytes of STL; read back: %zu triangles, %s\n", options.iso,
                    mesh.triangle_count(), stl.size(), back.triangle_count(), shape.c_str());
        if (back.triangle_count() != mesh.triangle_count() || mesh.triangle_count() == 0) {
            std::fprintf(stderr, "mesh_bytes: the STL bytes did not read back as the mesh\n");
            return 1;
        }
        return argc > 1 || topology.closed() ? 0 : 1;  // the built-in ball is closed
    } catch (const std::exception& e) {
        std::fprintf(stderr, "mesh_bytes: %s\n", e.what());
        return 2;
    }
}
