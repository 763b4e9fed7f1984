// Opening input files safely: regular files only (a directory, FIFO or device is refused
// before anything blocks on it), with errors that name the path. An InputFile can also stand
// for bytes in memory (the *_from_memory readers), so every reader has one way in.
#pragma once

#include "core/out_of_memory.hpp"

#include <algorithm>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace voxmesh::io {

// Throws Error("'path': what").
[[noreturn]] void fail(const std::string& path, const std::string& what);

// Makes InputFile::map() behave as if mmap failed, so tests reach the read fallback.
void refuse_mmap_for_testing(bool refuse);

class InputFile {
public:
    explicit InputFile(const std::string& path);
    // `size` bytes at `data`, named `name` in errors. Not copied: they must outlive this object.
    InputFile(const std::string& name, const void* data, std::size_t size);
    // Bytes handed over: map() gives them out, to be written in place, instead of a copy.
    InputFile(const std::string& name, std::shared_ptr<unsigned char> owned, std::size_t size);
    ~InputFile();
    InputFile(const InputFile&) = delete;
    InputFile& operator=(const InputFile&) = delete;

    const std::string& path() const { return path_; }
    std::size_t size() const { return size_; }
    // Bytes in memory, not a file: there is no directory to find a detached data file in.
    bool in_memory() const { return memory_ != nullptr; }
    // map() costs no copy: a file (mapped) or bytes handed over.
    bool maps_in_place() const { return !in_memory() || owned_ != nullptr; }

    // Up to `max_bytes` bytes from `offset` (fewer at the end of the file).
    std::string read(std::size_t offset, std::size_t max_bytes) const;
    // Exactly `bytes` bytes into `out`; throws on a short read.
    void read_exact(std::size_t offset, void* out, std::size_t bytes) const;
    // The whole file, mapped private and writable (copy-on-write); the pointer owns the
    // mapping. Where the file cannot be mapped, a heap copy of it (at least 16-byte aligned).
    // Throws for an empty file. In memory: the bytes handed over, else a heap copy, so that
    // writes never reach the caller's bytes.
    std::shared_ptr<unsigned char> map() const;
    // The whole file to read only: map() for a file, the caller's bytes (not owned, not copied)
    // in memory. Throws for an empty file.
    std::shared_ptr<const unsigned char> view() const;

private:
    std::shared_ptr<unsigned char> copy() const;

    std::string path_;
    int fd_ = -1;
    const unsigned char* memory_ = nullptr;
    std::shared_ptr<unsigned char> owned_;  // memory_, when handed over
    std::size_t size_ = 0;
};

// A whole file mapped for a parser that reads it as bytes or as text (the mesh readers);
// an empty file is an Error naming it.
struct MappedFile {
    std::shared_ptr<const unsigned char> mapping;
    std::string_view text;  // all of it
    const unsigned char* bytes() const { return mapping.get(); }
};
MappedFile map_whole_file(const InputFile& file);

// The machine's physical memory in bytes (SIZE_MAX when the system does not say).
std::size_t physical_memory();
// Bytes of memory the system can give us now (MemAvailable, else physical memory).
std::size_t available_memory();
// Throws when `bytes` exceed available_memory(), before anything is allocated.
void check_memory(const std::string& path, std::size_t bytes);

// Makes room for `total` items in `v` (at least doubling, as push_back would), checking the
// memory available first: for arrays that a file's content, not a checked header count,
// makes larger (a mesh reader's indices from polygons of many corners).
template <class T>
void reserve_checked(const std::string& path, std::vector<T>& v, std::size_t total) {
    if (total <= v.capacity()) return;
    const std::size_t grown = std::max(total, 2 * v.capacity());
    check_memory(path, grown * sizeof(T));
    v.reserve(grown);
}

// f(); out of memory in it an Error "'path': out of memory reading the <what>".
template <class F>
auto out_of_memory_reading(const std::string& path, const char* what, F&& f) {
    return detail::out_of_memory_as_error([&] { return "'" + path + "': out of memory reading the " + what; }, f);
}

// True when `path` ends with `suffix`, ignoring ASCII case.
bool ends_with_nocase(const std::string& path, const std::string& suffix);
// The data file `name` that `header` points to, resolved against the directory holding it
// (unless absolute); an Error for a header in memory, which has no directory to look in.
std::string detached_data_path(const InputFile& header, const std::string& name);

}  // namespace voxmesh::io
