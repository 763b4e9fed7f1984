// The volume files voxmesh-bench writes for bench/peers: NRRD through the library's writer,
// with the field's iso as a key/value pair, so every tool meshes the same samples at the same iso.
#include "bench.hpp"

#include <voxmesh/io.hpp>

#include <cstdio>

namespace vmbench {

void write_volume_nrrd(const std::string& path, const Input& input) {
    char iso[64];
    std::snprintf(iso, sizeof iso, "%.17g", input.iso);
    voxmesh::write_nrrd(path, input.volume.view(), {{"voxmesh_field", input.field}, {"voxmesh_iso", iso}});
}

bool read_nrrd_iso(const std::string& path, double& iso) {
    const voxmesh::VolumeInfo info = voxmesh::read_volume_info(path);
    const auto it = info.key_values.find("voxmesh_iso");
    if (it == info.key_values.end()) return false;
    char* end = nullptr;
    iso = std::strtod(it->second.c_str(), &end);
    return end != it->second.c_str();
}

}  // namespace vmbench
