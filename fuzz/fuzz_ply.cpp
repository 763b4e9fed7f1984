// libFuzzer target: read_ply (ASCII and both binary byte orders); what it returns must be a
// well-formed mesh.
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string path = fuzz::input_file("input.ply", data, size);
    try {
        fuzz::check_mesh(voxmesh::read_ply(path));
    } catch (const voxmesh::Error&) {
    }
    return 0;
}
