#include "inflate.hpp"

#include "input_file.hpp"

#include <algorithm>
#include <climits>
#include <new>
#include <vector>
#include <zlib.h>

namespace voxmesh::io {

struct Inflater::State {
    z_stream z{};
    const unsigned char* data = nullptr;
    std::size_t size = 0;
    std::size_t fed = 0;  // input bytes handed to zlib so far
    bool ended = false;   // the current member reached its end
    std::size_t remaining_input() const { return size - fed + z.avail_in; }
};

Inflater::Inflater(const std::string& path, const unsigned char* data, std::size_t size)
    : state_(std::make_unique<State>()), path_(path) {
    state_->data = data;
    state_->size = size;
    // 15 + 32: accept both zlib (MetaImage) and gzip (NRRD, .nii.gz) headers.
    const int rc = inflateInit2(&state_->z, 15 + 32);
    if (rc == Z_MEM_ERROR) throw std::bad_alloc();  // the readers name the file
    if (rc != Z_OK) fail(path, "cannot initialise zlib");
}

Inflater::~Inflater() { inflateEnd(&state_->z); }

std::size_t Inflater::read(void* out, std::size_t bytes) {
    State& s = *state_;
    auto* dst = static_cast<unsigned char*>(out);
    std::size_t done = 0;
    while (done < bytes) {
        if (s.ended) {
            // Another gzip member follows: keep going as one stream.
            const unsigned char* next = s.z.next_in;
            if (s.z.avail_in == 0 && s.fed < s.size) {
                next = s.data + s.fed;
            }
            if (s.remaining_input() >= 2 && next[0] == 0x1f && next[1] == 0x8b) {
                if (inflateReset(&s.z) != Z_OK) fail(path_, "cannot reset zlib");
                s.ended = false;
            } else {
                break;
            }
        }
        if (s.z.avail_in == 0 && s.fed < s.size) {
            const std::size_t chunk = std::min<std::size_t>(s.size - s.fed, UINT_MAX);
            s.z.next_in = const_cast<unsigned char*>(s.data + s.fed);
            s.z.avail_in = static_cast<uInt>(chunk);
            s.fed += chunk;
        }
        s.z.next_out = dst + done;
        s.z.avail_out = static_cast<uInt>(std::min<std::size_t>(bytes - done, UINT_MAX));
        const uInt before = s.z.avail_out;
        const int rc = inflate(&s.z, Z_NO_FLUSH);
        done += before - s.z.avail_out;
        if (rc == Z_STREAM_END) {
            s.ended = true;
        } else if (rc == Z_BUF_ERROR) {
            if (s.remaining_input() == 0) fail(path_, "compressed data ends early (truncated file?)");
        } else if (rc == Z_MEM_ERROR) {
            // zlib allocates its window on the first inflate: memory ran out, the data may be
            // sound (it was reported as corrupt data, exit 2, before).
            throw std::bad_alloc();
        } else if (rc != Z_OK) {
            fail(path_, std::string("corrupt compressed data: ") + (s.z.msg ? s.z.msg : "zlib error " + std::to_string(rc)));
        }
    }
    return done;
}

std::size_t Inflater::skip(std::size_t bytes) {
    std::vector<unsigned char> scratch(std::min<std::size_t>(bytes, 1 << 16));
    std::size_t done = 0;
    while (done < bytes) {
        const std::size_t want = std::min(bytes - done, scratch.size());
        const std::size_t got = read(scratch.data(), want);
        done += got;
        if (got < want) break;
    }
    return done;
}

bool Inflater::at_end() {
    unsigned char extra = 0;
    if (read(&extra, 1) != 0) return false;
    // The stream ended; anything after it is not ours to ignore silently, except zero bytes:
    // padding to a block size, which gzip -d, zlib's gzread and Python's gzip (so nibabel) skip.
    const State& s = *state_;
    const std::size_t trailing = s.remaining_input();
    const unsigned char* rest = s.data + (s.size - trailing);
    if (std::any_of(rest, rest + trailing, [](unsigned char b) { return b != 0; }))
        fail(path_, std::to_string(trailing) + " bytes of unexpected data follow the compressed stream");
    return true;
}

}  // namespace voxmesh::io
