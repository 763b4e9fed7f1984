#include "samples.hpp"

#include "header_text.hpp"
#include "inflate.hpp"
#include "core/dims_text.hpp"
#include "core/out_of_memory.hpp"
#include "input_file.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <limits>
#include <string_view>
#include <type_traits>
#include <cstdint>
#include <cstring>
#include <istream>
#include <optional>
#include <vector>

namespace voxmesh::io {

namespace {

// Deflate cannot expand data by more than about 1032:1; a header asking for more than
// that from the stream at hand is lying, and we say so before allocating anything.
constexpr std::size_t kMaxDeflateRatio = 1032;

using detail::dims_text;

// Volume::allocate, its Error (out of memory) naming the file.
Volume allocate_samples(const std::string& path, const SampleLayout& layout) {
    try {
        return Volume::allocate(layout.type, layout.dims);
    } catch (const Error& e) {
        detail::rethrow_with_message(e, "'" + path + "': " + e.what());
    }
}

struct Located {
    std::size_t file_size = 0;
    std::size_t start = 0;   // raw: first sample; compressed: first stream byte; text: first byte
    std::size_t length = 0;  // raw: sample bytes; compressed: stream bytes; text: to the file's end
};

Located locate(const InputFile& file, const std::string& header_path, const SampleLayout& layout,
               std::size_t bytes) {
    const std::string& path = file.path();
    const std::string ctx = data_file_note(header_path, layout);
    Located at;
    at.file_size = file.size();
    if (at.file_size == 0) fail(path, "file is empty" + ctx);
    const std::string samples_text = dims_text(layout.dims) + " " + scalar_name(layout.type) + " samples";
    if (layout.text) {
        // Each number takes a character and is followed by a separator (but the last): a file
        // too short for the count is refused before anything is allocated.
        at.start = std::min(layout.offset, at.file_size);
        at.length = at.file_size - at.start;
        const std::size_t count = bytes / scalar_size(layout.type);
        if (at.length / 2 + at.length % 2 < count)
            fail(path, "the " + std::to_string(at.length) + " bytes after the header cannot hold " + samples_text +
                           " as text (truncated file, or dims that do not match it)" + ctx);
        check_memory(path, bytes);
        return at;
    }
    if (!layout.compressed && layout.more_may_follow) {
        if (layout.offset > at.file_size || at.file_size - layout.offset < bytes)
            fail(path, "holds " + std::to_string(at.file_size) + " bytes; " + samples_text + " after a " +
                           std::to_string(layout.offset) + "-byte header need " + std::to_string(bytes) +
                           " more (truncated file, or dims that do not match it)" + ctx);
        at.start = layout.offset;
        at.length = bytes;
        return at;
    }
    if (!layout.compressed) {
        if (layout.at_end) {
            if (at.file_size < bytes || at.file_size - bytes < layout.min_start)
                fail(path, "holds " + std::to_string(at.file_size) + " bytes but " + dims_text(layout.dims) + " " +
                               scalar_name(layout.type) + " samples need " + std::to_string(bytes) +
                               (layout.min_start ? " after its " + std::to_string(layout.min_start) +
                                                       "-byte header (samples at the end of the file may not overlap it)"
                                                 : std::string()) +
                               ctx);
            at.start = at.file_size - bytes;
        } else {
            if (layout.offset > at.file_size || at.file_size - layout.offset != bytes)
                fail(path, "holds " + std::to_string(at.file_size) + " bytes; " + dims_text(layout.dims) + " " +
                               scalar_name(layout.type) + " samples after a " + std::to_string(layout.offset) +
                               "-byte header need exactly " +
                               (layout.offset > SIZE_MAX - bytes ? std::string("more than SIZE_MAX")
                                                                 : std::to_string(layout.offset + bytes)) +
                               " (truncated file, or dims that do not match it)" + ctx);
            at.start = layout.offset;
        }
        at.length = bytes;
        return at;
    }
    if (layout.offset >= at.file_size) fail(path, "no compressed data after the header" + ctx);
    at.start = layout.offset;
    at.length = at.file_size - layout.offset;
    if (layout.compressed_size != 0) {
        if (layout.compressed_size > at.length)
            fail(path, "compressed data should be " + std::to_string(layout.compressed_size) + " bytes but only " +
                           std::to_string(at.length) + " follow the header (truncated file?)" + ctx);
        at.length = layout.compressed_size;
    }
    check_memory(path, bytes);
    const std::size_t needed = bytes + std::min(layout.skip, SIZE_MAX - bytes);
    if (needed / kMaxDeflateRatio > at.length + 64)
        fail(path, std::to_string(at.length) + " bytes of compressed data cannot hold " + dims_text(layout.dims) + " " +
                       scalar_name(layout.type) + " samples (" + std::to_string(bytes) +
                       " bytes): the dims or the file are wrong" + ctx);
    return at;
}

}  // namespace

std::string data_file_note(const std::string& header_path, const SampleLayout& layout) {
    if (layout.data_path == header_path) return "";
    return " (data file of '" + header_path + "')";
}

const InputFile& open_data(const InputFile& header, const SampleLayout& layout, std::optional<InputFile>& detached) {
    if (layout.data_path == header.path()) return header;
    try {
        return detached.emplace(layout.data_path);
    } catch (const Error& e) {
        detail::rethrow_with_message(e, e.what() + data_file_note(header.path(), layout));
    }
}

namespace {

bool any_flipped(const SampleLayout& layout) {
    return layout.flipped[0] || layout.flipped[1] || layout.flipped[2];
}

bool host_order(const SampleLayout& layout) {
    return scalar_size(layout.type) == 1 || layout.big_endian == (std::endian::native == std::endian::big);
}

// Samples read into memory (copied, inflated or streamed) in the layout's byte order and
// axis directions, made host-order and reversed along the flipped axes.
void to_host_layout(Volume& v, const SampleLayout& layout) {
    const std::size_t value_size = scalar_size(layout.type);
    if (!host_order(layout)) swap_bytes(v.data, v.byte_size() / value_size, value_size);
    reverse_axes(v, layout.flipped);
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

// One number of text samples as T: an integer whole and in T's range (it may start with '+'), a
// float or double as float_word and double_word read it; what is wrong with it otherwise.
template <class T>
const char* parse_sample(std::string_view word, T& out) {
    if constexpr (std::is_same_v<T, float>) {
        return float_word(word, out);
    } else if constexpr (std::is_same_v<T, double>) {
        return double_word(word, out);
    } else {
        // from_chars rejects a leading '+', which VTK's reader (operator>>) takes.
        if (word.size() > 1 && word[0] == '+' && word[1] != '-') word.remove_prefix(1);
        long long value = 0;
        const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
        if (error == std::errc::result_out_of_range) return "is out of range";
        if (error != std::errc() || end != word.data() + word.size()) return "is not a number";
        if (value < std::numeric_limits<T>::min() || value > std::numeric_limits<T>::max())
            return "is out of range for the type";
        out = static_cast<T>(value);
        return nullptr;
    }
}

// A byte written as a fraction of 255 (legacy VTK's ASCII COLOR_SCALARS), read back as VTK's
// reader does: rounded to the nearest byte.
const char* parse_unit_color(std::string_view word, std::uint8_t& out) {
    float value = 0;
    if (const char* problem = float_word(word, value)) return problem;
    if (!(value >= 0 && value <= 1)) return "is not a colour value from 0 to 1";
    out = static_cast<std::uint8_t>(255 * value + 0.5f);
    return nullptr;
}

// `count` whitespace-separated numbers into `out`, parse(word, out[i]) reading each.
template <class T, class Parse>
void parse_numbers(const std::string& path, std::string_view text, T* out, std::size_t count, Parse parse) {
    std::size_t pos = 0;
    for (std::size_t i = 0; i < count; ++i) {
        while (pos < text.size() && is_space(text[pos])) ++pos;
        if (pos == text.size())
            fail(path, "the text data ends after " + std::to_string(i) + " of its " + std::to_string(count) +
                           " samples (truncated file, or dims that do not match it)");
        std::size_t end = pos;
        while (end < text.size() && !is_space(text[end])) ++end;
        std::string_view word = text.substr(pos, end - pos);
        if (const char* problem = parse(word, out[i]))
            fail(path, "sample " + std::to_string(i) + ": '" + shown(word) + "' " + problem);
        pos = end;
    }
}

template <class T>
void parse_numbers_as(const std::string& path, std::string_view text, void* out, std::size_t count) {
    parse_numbers(path, text, static_cast<T*>(out), count, parse_sample<T>);
}

// Numbers as text (legacy VTK ASCII) into `v`, in the file's order; what follows the last one
// (more arrays) is not read.
void parse_text_samples(const std::string& path, std::string_view text, bool unit_colors, Volume& v) {
    const std::size_t n = v.sample_count();
    if (unit_colors) return parse_numbers(path, text, static_cast<std::uint8_t*>(v.data), n, parse_unit_color);
    switch (v.type) {
        case ScalarType::U8: return parse_numbers_as<std::uint8_t>(path, text, v.data, n);
        case ScalarType::I8: return parse_numbers_as<std::int8_t>(path, text, v.data, n);
        case ScalarType::U16: return parse_numbers_as<std::uint16_t>(path, text, v.data, n);
        case ScalarType::I16: return parse_numbers_as<std::int16_t>(path, text, v.data, n);
        case ScalarType::U32: return parse_numbers_as<std::uint32_t>(path, text, v.data, n);
        case ScalarType::I32: return parse_numbers_as<std::int32_t>(path, text, v.data, n);
        case ScalarType::F32: return parse_numbers_as<float>(path, text, v.data, n);
        case ScalarType::F64: return parse_numbers_as<double>(path, text, v.data, n);
    }
    throw Error("parse_text_samples: unexpected sample type");
}

}  // namespace

std::size_t sample_bytes(const std::string& path, std::array<std::size_t, 3> dims, ScalarType type) {
    if (dims[0] == 0 || dims[1] == 0 || dims[2] == 0)
        fail(path, "dimensions " + dims_text(dims) + " are empty; every size must be at least 1");
    try {
        return checked_volume_bytes(dims, type);
    } catch (const Error& e) {
        fail(path, e.what());
    }
}

std::size_t check_samples(const InputFile& header, const SampleLayout& layout) {
    const std::size_t bytes = sample_bytes(header.path(), layout.dims, layout.type);
    std::optional<InputFile> detached;
    const InputFile& file = open_data(header, layout, detached);
    locate(file, header.path(), layout, bytes);
    return file.size();
}

void swap_bytes(void* data, std::size_t count, std::size_t size) {
    auto* p = static_cast<unsigned char*>(data);
    if (size <= 1) return;
    for (std::size_t i = 0; i < count; ++i, p += size) std::reverse(p, p + size);
}

Volume load_samples(const InputFile& header, const SampleLayout& layout) {
    const std::size_t bytes = sample_bytes(header.path(), layout.dims, layout.type);
    std::optional<InputFile> detached;
    const InputFile& file = open_data(header, layout, detached);
    const Located at = locate(file, header.path(), layout, bytes);
    const std::size_t value_size = scalar_size(layout.type);
    const std::string ctx = data_file_note(header.path(), layout);

    if (layout.text) {
        check_memory(file.path(), bytes);
        Volume v = allocate_samples(file.path(), layout);
        const std::shared_ptr<const unsigned char> mapping = file.view();
        const std::string_view text(reinterpret_cast<const char*>(mapping.get()) + at.start, at.length);
        parse_text_samples(file.path(), text, layout.unit_colors, v);
        reverse_axes(v, layout.flipped);
        return v;
    }

    if (!layout.compressed && host_order(layout) && at.start % value_size == 0 && file.maps_in_place()) {
        // Map (or take the bytes handed over), don't copy: the Volume keeps them alive.
        std::shared_ptr<unsigned char> mapping = file.map();
        Volume v;
        v.type = layout.type;
        v.dims = layout.dims;
        v.data = mapping.get() + at.start;
        v.storage = std::move(mapping);
        // Reversing writes every page of the private mapping: as much memory as a copy.
        if (any_flipped(layout) && !file.in_memory()) check_memory(file.path(), bytes);
        reverse_axes(v, layout.flipped);
        return v;
    }

    check_memory(file.path(), bytes);
    Volume v = allocate_samples(file.path(), layout);
    if (!layout.compressed) {
        file.read_exact(at.start, v.data, bytes);
    } else {
        const std::shared_ptr<const unsigned char> mapping = file.view();
        Inflater inflater(file.path(), mapping.get() + at.start, at.length);
        if (inflater.skip(layout.skip) != layout.skip)
            fail(file.path(), "decompressed data ends inside the " + std::to_string(layout.skip) + "-byte header" + ctx);
        const std::size_t got = inflater.read(v.data, bytes);
        if (got != bytes)
            fail(file.path(), "decompressed data holds " + std::to_string(got) + " bytes of samples but " +
                                  dims_text(layout.dims) + " " + scalar_name(layout.type) + " needs " +
                                  std::to_string(bytes) + " (truncated data, or dims that do not match it)" + ctx);
        // Data after the samples, where allowed, is read through so that the gzip CRC is still
        // checked, but only so far: a small compressed tail can inflate to gigabytes.
        constexpr std::size_t kTailChecked = std::size_t{64} << 20;
        if (layout.more_may_follow) {
            if (inflater.skip(kTailChecked) < kTailChecked) (void)inflater.at_end();  // input after the stream
        } else if (!inflater.at_end())
            fail(file.path(), "decompressed data is longer than the " + std::to_string(bytes) + " bytes that " +
                                  dims_text(layout.dims) + " " + scalar_name(layout.type) +
                                  " samples need (dims do not match the data)" + ctx);
    }
    to_host_layout(v, layout);
    return v;
}

namespace {

// The caller's exception mask off while reading, so that the end of the stream is one of our
// Errors (naming what is missing) and not a std::ios_base::failure; put back afterwards,
// without throwing for the eof and fail bits the read leaves.
class NoStreamExceptions {
public:
    explicit NoStreamExceptions(std::istream& in) : in_(in), mask_(in.exceptions()) { in_.exceptions(std::ios::goodbit); }
    ~NoStreamExceptions() {
        try {
            in_.exceptions(mask_);  // sets the mask, then throws if the state has a bit of it
        } catch (const std::ios_base::failure&) {
        }
    }
    NoStreamExceptions(const NoStreamExceptions&) = delete;
    NoStreamExceptions& operator=(const NoStreamExceptions&) = delete;

private:
    std::istream& in_;
    std::ios::iostate mask_;
};

}  // namespace

Volume load_stream_samples(std::istream& in, const std::string& name, const SampleLayout& layout) {
    const std::size_t bytes = sample_bytes(name, layout.dims, layout.type);
    check_memory(name, bytes);
    const NoStreamExceptions quiet(in);
    // Reads up to n bytes; fewer only where the stream ends.
    const auto read_some = [&](char* out, std::size_t n) {
        std::size_t done = 0;
        while (done < n && in) {
            in.read(out + done, static_cast<std::streamsize>(std::min<std::size_t>(n - done, std::size_t{1} << 30)));
            done += static_cast<std::size_t>(in.gcount());
        }
        if (in.bad()) fail(name, "read failed");
        return done;
    };
    std::vector<char> skipped(std::min<std::size_t>(layout.offset, std::size_t{1} << 16));
    for (std::size_t left = layout.offset; left > 0;) {
        const std::size_t want = std::min(left, skipped.size());
        const std::size_t got = read_some(skipped.data(), want);
        if (got < want)
            fail(name, "the stream ends after " + std::to_string(layout.offset - left + got) + " bytes, inside the " +
                           std::to_string(layout.offset) + "-byte offset");
        left -= got;
    }
    Volume v = allocate_samples(name, layout);
    const std::size_t got = read_some(static_cast<char*>(v.data), bytes);
    if (got < bytes)
        fail(name, "the stream holds " + std::to_string(got) + " bytes of samples but " + dims_text(layout.dims) + " " +
                       scalar_name(layout.type) + " needs " + std::to_string(bytes) +
                       " (truncated input, or dims and type that do not match it)");
    if (in.peek() != std::char_traits<char>::eof())
        fail(name, "the stream goes on past the " + std::to_string(bytes) + " bytes that " + dims_text(layout.dims) +
                       " " + scalar_name(layout.type) + " samples need (dims, type or offset do not match it)");
    if (in.bad()) fail(name, "read failed");
    to_host_layout(v, layout);
    return v;
}

namespace {

// Reverses `rows` runs of `count` samples of N bytes each, a sample at a time: N is a
// constant, so each swap is a pair of loads and stores, not a byte loop.
template <std::size_t N>
void reverse_rows(unsigned char* data, std::size_t rows, std::size_t count) {
    for (std::size_t r = 0; r < rows; ++r) {
        unsigned char* row = data + r * count * N;
        for (std::size_t i = 0, j = count - 1; i < j; ++i, --j) {
            unsigned char t[N];
            std::memcpy(t, row + i * N, N);
            std::memcpy(row + i * N, row + j * N, N);
            std::memcpy(row + j * N, t, N);
        }
    }
}

void reverse_x(Volume& volume) {
    auto* data = static_cast<unsigned char*>(volume.data);
    const std::size_t rows = volume.dims[1] * volume.dims[2], count = volume.dims[0];
    if (count < 2) return;
    switch (scalar_size(volume.type)) {
        case 1: return reverse_rows<1>(data, rows, count);
        case 2: return reverse_rows<2>(data, rows, count);
        case 4: return reverse_rows<4>(data, rows, count);
        case 8: return reverse_rows<8>(data, rows, count);
        default: throw Error("reverse_axes: unexpected sample size");
    }
}

}  // namespace

void reverse_axes(Volume& volume, std::array<bool, 3> flipped) {
    if (flipped[0]) reverse_x(volume);
    // Along y or z the samples form `outer` runs of dims[a] blocks; a block is everything
    // below that axis (a row for y, a slice for z) and moves whole.
    auto* data = static_cast<unsigned char*>(volume.data);
    for (std::size_t a = 1; a < 3; ++a) {
        if (!flipped[a]) continue;
        std::size_t block = scalar_size(volume.type), outer = 1;
        for (std::size_t b = 0; b < a; ++b) block *= volume.dims[b];
        for (std::size_t b = a + 1; b < 3; ++b) outer *= volume.dims[b];
        const std::size_t count = volume.dims[a];
        for (std::size_t o = 0; o < outer; ++o) {
            unsigned char* run = data + o * count * block;
            for (std::size_t i = 0; i < count / 2; ++i)
                std::swap_ranges(run + i * block, run + (i + 1) * block, run + (count - 1 - i) * block);
        }
    }
}

}  // namespace voxmesh::io
