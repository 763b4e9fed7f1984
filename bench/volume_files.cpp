// The volume files voxmesh-bench writes for bench/peers: NRRD through the library's writer,
// with the field's iso as a key/value pair, so every tool meshes the same samples at the same iso.
#include "bench.hpp"

#include <voxmesh/io.hpp>

#include <cstdio>

namespace vmbench {

void write_volume_nrrd(const std::string& path, const Input& input) {
    char iso[64];
    std::snprintf(iso, sizeof iso, "%.17g", input.iso);
    voxmesh::write_nrrd(path, input.volume.view(), {{"voxmesh_field", input.field}, {voxmesh::kRecordedIsoKey, iso}});
}

}  // namespace vmbench
