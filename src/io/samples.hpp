// Where a volume's samples live, as a header describes them, and loading them: the one
// place that checks sizes against the file, maps, copies, decompresses and byte-swaps.
#pragma once

#include "input_file.hpp"

#include <voxmesh/io.hpp>

#include <array>
#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>

namespace voxmesh::io {

struct SampleLayout {
    ScalarType type = ScalarType::U8;
    std::array<std::size_t, 3> dims{0, 0, 0};
    bool big_endian = false;
    std::string data_path;        // the file holding the samples
    std::size_t offset = 0;       // raw: first sample; compressed: start of the stream
    bool at_end = false;          // raw: the samples are the file's last bytes ...
    std::size_t min_start = 0;    // ... and start no sooner than this (the header's end, in its own file)
    bool more_may_follow = false; // other data may follow the samples (compressed: in the stream)
    bool text = false;            // numbers as text, separated by whitespace (legacy VTK ASCII)
    bool unit_colors = false;     // text, u8: each a number 0..1 standing for round(255 x)
    bool compressed = false;      // zlib or gzip stream
    std::size_t skip = 0;         // compressed: decompressed bytes before the first sample
    std::size_t compressed_size = 0;  // compressed: stream length; 0 = to the end of the file
    std::array<bool, 3> flipped{false, false, false};  // axes to reverse once loaded
};

// Overflow-checked byte size of the samples; errors name `path`. Zero dims are an error.
std::size_t sample_bytes(const std::string& path, std::array<std::size_t, 3> dims, ScalarType type);

// " (data file of 'header_path')" where the samples are in a detached file, else "": the
// note every error about the data file ends with.
std::string data_file_note(const std::string& header_path, const SampleLayout& layout);

// The file holding the samples: `header` itself, or the detached data file opened into
// `detached`, its errors naming the header too.
const InputFile& open_data(const InputFile& header, const SampleLayout& layout, std::optional<InputFile>& detached);

// Both read the samples from `header` itself where layout.data_path is its path (attached
// data, a raw file), else from the detached data file, naming the header in its errors.
//
// Everything that can be checked without reading samples: the data file exists, raw data
// matches the file size exactly, compressed data could hold that much. Returns the data
// file's size.
std::size_t check_samples(const InputFile& header, const SampleLayout& layout);

// The samples, mapped when possible (see io.hpp; copied from a header in memory), otherwise
// copied / inflated / swapped; then reversed along layout.flipped.
Volume load_samples(const InputFile& header, const SampleLayout& layout);

// The samples from a stream (a pipe, stdin), never mapped: layout.offset bytes skipped, then
// exactly the samples, and nothing after them; swapped and reversed as load_samples does.
// Errors name `name`.
Volume load_stream_samples(std::istream& in, const std::string& name, const SampleLayout& layout);

// Reverses the samples' order along each axis with flipped[a], in place.
void reverse_axes(Volume& volume, std::array<bool, 3> flipped);

// Reverses the byte order of `count` values of `size` bytes each, in place.
void swap_bytes(void* data, std::size_t count, std::size_t size);

}  // namespace voxmesh::io
