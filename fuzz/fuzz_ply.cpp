// libFuzzer target: read_ply (ASCII and both binary byte orders); what it returns must be a
// well-formed mesh (a point cloud, without triangles, is one), and read_mesh_from_memory on the
// same bytes must give the same mesh or the same Error.
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::read_mesh_input("input.ply", data, size);
    return 0;
}
