// libFuzzer target: read_volume / read_volume_info on a NumPy .npy file (format 1.0 to 3.0, any
// byte order and axis order), and the *_from_memory readers on the same bytes, which must agree.
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::read_volume_input("input.npy", data, size);
    return 0;
}
