// write_mesh to .glb and .ply of the same mesh (gyroid u8 512³, 10.1 M triangles) in a loop in
// one process, and glb_json alone (the positions' bounds), seconds per call. Build from the
// repository root after `bash scripts/test.sh build`:
//   g++ -O2 -std=c++20 -Iinclude -Isrc -Ibuild/include bench/results/session55/glb_write.cpp \
//       -o /tmp/glb_write build/src/libvoxmesh.a -lOpenCL -lz -lpthread && /tmp/glb_write
#include "core/glb_writer.hpp"

#include <voxmesh/fields.hpp>
#include <voxmesh/voxmesh.hpp>

#include <chrono>
#include <cstdio>

int main() {
    const voxmesh::FieldVolume fv = voxmesh::make_field(voxmesh::Field::Gyroid, 512, voxmesh::ScalarType::U8, 1);
    voxmesh::Options o;
    o.iso = fv.iso;
    const voxmesh::Mesh m = voxmesh::extract(fv.volume.view(), o);
    const auto seconds = [](auto&& f) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    for (int r = 0; r < 5; ++r) {
        const double json = seconds([&] { (void)voxmesh::detail::glb_json(m); });
        const double glb = seconds([&] { voxmesh::write_mesh("/tmp/glb_write.glb", m); });
        const double ply = seconds([&] { voxmesh::write_mesh("/tmp/glb_write.ply", m); });
        std::printf("round %d: glb_json %.4f  write .glb %.4f  write .ply %.4f\n", r + 1, json, glb, ply);
    }
    std::remove("/tmp/glb_write.glb");
    std::remove("/tmp/glb_write.ply");
}
