// Writes a file through a temporary in the same directory and renames it into place, so a
// failure never leaves a partial or empty output behind.
#pragma once

#include <cstdio>
#include <functional>
#include <string>

namespace voxmesh::detail {

// Calls write(FILE*) on a temporary next to `path`; throws Error (naming the path) on any
// failure, removing the temporary.
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);

// fwrite that throws Error on a short write.
void write_bytes(std::FILE* file, const void* data, std::size_t bytes);

}  // namespace voxmesh::detail
