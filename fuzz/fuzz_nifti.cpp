// libFuzzer target: read_volume / read_volume_info on a .nii file.
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::read_volume_file(fuzz::input_file("input.nii", data, size));
    return 0;
}
