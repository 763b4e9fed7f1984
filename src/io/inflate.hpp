// Streaming zlib/gzip decompression from memory, for gzip-encoded NRRD, compressed
// MetaImage and .nii.gz. Output is only ever written into buffers the caller sized from
// checked header fields; the stream's own length is never trusted.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

namespace voxmesh::io {

class Inflater {
public:
    // Decompresses [data, data + size); `path` names the file in errors.
    Inflater(const std::string& path, const unsigned char* data, std::size_t size);
    ~Inflater();
    Inflater(const Inflater&) = delete;
    Inflater& operator=(const Inflater&) = delete;

    // Up to `bytes` decompressed bytes into `out`; fewer only when the stream ended.
    // Throws on corrupt or truncated data. Concatenated gzip members are one stream.
    std::size_t read(void* out, std::size_t bytes);
    // Discards up to `bytes`; returns how many were discarded.
    std::size_t skip(std::size_t bytes);
    // True when no decompressed byte follows; throws when input bytes trail the stream.
    bool at_end();

private:
    struct State;
    std::unique_ptr<State> state_;
    std::string path_;
};

}  // namespace voxmesh::io
