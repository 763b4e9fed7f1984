// A small glTF 2.0 binary (.glb) reader for tests and fuzz targets: it follows the file's own
// references (scene -> node -> mesh -> accessor -> bufferView -> buffer) and checks on the way
// what the glTF 2.0 specification requires of each, throwing std::runtime_error naming the
// first rule broken. Only what voxmesh writes is read: one scene, one node, one primitive.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace vmtest {

struct GlbContents {
    voxmesh::Mesh mesh;
    int mode = -1;                 // the primitive's mode: 4 triangles, 0 points; -1 without one
    std::size_t meshes = 0;
    std::vector<double> min, max;  // POSITION's bounds as written
};

GlbContents read_glb(const std::string& bytes);

}  // namespace vmtest
