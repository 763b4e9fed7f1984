// What every fuzz target shares. Each input is written to a file in a private scratch
// directory and read back through the public API (the readers map files and open detached
// data files): the whole path is fuzzed, not just the header parser. The readers also take
// the same bytes from memory (*_from_memory), which must give the same result or the same
// Error, word for word.
#pragma once

#include <voxmesh/io.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fuzz {

// The scratch directory, created once per process with a companion "data.bin" (a few KB
// of varied bytes) that inputs can name as a detached data file. Removed at exit.
inline const std::string& scratch_dir() {
    static const std::string dir = [] {
        std::string pattern = (std::filesystem::temp_directory_path() / "voxmesh_fuzz_XXXXXX").string();
        if (!mkdtemp(pattern.data())) std::abort();
        std::FILE* f = std::fopen((pattern + "/data.bin").c_str(), "wb");
        if (!f) std::abort();
        for (unsigned i = 0; i < 4096; ++i) std::fputc(static_cast<int>((i * 37u) ^ (i >> 3)) & 0xff, f);
        std::fclose(f);
        static const std::string keep = pattern;
        std::atexit([] {
            std::error_code ec;
            std::filesystem::remove_all(keep, ec);
        });
        return pattern;
    }();
    return dir;
}

// Writes the input to scratch_dir()/name and returns its path.
inline std::string input_file(const char* name, const std::uint8_t* data, std::size_t size) {
    const std::string path = scratch_dir() + "/" + name;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) std::abort();
    if (size && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
    return path;
}

// Reads every byte of a loaded volume, so a mapping or buffer shorter than its dims shows up
// under ASan (or as SIGSEGV/SIGBUS for a mapping).
inline void touch(const voxmesh::Volume& v) {
    const auto* p = static_cast<const volatile unsigned char*>(v.data);
    unsigned sum = 0;
    for (std::size_t i = 0, n = v.byte_size(); i < n; ++i) sum += p[i];
    static volatile unsigned sink;
    sink = sum;
}

// f()'s Error message, or nothing when it returned.
template <class F>
std::optional<std::string> error_of(F&& f) {
    try {
        f();
        return std::nullopt;
    } catch (const voxmesh::Error& e) {
        return std::string(e.what());
    }
}

// The file's outcome and the memory's must agree: both fail with one message, or both read.
// Only memory refuses a header naming a separate data file.
inline void check_same_outcome(const std::optional<std::string>& file, const std::optional<std::string>& memory) {
    if (memory && memory->find("separate data file") != std::string::npos) return;
    if (file != memory) std::abort();
}

inline bool same_volume(const voxmesh::Volume& a, const voxmesh::Volume& b) {
    return a.type == b.type && a.dims == b.dims && a.spacing == b.spacing && a.origin == b.origin &&
           std::memcmp(a.data, b.data, a.byte_size()) == 0;
}

// Reads a volume input (written to scratch_dir()/name) with read_volume_info and read_volume,
// and from memory; voxmesh::Error is the expected outcome for bad input, and anything else
// (another exception, a crash, a sanitizer report, the two ways disagreeing) is a finding.
inline void read_volume_input(const char* name, const std::uint8_t* data, std::size_t size) {
    const std::string path = input_file(name, data, size);
    voxmesh::VolumeInfo info, memory_info;
    voxmesh::Volume v, memory_v;
    const auto info_error = error_of([&] { info = voxmesh::read_volume_info(path); });
    const auto memory_info_error =
        error_of([&] { memory_info = voxmesh::read_volume_info_from_memory(data, size, path); });
    const auto error = error_of([&] { v = voxmesh::read_volume(path); });
    const auto memory_error = error_of([&] { memory_v = voxmesh::read_volume_from_memory(data, size, path); });
    voxmesh::Volume handed_v;  // the bytes handed over, used in place where a file is mapped
    const auto handed_error = error_of(
        [&] { handed_v = voxmesh::read_volume_from_memory(std::vector<unsigned char>(data, data + size), path); });
    check_same_outcome(info_error, memory_info_error);
    check_same_outcome(error, memory_error);
    if (memory_error != handed_error) std::abort();
    if (error) return;
    touch(v);
    if (!info_error && (v.dims != info.dims || v.type != info.type)) std::abort();  // info and load must agree
    if (!memory_error && (!same_volume(v, memory_v) || !same_volume(v, handed_v))) std::abort();
}

// What a mesh reader returns must be a well-formed mesh: whole triples, normals for every
// vertex or none, every index in range, every coordinate and normal finite.
inline void check_mesh(const voxmesh::Mesh& mesh) {
    if (mesh.indices.size() % 3 != 0 || mesh.positions.size() % 3 != 0) std::abort();
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size()) std::abort();
    for (std::uint32_t i : mesh.indices)
        if (i >= mesh.vertex_count()) std::abort();
    for (float v : mesh.positions)
        if (!std::isfinite(v)) std::abort();
    for (float v : mesh.normals)
        if (!std::isfinite(v)) std::abort();
}

// Reads `data` as a mesh file named `name` (its extension picks the reader), and from memory:
// a well-formed mesh (no triangles is one, in every format) or an Error, nothing else, and the
// same either way.
inline void read_mesh_input(const char* name, const std::uint8_t* data, std::size_t size) {
    const std::string path = input_file(name, data, size);
    voxmesh::Mesh mesh, memory_mesh;
    const auto error = error_of([&] { mesh = voxmesh::read_mesh(path); });
    const auto memory_error = error_of([&] { memory_mesh = voxmesh::read_mesh_from_memory(data, size, path); });
    check_same_outcome(error, memory_error);
    if (error) return;
    check_mesh(mesh);
    if (mesh.positions != memory_mesh.positions || mesh.normals != memory_mesh.normals ||
        mesh.indices != memory_mesh.indices)
        std::abort();
}

// extract() of a volume the library made (a sculpt's, voxelize's), on the CPU engine and one
// thread: it must mesh it, so an Error is a finding.
inline voxmesh::Mesh extract_or_abort(const voxmesh::VolumeView& volume, double iso) {
    voxmesh::Options options;
    options.iso = iso;
    options.backend = voxmesh::Backend::Cpu;
    options.threads = 1;
    try {
        return voxmesh::extract(volume, options);
    } catch (const voxmesh::Error&) {
        std::abort();
    }
}

}  // namespace fuzz
