// Writes a file through a temporary in the same directory and renames it into place, so a
// failure never leaves a partial or empty output behind; the temporaries are listed for a
// signal handler to remove (remove_partial_outputs).
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace voxmesh::detail {

// Calls write(FILE*) on a temporary next to `path`; throws Error (naming the path) on any
// failure, removing the temporary. A symbolic link at `path` is followed: the file it names
// is replaced, the link kept. A file replaced keeps its permission bits; a new one gets 0666
// less the umask.
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);

// Throws the Error write_file_atomically(path, ...) would throw before writing anything: a
// directory or a missing one, a file or a symbolic link this process may not write through,
// a directory it may not create the temporary in. For a program to refuse an output before
// its work, not after.
void check_writable(const std::string& path);

// The directory a write of `path` puts its temporary in: `path`'s own, or "."; throws Error
// (naming `path`) when `path` is a directory or that directory does not exist.
std::filesystem::path target_directory(const std::string& path);

// Calls write(FILE*) on a stream the caller opened (standard output), then flushes it; throws
// Error as write_file_atomically does, naming `name`. What was written stays written.
void write_to_stream(std::FILE* file, const std::string& name, const std::function<void(std::FILE*)>& write);

// Calls write(FILE*) on a stream into memory and returns what it wrote; throws Error as
// write_file_atomically does, naming `name` (running out of memory an OutOfMemoryError).
// `expected_bytes`, where the writer knows its size, is reserved at once: no growing copies,
// and the result holds no spare capacity.
std::vector<unsigned char> write_to_memory(const std::string& name, const std::function<void(std::FILE*)>& write,
                                           std::size_t expected_bytes = 0);

// A temporary file's name listed for remove_partial_outputs() (a signal handler's cleanup)
// for as long as this object lives or until unlist().
class ListedTemporary {
public:
    ListedTemporary() = default;
    ~ListedTemporary();
    ListedTemporary(const ListedTemporary&) = delete;
    ListedTemporary& operator=(const ListedTemporary&) = delete;

    // Lists `temp`, replacing a name listed before. Call it before the file is created where
    // the name is known first, so that no signal in between can leave the file behind.
    void list(const std::string& temp);
    void unlist();

private:
    void* slot_ = nullptr;  // a slot of atomic_file.cpp's fixed table
};

// fwrite that throws Error on a short write.
void write_bytes(std::FILE* file, const void* data, std::size_t bytes);

}  // namespace voxmesh::detail
