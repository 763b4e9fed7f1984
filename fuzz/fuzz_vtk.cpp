// libFuzzer target: read_volume / read_volume_info on a legacy .vtk file (STRUCTURED_POINTS,
// BINARY and ASCII), and the *_from_memory readers on the same bytes, which must agree with them.
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::read_volume_input("input.vtk", data, size);
    return 0;
}
