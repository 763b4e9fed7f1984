// Writes a file through a temporary in the same directory and renames it into place, so a
// failure never leaves a partial or empty output behind.
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>

namespace voxmesh::detail {

// Calls write(FILE*) on a temporary next to `path`; throws Error (naming the path) on any
// failure, removing the temporary. A symbolic link at `path` is followed: the file it names
// is replaced, the link kept. A file replaced keeps its permission bits; a new one gets 0666
// less the umask.
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);

// The directory a write of `path` puts its temporary in: `path`'s own, or "."; throws Error
// (naming `path`) when `path` is a directory or that directory does not exist.
std::filesystem::path target_directory(const std::string& path);

// fwrite that throws Error on a short write.
void write_bytes(std::FILE* file, const void* data, std::size_t bytes);

}  // namespace voxmesh::detail
