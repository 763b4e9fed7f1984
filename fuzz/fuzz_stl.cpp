// libFuzzer target: read_stl (binary and ASCII), plus a check that every index is in range.
#include "fuzz_common.hpp"

#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string path = fuzz::input_file("input.stl", data, size);
    try {
        const voxmesh::Mesh mesh = voxmesh::read_stl(path);
        if (mesh.indices.size() % 3 != 0 || mesh.positions.size() % 3 != 0) std::abort();
        for (std::uint32_t i : mesh.indices)
            if (i >= mesh.vertex_count()) std::abort();
    } catch (const voxmesh::Error&) {
    }
    return 0;
}
