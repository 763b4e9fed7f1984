// libFuzzer target: write_nrrd, then read_volume of what it wrote. Whatever volume, geometry
// and key/value lines the writer accepts, the reader must give back exactly: type, dims,
// samples byte for byte, key/values, and spacing and origin (negative spacings flip an axis:
// the reader reverses it and moves the origin to the minimum corner). The input is a header
// (type, dims, 6 doubles of geometry), a key and a value separated by a 0 byte, then samples.
// write_nrrd_to_memory must give the file's bytes (or write_nrrd's refusal), and
// read_volume_from_memory of them the volume read_volume gives.
#include "fuzz_common.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    constexpr std::size_t kHeader = 4 + 6 * sizeof(double);
    if (size < kHeader) return 0;
    constexpr voxmesh::ScalarType kTypes[] = {voxmesh::ScalarType::U8,  voxmesh::ScalarType::I8,
                                              voxmesh::ScalarType::U16, voxmesh::ScalarType::I16,
                                              voxmesh::ScalarType::U32, voxmesh::ScalarType::I32,
                                              voxmesh::ScalarType::F32, voxmesh::ScalarType::F64};
    voxmesh::VolumeView view;
    view.type = kTypes[data[0] % 8];
    view.dims = {1 + data[1] % 9u, 1 + data[2] % 9u, 1 + data[3] % 9u};
    std::memcpy(view.spacing.data(), data + 4, 3 * sizeof(double));
    std::memcpy(view.origin.data(), data + 4 + 3 * sizeof(double), 3 * sizeof(double));

    const char* rest = reinterpret_cast<const char*>(data + kHeader);
    const std::size_t rest_size = size - kHeader;
    const std::string text(rest, std::min<std::size_t>(rest_size, 64));
    const std::size_t split = text.find('\0');
    std::map<std::string, std::string> key_values;
    if (split != std::string::npos) key_values[text.substr(0, split)] = text.substr(split + 1);

    const std::size_t bytes = view.dims[0] * view.dims[1] * view.dims[2] * voxmesh::scalar_size(view.type);
    std::vector<double> storage(bytes / sizeof(double) + 1, 0.0);  // aligned for every type
    std::memcpy(storage.data(), rest, std::min(bytes, rest_size));
    view.data = storage.data();

    const std::string path = fuzz::scratch_dir() + "/roundtrip.nrrd";
    std::vector<unsigned char> in_memory;
    const auto memory_error = fuzz::error_of([&] { in_memory = voxmesh::write_nrrd_to_memory(view, path, key_values); });
    const auto error = fuzz::error_of([&] { voxmesh::write_nrrd(path, view, key_values); });
    if (error != memory_error) std::abort();
    if (error) return 0;  // refused with a message: bad geometry or key/value
    std::ifstream file(path, std::ios::binary);
    if (std::string{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()} !=
        std::string(in_memory.begin(), in_memory.end()))
        std::abort();
    voxmesh::VolumeInfo info;
    voxmesh::Volume back, back_from_memory;
    try {
        back = voxmesh::read_volume(path, info);
        back_from_memory = voxmesh::read_volume_from_memory(in_memory.data(), in_memory.size(), path);
    } catch (const voxmesh::Error&) {
        std::abort();  // the writer wrote what the reader refuses
    }
    if (!fuzz::same_volume(back, back_from_memory)) std::abort();
    if (back.type != view.type || back.dims != view.dims || back.byte_size() != bytes) std::abort();
    for (const auto& [key, value] : key_values) {
        const auto it = info.key_values.find(key);
        if (it == info.key_values.end() || it->second != value) std::abort();
    }
    // Where an axis was flipped, sample i of the file is sample n-1-i of the volume read.
    const std::size_t value_size = voxmesh::scalar_size(view.type);
    const auto* want = reinterpret_cast<const unsigned char*>(view.data);
    const auto* got = static_cast<const unsigned char*>(back.data);
    for (std::size_t z = 0; z < view.dims[2]; ++z)
        for (std::size_t y = 0; y < view.dims[1]; ++y)
            for (std::size_t x = 0; x < view.dims[0]; ++x) {
                const std::size_t p[3] = {x, y, z};
                std::size_t f[3];
                for (int a = 0; a < 3; ++a) f[a] = view.spacing[a] < 0 ? view.dims[a] - 1 - p[a] : p[a];
                const std::size_t at = x + view.dims[0] * (y + view.dims[1] * z);
                const std::size_t from = f[0] + view.dims[0] * (f[1] + view.dims[1] * f[2]);
                if (std::memcmp(got + at * value_size, want + from * value_size, value_size) != 0) std::abort();
            }
    for (int a = 0; a < 3; ++a) {
        if (back.spacing[a] != std::fabs(view.spacing[a])) std::abort();
        const double corner = view.spacing[a] < 0 ? view.origin[a] + view.spacing[a] * double(view.dims[a] - 1)
                                                  : view.origin[a];
        if (back.origin[a] != corner) std::abort();
    }
    return 0;
}
