// NumPy .npy files (numpy.save): the magic "\x93NUMPY", a version (1.0, 2.0 or 3.0), the
// header's length (2 bytes little-endian in 1.0, 4 in 2.0 and 3.0), then the header, a Python
// dict literal such as {'descr': '<f4', 'fortran_order': False, 'shape': (64, 64, 64), },
// and the samples, which must fill the rest of the file exactly. An array [z, y, x] in C order
// has x varying fastest, as voxmesh stores samples; in Fortran order the first axis does. The
// format has no geometry: spacing 1, origin 0.
#include "header_text.hpp"
#include "input_file.hpp"
#include "readers.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace voxmesh::io {

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicBytes = 6;
// numpy writes headers of a few hundred bytes; this bounds what is read before it is parsed.
constexpr std::size_t kMaxHeader = std::size_t{1} << 16;

// A cursor over the header dict's text, failing with the file's name on anything unexpected.
class DictText {
public:
    DictText(const std::string& path, std::string_view text) : path_(path), text_(text) {}

    void skip_space() {
        while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    }
    bool take(char c) {
        skip_space();
        if (pos_ < text_.size() && text_[pos_] == c) {
            ++pos_;
            return true;
        }
        return false;
    }
    void expect(char c, const char* where) {
        if (!take(c)) fail(path_, std::string("malformed .npy header: expected '") + c + "' " + where);
    }
    bool at_end() {
        skip_space();
        return pos_ == text_.size();
    }
    // 'text' or "text" (numpy writes no escapes in these keys and values).
    std::string quoted(const char* what) {
        skip_space();
        if (pos_ >= text_.size() || (text_[pos_] != '\'' && text_[pos_] != '"'))
            fail(path_, std::string("malformed .npy header: expected a quoted ") + what);
        const char quote = text_[pos_++];
        const std::size_t end = text_.find(quote, pos_);
        if (end == std::string_view::npos) fail(path_, std::string("malformed .npy header: unterminated ") + what);
        const std::string value(text_.substr(pos_, end - pos_));
        pos_ = end + 1;
        return value;
    }
    bool boolean(const char* key) {
        skip_space();
        for (const auto& [word, value] : {std::pair<std::string_view, bool>{"True", true}, {"False", false}})
            if (text_.substr(pos_, word.size()) == word) {
                pos_ += word.size();
                return value;
            }
        fail(path_, std::string("malformed .npy header: '") + key + "' must be True or False");
    }
    // (a, b, c) or (a,) or (): non-negative integers.
    std::vector<std::size_t> sizes() {
        expect('(', "to open 'shape'");
        std::vector<std::size_t> found;
        while (!take(')')) {
            skip_space();
            const std::size_t start = pos_;
            while (pos_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[pos_]))) ++pos_;
            if (pos_ == start) fail(path_, "malformed .npy header: 'shape' must be a tuple of sizes");
            if (found.size() == 32) fail(path_, "'shape' has more than 32 axes");
            found.push_back(parse_size(path_, "shape", text_.substr(start, pos_ - start)));
            if (pos_ < text_.size() && text_[pos_] == 'L') ++pos_;  // Python 2 wrote longs as 5L
            if (!take(',')) {
                expect(')', "to close 'shape'");
                break;
            }
        }
        return found;
    }

private:
    const std::string& path_;
    std::string_view text_;
    std::size_t pos_ = 0;
};

// numpy's type string: byte order ('<', '>', '|' or '='), kind, size in bytes.
ScalarType npy_type(const std::string& path, const std::string& descr, bool& big_endian) {
    struct Known {
        const char* code;
        ScalarType type;
    };
    static constexpr Known kTypes[] = {{"u1", ScalarType::U8},  {"i1", ScalarType::I8},  {"b1", ScalarType::U8},
                                       {"u2", ScalarType::U16}, {"i2", ScalarType::I16}, {"u4", ScalarType::U32},
                                       {"i4", ScalarType::I32}, {"f4", ScalarType::F32}, {"f8", ScalarType::F64}};
    if (descr.size() == 3 && std::strchr("<>|=", descr[0]))
        for (const Known& k : kTypes)
            if (descr.compare(1, 2, k.code) == 0) {
                // '=' is the writer's native order; numpy writes '<' or '>' instead, so take it as
                // this (little-endian) machine's.
                big_endian = descr[0] == '>';
                return k.type;
            }
    fail(path, "unsupported .npy dtype '" + shown(descr) +
                   "' (supported: bool, 8/16/32-bit integers, float32, float64; not 64-bit integers, float16, "
                   "complex or structured arrays)");
}

}  // namespace

VolumeHeader read_npy_header(const InputFile& file) {
    const std::string& path = file.path();
    const std::string start = file.read(0, kMagicBytes + 6);
    if (start.size() < kMagicBytes + 4 || start.compare(0, kMagicBytes, kMagic, kMagicBytes) != 0)
        fail(path, "not a .npy file (no \\x93NUMPY magic)");
    const unsigned major = static_cast<unsigned char>(start[6]);
    if (major < 1 || major > 3)
        fail(path, "unsupported .npy format version " + std::to_string(major) + "." +
                       std::to_string(static_cast<unsigned char>(start[7])) + " (1.0, 2.0 or 3.0)");
    const std::size_t length_bytes = major == 1 ? 2 : 4;
    if (start.size() < 8 + length_bytes) fail(path, "the .npy header's length is cut off");
    std::size_t header_length = 0;
    for (std::size_t i = 0; i < length_bytes; ++i)
        header_length |= static_cast<std::size_t>(static_cast<unsigned char>(start[8 + i])) << (8 * i);
    const std::size_t header_start = 8 + length_bytes;
    if (header_length > kMaxHeader)
        fail(path, "the .npy header is " + std::to_string(header_length) + " bytes; at most " +
                       std::to_string(kMaxHeader) + " are read");
    const std::string text = file.read(header_start, header_length);
    if (text.size() != header_length)
        fail(path, "the .npy header is cut off (" + std::to_string(text.size()) + " of " +
                       std::to_string(header_length) + " bytes)");

    DictText dict(path, text);
    std::string descr;
    bool fortran_order = false, have_descr = false, have_order = false, have_shape = false;
    std::vector<std::size_t> shape;
    dict.expect('{', "at the start of the header");
    while (!dict.take('}')) {
        const std::string key = dict.quoted("key");
        dict.expect(':', "after a key");
        if (key == "descr") {
            descr = dict.quoted("'descr'");
            have_descr = true;
        } else if (key == "fortran_order") {
            fortran_order = dict.boolean("fortran_order");
            have_order = true;
        } else if (key == "shape") {
            shape = dict.sizes();
            have_shape = true;
        } else {
            fail(path, "unexpected key '" + shown(key) + "' in the .npy header (descr, fortran_order, shape)");
        }
        if (!dict.take(',')) {
            dict.expect('}', "to close the header");
            break;
        }
    }
    if (!dict.at_end()) fail(path, "malformed .npy header: text after the closing '}'");
    if (!have_descr || !have_order || !have_shape) {
        const char* missing = !have_descr ? "descr" : !have_order ? "fortran_order" : "shape";
        fail(path, std::string("the .npy header lacks '") + missing + "'");
    }

    VolumeHeader h;
    VolumeInfo& info = h.info;
    info.format = "npy";
    info.encoding = "raw";
    info.type = npy_type(path, descr, info.big_endian);
    if (shape.size() < 3)
        fail(path, "has " + std::to_string(shape.size()) + " dimension(s); a volume needs 3 (an array [z, y, x])");
    const auto longer =
        static_cast<std::size_t>(std::count_if(shape.begin(), shape.end(), [](std::size_t n) { return n != 1; }));
    if (longer > 3) {
        std::string listed;
        for (const std::size_t n : shape) {
            if (!listed.empty()) listed += ", ";
            listed += std::to_string(n);
        }
        fail(path, "'shape' (" + listed + ") has " + std::to_string(longer) +
                       " axes longer than 1; a volume is a 3-D array (more axes only of size 1)");
    }
    // Fastest axis first: x is the last in C order, the first in Fortran order. Axes of size 1
    // beyond three, anywhere ((z, y, x, 1) too), leave the samples' order unchanged.
    std::vector<std::size_t> sizes = shape;
    if (!fortran_order) std::reverse(sizes.begin(), sizes.end());
    const std::array<std::size_t, 3> xyz = volume_axes(path, sizes);
    info.dims = {sizes[xyz[0]], sizes[xyz[1]], sizes[xyz[2]]};
    info.data_file = path;
    SampleLayout& layout = h.layout;
    layout.type = info.type;
    layout.dims = info.dims;
    layout.big_endian = info.big_endian;
    layout.data_path = path;
    layout.offset = header_start + header_length;
    return h;
}

}  // namespace voxmesh::io
