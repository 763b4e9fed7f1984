// libFuzzer target: read_stl (binary and ASCII); what it returns must be a well-formed mesh
// with at least one triangle (a file without any is an Error), and read_mesh_from_memory on the
// same bytes must give the same mesh or the same Error.
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::read_mesh_input("input.stl", data, size);
    return 0;
}
