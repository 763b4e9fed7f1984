// libFuzzer target: read_obj; what it returns must be a well-formed mesh with at least one
// triangle (a file without faces is an Error).
#include "fuzz_common.hpp"

#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string path = fuzz::input_file("input.obj", data, size);
    try {
        const voxmesh::Mesh mesh = voxmesh::read_obj(path);
        fuzz::check_mesh(mesh);
        if (mesh.indices.empty()) std::abort();
    } catch (const voxmesh::Error&) {
    }
    return 0;
}
