// Legacy VTK (.vtk, as vtkStructuredPointsWriter and vtkDataSetWriter write it, file versions
// 1.0 to 5.1): DATASET STRUCTURED_POINTS with DIMENSIONS (or EXTENT), SPACING (or ASPECT_RATIO)
// and ORIGIN, then POINT_DATA whose first SCALARS with one component, COLOR_SCALARS with one
// (how VTK writes unsigned char: bytes in BINARY, 0..1 in ASCII), or first array of a FIELD is
// the volume (other attributes before it are skipped). BINARY data is big-endian; ASCII data is numbers as text. The
// dataset's field data (before the geometry) and cell data (before the point data, as VTK
// writes a volume that has both), with their arrays' METADATA blocks, are skipped; arrays after
// the volume's are ignored.
#include "header_text.hpp"
#include "input_file.hpp"
#include "readers.hpp"

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace voxmesh::io {

namespace {

// The bytes of the file the header is read through at a time (its lines are short; the window
// moves on past data the header skips).
constexpr std::size_t kMaxVtkHeader = std::size_t{1} << 16;

struct TypeName {
    const char* name;
    ScalarType type;
};
constexpr TypeName kTypes[] = {
    {"unsigned_char", ScalarType::U8},   {"char", ScalarType::I8},           {"signed_char", ScalarType::I8},
    {"unsigned_short", ScalarType::U16}, {"short", ScalarType::I16},         {"unsigned_int", ScalarType::U32},
    {"int", ScalarType::I32},            {"float", ScalarType::F32},         {"double", ScalarType::F64},
    {"vtktypeuint8", ScalarType::U8},    {"vtktypeint8", ScalarType::I8},    {"vtktypeuint16", ScalarType::U16},
    {"vtktypeint16", ScalarType::I16},   {"vtktypeuint32", ScalarType::U32}, {"vtktypeint32", ScalarType::I32},
    {"vtktypefloat32", ScalarType::F32}, {"vtktypefloat64", ScalarType::F64},
};

ScalarType parse_type(const std::string& path, std::string_view name) {
    for (const TypeName& t : kTypes)
        if (lower(name) == t.name) return t.type;
    fail(path, "unsupported VTK data type '" + shown(name) +
                   "' (supported: 8/16/32-bit signed and unsigned integers, float, double)");
}

// The header's lines, read as the legacy reader does: keywords case-insensitive, blank lines
// skipped. They are read through a window of the file, moved on where the header skips data
// (field data, cell data before the point data), so views of earlier lines may not outlive the
// next read.
class Lines {
public:
    Lines(const std::string& path, const InputFile& file) : path_(path), file_(file) { move_to(0); }

    // The next line, blank or not; fails at the end of the file.
    std::string_view raw(const char* wanted) {
        if (pos_ >= window_.size() || window_.find('\n', pos_) == std::string::npos) {
            if (!file_ends_in_window()) move_to(offset());  // the line's start at the window's
            if (!file_ends_in_window() && window_.find('\n') == std::string::npos)
                fail(path_, std::string("has a line of more than ") + std::to_string(kMaxVtkHeader) + " bytes before " +
                                wanted);
        }
        std::string_view line;
        if (!next_line(window_, pos_, line))
            fail(path_, std::string("ends before ") + wanted + " (truncated, or not a volume file)");
        return line;
    }
    // Passes the next line, blank or not and however long (an ASCII string value: VTK writes
    // one a line, and one longer than the window was refused); fails at the end of the file.
    void skip_line(const char* wanted) {
        if (pos_ >= window_.size() && file_ends_in_window())
            fail(path_, std::string("ends before ") + wanted + " (truncated, or not a volume file)");
        std::size_t end;
        while ((end = window_.find('\n', pos_)) == std::string::npos && !file_ends_in_window())
            move_to(base_ + window_.size());
        pos_ = end == std::string::npos ? window_.size() : end + 1;
    }
    // The next non-blank line, as words. Blanks before it of any length (a line of them longer
    // than the window was refused as too long).
    std::vector<std::string_view> words(const char* wanted) {
        const std::size_t at = first_non_blank();
        if (at >= base_ + window_.size()) move_to(at);
        else pos_ = at - base_;
        for (;;) {
            const std::string_view line = trim(raw(wanted));
            if (!line.empty()) return split_words(line);
        }
    }
    // Where the line after the last one read starts: the data, after the header.
    std::size_t offset() const { return base_ + pos_; }
    // Where a word of the last line read starts in the file.
    std::size_t offset_of(std::string_view word) const {
        return base_ + static_cast<std::size_t>(word.data() - window_.data());
    }
    std::size_t bytes_left() const { return file_.size() - offset(); }
    // Skips `bytes` of binary data from offset().
    void skip_bytes(std::uint64_t bytes, const char* what) {
        if (bytes > bytes_left()) fail(path_, std::string("ends inside ") + what + " (truncated)");
        if (bytes <= window_.size() - pos_) pos_ += static_cast<std::size_t>(bytes);
        else move_to(offset() + static_cast<std::size_t>(bytes));
    }
    // The writer's line break after binary data, if there is one.
    void skip_line_break() {
        if (pos_ + 2 > window_.size()) move_to(offset());
        if (std::string_view(window_).substr(pos_, 2) == "\r\n") pos_ += 2;
        else if (std::string_view(window_).substr(pos_, 1) == "\n") ++pos_;
    }
    // The bytes at offset() (a binary string's length), `count` <= 8.
    std::uint64_t big_endian(std::size_t count, const char* what) {
        if (count > window_.size() - pos_) move_to(offset());
        if (count > window_.size() - pos_) fail(path_, std::string("ends inside ") + what + " (truncated)");
        std::uint64_t value = 0;
        for (std::size_t b = 0; b < count; ++b) value = value << 8 | static_cast<unsigned char>(window_[pos_ + b]);
        return value;
    }
    // Whether the next non-blank line starts with `keyword`. Past blanks of any kind, as
    // words() reads the line: an indented "  LOOKUP_TABLE default" (or one after a line of
    // spaces) was taken for the first samples, silently in BINARY.
    // Reads nothing: a run of blanks longer than the window (which hid the keyword) is
    // looked past in the file, the window left where it is (BINARY data may start here).
    bool next_starts_with(std::string_view keyword) {
        if (window_.size() - pos_ < kMaxVtkHeader / 2 && !file_ends_in_window()) move_to(offset());
        const std::size_t at = first_non_blank();
        if (at + keyword.size() <= base_ + window_.size() || file_ends_in_window())
            return lower(std::string_view(window_).substr(at - base_, keyword.size())) == lower(keyword);
        return lower(file_.read(at, keyword.size())) == lower(keyword);
    }
    // Back to a place offset() gave (a look ahead that did not match).
    void seek(std::size_t offset) { move_to(offset); }

private:
    static bool is_blank(char c) { return trim(std::string_view(&c, 1)).empty(); }
    // Where the first byte from offset() on that is not blank lies in the file (its size when
    // none is), past a run of blanks of any length; moves nothing.
    std::size_t first_non_blank() const {
        std::size_t at = pos_;
        while (at < window_.size() && is_blank(window_[at])) ++at;
        if (at < window_.size() || file_ends_in_window()) return base_ + at;
        for (std::size_t from = base_ + at;;) {
            const std::string more = file_.read(from, kMaxVtkHeader);
            std::size_t i = 0;
            while (i < more.size() && is_blank(more[i])) ++i;
            if (i < more.size() || from + more.size() >= file_.size()) return from + i;
            from += more.size();
        }
    }
    void move_to(std::size_t offset) {
        window_ = file_.read(offset, kMaxVtkHeader);
        base_ = offset;
        pos_ = 0;
    }
    bool file_ends_in_window() const { return base_ + window_.size() >= file_.size(); }

    const std::string& path_;
    const InputFile& file_;
    std::string window_;
    std::size_t base_ = 0, pos_ = 0;
};

std::string keyword(std::string_view word) {
    std::string k(word);
    for (char& c : k) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return k;
}

// Bytes of `values` values of a type in BINARY, as vtkDataWriter writes them (vtkIdType as 32
// bits, long as 64, bits packed eight a byte).
std::uint64_t binary_bytes(const std::string& path, std::string_view type, std::uint64_t values) {
    const std::string t = lower(type);
    if (t == "bit") return (values + 7) / 8;
    if (t == "vtkidtype") return 4 * values;
    if (t == "long" || t == "unsigned_long" || t == "vtktypeint64" || t == "vtktypeuint64") return 8 * values;
    return values * scalar_size(parse_type(path, type));
}

std::uint64_t product(const std::string& path, std::uint64_t a, std::uint64_t b, const std::string& what) {
    if (b != 0 && a > std::numeric_limits<std::uint64_t>::max() / b) fail(path, what + " has too many values");
    return a * b;
}

// The words of the next non-blank line as strings: the window moves on under later reads.
std::vector<std::string> copied_words(Lines& lines, const char* wanted) {
    const std::vector<std::string_view> w = lines.words(wanted);
    return {w.begin(), w.end()};
}

// The optional "LOOKUP_TABLE name" line after SCALARS, read; returns the ASCII values on that
// line (0 or more; VTK's reader reads words, so they may follow the name there: they were
// lost) and sets `data` to where the values start. BINARY data starts on the next line.
std::uint64_t skip_lookup_table_line(Lines& lines, bool binary, std::size_t& data) {
    data = lines.offset();
    if (!lines.next_starts_with("LOOKUP_TABLE")) return 0;
    const std::vector<std::string_view> w = lines.words("LOOKUP_TABLE");
    if (binary || w.size() <= 2) {
        data = lines.offset();
        return 0;
    }
    data = lines.offset_of(w[2]);
    return w.size() - 2;
}

// Whether the next `count` lines are one encoded string each (vtkDataWriter writes blanks and
// '%' as %XX, so a string line has no blank in it; an empty one is a blank line) and the line
// after them can follow a key: a blank one (the block's end), the next key's NAME, or the
// file's end. Reads them when so; else reads nothing.
bool skip_string_lines(Lines& lines, std::uint64_t count, const char* context) {
    const std::size_t start = lines.offset();
    if (count > lines.bytes_left()) return false;  // a line a string
    bool strings = true;
    for (std::uint64_t i = 0; i < count && strings; ++i) {
        if (lines.bytes_left() == 0) strings = false;
        else strings = split_words(lines.raw(context)).size() <= 1;
    }
    if (strings && lines.bytes_left() > 0) {
        const std::size_t after = lines.offset();
        const std::string_view next = trim(lines.raw(context));
        strings = next.empty() || next.substr(0, 5) == "NAME ";
        lines.seek(after);
    }
    if (!strings) lines.seek(start);
    return strings;
}

// An array's INFORMATION keys ("INFORMATION count" read), as vtkDataWriter writes them: a
// "NAME key LOCATION class" line (after any blank lines), then "DATA" and the value on one
// line, but a string vector's strings on lines of their own after "DATA count". An empty
// string is a blank line, which ended the METADATA skip early ("unknown cell data attribute").
// Which keys hold string vectors only VTK's key registry knows, so a "DATA n" line is taken
// for one where the n lines after it read as strings (an integer key's n otherwise).
void skip_information(Lines& lines, const std::string& path, std::string_view count, const char* context) {
    const std::size_t keys = parse_size(path, "INFORMATION", count);
    if (keys > lines.bytes_left()) fail(path, std::string("ends inside ") + context + " (truncated)");  // a line a key
    for (std::size_t k = 0; k < keys; ++k) {
        const std::vector<std::string_view> name = lines.words(context);
        if (name[0] != "NAME") continue;  // VTK's reader passes over such a line, as one key
        const std::vector<std::string_view> data = split_words(lines.raw(context));
        if (data.size() == 2 && data[0] == "DATA" && data[1].find_first_not_of("0123456789") == std::string_view::npos &&
            data[1].size() < 19)
            (void)skip_string_lines(lines, std::stoull(std::string(data[1])), context);
    }
}

// Skips an array's METADATA block, if one follows, as VTK's reader does: the blank lines before
// it (ASCII values end with one when their count is a multiple of nine, strings always do),
// then lines to a blank one, but COMPONENT_NAMES is one line a component, and an unnamed
// component's is blank (INFORMATION's keys: skip_information). Taking the blank line before
// METADATA, or an unnamed component's, for the block's end refused files VTK wrote ("unknown
// cell data attribute 'METADATA'").
void skip_metadata(Lines& lines, const std::string& path, std::uint64_t components, const std::string& what) {
    if (!lines.next_starts_with("METADATA")) return;
    const std::string context = "the METADATA block of " + what;
    (void)lines.words(context.c_str());  // METADATA, after any blank lines
    for (;;) {
        const std::vector<std::string_view> line = split_words(lines.raw(context.c_str()));
        if (line.empty()) return;
        if (line.size() == 2 && lower(line[0]) == "information") {
            const std::string count(line[1]);  // the window moves on under later reads
            skip_information(lines, path, count, context.c_str());
            continue;
        }
        if (line.size() != 1 || lower(line[0]) != "component_names") continue;
        if (components > lines.bytes_left()) fail(path, "ends inside " + context + " (truncated)");  // a line a name
        for (std::uint64_t c = 0; c < components; ++c) lines.skip_line(context.c_str());
    }
}

// Skips an array's `values` values (`components` a tuple) of `type` after its header line, as
// vtkDataWriter writes them: BINARY bytes and a line break; ASCII numbers, several a line.
// Strings: in ASCII one a line (spaces as %20, possibly empty), in BINARY each after a
// big-endian length of 1, 2, 4 or 8 bytes whose top two bits say which (11, 10, 01, 00;
// checked against VTK 9.1's output). Variants: one a line in both. Then the array's METADATA
// block, if one follows.
void skip_values(Lines& lines, const std::string& path, bool binary, std::uint64_t values, std::uint64_t components,
                 const std::string& type, const std::string& what) {
    if (values / 8 > lines.bytes_left()) fail(path, "ends inside " + what + " (truncated)");  // a value takes a bit or more
    const std::string t = lower(type);
    const bool strings = t == "string" || t == "utf8_string";  // utf8_string: a vtkUnicodeStringArray
    if (t == "variant" || (!binary && strings)) {  // variants are "type value" lines in BINARY too
        for (std::uint64_t v = 0; v < values; ++v) lines.skip_line(what.c_str());
    } else if (!binary) {
        // The type checked as in BINARY: an unknown one's values were counted as words, and a
        // utf8_string's or variant's lines misread as header lines.
        (void)binary_bytes(path, type, 0);
        for (std::uint64_t left = values; left > 0;) {
            const std::size_t n = lines.words(what.c_str()).size();
            if (n > left) fail(path, what + " has more values than its " + std::to_string(values));
            left -= n;
        }
    } else if (strings) {
        for (std::uint64_t v = 0; v < values; ++v) {
            const std::uint64_t first = lines.big_endian(1, what.c_str());
            const std::size_t prefix = first >= 0xC0 ? 1 : first >= 0x80 ? 2 : first >= 0x40 ? 4 : 8;
            const std::uint64_t length = lines.big_endian(prefix, what.c_str()) & (~std::uint64_t{0} >> (66 - 8 * prefix));
            lines.skip_bytes(prefix, what.c_str());
            lines.skip_bytes(length, what.c_str());
        }
        lines.skip_line_break();
    } else {
        lines.skip_bytes(binary_bytes(path, type, values), what.c_str());
        lines.skip_line_break();
    }
    skip_metadata(lines, path, components, what);
}

// A FIELD's arrays ("FIELD name count" read), skipped as their lines say: the dataset's field
// data before the geometry (a time value, a cycle), or a FIELD of the cell data. Both were
// refused, so a file VTK wrote with either did not read.
void skip_field(Lines& lines, const std::string& path, bool binary, const std::vector<std::string>& field) {
    if (field.size() != 3) fail(path, "'FIELD' takes a name and an array count");
    const std::size_t arrays = parse_size(path, "FIELD", field[2]);
    for (std::size_t i = 0; i < arrays; ++i) {
        const std::vector<std::string> a = copied_words(lines, "a FIELD array");
        if (a.size() == 1 && keyword(a[0]) == "NULL_ARRAY") continue;  // what VTK writes for a null array
        if (a.size() != 4) fail(path, "a FIELD array line is 'name components tuples type'");
        const std::string what = "FIELD array '" + shown(a[0]) + "'";
        const std::uint64_t components = parse_size(path, "FIELD array", a[1]);
        skip_values(lines, path, binary, product(path, components, parse_size(path, "FIELD array", a[2]), what),
                    components, a[3], what);
    }
}

// Skips one attribute (its line `a` read) of `count` tuples: the cell data's before the point
// data (how VTK writes a volume that has both), and the point data's before the volume's
// array (VECTORS, NORMALS, ... that VTK's reader passes looking for the scalars). Both were
// refused. False, reading nothing more, for a line that is no attribute: the caller says why.
bool skip_attribute(Lines& lines, const std::string& path, bool binary, std::uint64_t count,
                    const std::vector<std::string>& a, const std::string& data) {
    const std::string k = keyword(a[0]);
    const std::string what = data + " " + k + (a.size() > 1 ? " '" + shown(a[1]) + "'" : std::string());
    const auto need = [&](std::size_t lo, std::size_t hi, const char* form) {
        if (a.size() < lo || a.size() > hi) fail(path, "'" + k + "' is '" + k + " " + form + "'");
    };
    const auto per_tuple = [&](std::uint64_t n, const std::string& type) {
        skip_values(lines, path, binary, product(path, count, n, what), n, type, what);
    };
    if (k == "SCALARS") {
        need(3, 4, "name type [components]");
        const std::uint64_t components = a.size() == 4 ? parse_size(path, "SCALARS", a[3]) : 1;
        std::size_t data = 0;
        const std::uint64_t on_line = skip_lookup_table_line(lines, binary, data);
        const std::uint64_t values = product(path, count, components, what);
        if (on_line > values) fail(path, what + " has more values than its " + std::to_string(values));
        skip_values(lines, path, binary, values - on_line, components, a[2], what);
    } else if (k == "COLOR_SCALARS") {  // bytes in BINARY, fractions in ASCII
        need(3, 3, "name components");
        per_tuple(parse_size(path, "COLOR_SCALARS", a[2]), binary ? "unsigned_char" : "float");
    } else if (k == "VECTORS" || k == "NORMALS" || k == "TENSORS" || k == "TENSORS6") {
        need(3, 3, "name type");
        per_tuple(k == "TENSORS" ? 9 : k == "TENSORS6" ? 6 : 3, a[2]);
    } else if (k == "TEXTURE_COORDINATES") {
        need(4, 4, "name dimension type");
        per_tuple(parse_size(path, "TEXTURE_COORDINATES", a[2]), a[3]);
    } else if (k == "GLOBAL_IDS" || k == "PEDIGREE_IDS") {
        need(3, 3, "name type");
        per_tuple(1, a[2]);
    } else if (k == "LOOKUP_TABLE") {  // RGBA per entry: bytes in BINARY, fractions in ASCII
        need(3, 3, "name size");
        skip_values(lines, path, binary, product(path, parse_size(path, "LOOKUP_TABLE", a[2]), 4, what), 4,
                    binary ? "unsigned_char" : "float", what);
    } else if (k == "FIELD") {
        skip_field(lines, path, binary, a);
    } else {
        return false;
    }
    return true;
}

void skip_cell_data(Lines& lines, const std::string& path, bool binary, std::uint64_t cells) {
    while (!lines.next_starts_with("POINT_DATA")) {
        const std::vector<std::string> a = copied_words(lines, "POINT_DATA");
        if (!skip_attribute(lines, path, binary, cells, a, "cell data"))
            fail(path, "unknown cell data attribute '" + shown(a[0]) + "'");
    }
}

void expect_count(const std::string& path, const std::vector<std::string_view>& words, std::size_t count) {
    if (words.size() != count)
        fail(path, "'" + shown(words[0]) + "' takes " + std::to_string(count - 1) + " values, not " +
                       std::to_string(words.size() - 1));
}

}  // namespace

VolumeHeader read_vtk_header(const InputFile& file) {
    const std::string& path = file.path();
    if (file.size() == 0) fail(path, "file is empty");
    Lines lines(path, file);
    if (lower(lines.raw("the version line").substr(0, 22)) != "# vtk datafile version")
        fail(path, "not a legacy VTK file (the first line is not '# vtk DataFile Version x.y')");
    (void)lines.raw("the title line");

    VolumeHeader h;
    VolumeInfo& info = h.info;
    SampleLayout& layout = h.layout;
    info.format = "vtk";
    const std::vector<std::string_view> encoding = lines.words("ASCII or BINARY");
    if (keyword(encoding[0]) == "BINARY") {
        info.encoding = "raw";
        info.big_endian = true;  // legacy VTK's binary data always is
    } else if (keyword(encoding[0]) == "ASCII") {
        info.encoding = "ascii";
        layout.text = true;
    } else {
        fail(path, "the third line is '" + shown(encoding[0]) + "', not ASCII or BINARY");
    }
    const std::vector<std::string_view> dataset = lines.words("DATASET");
    if (keyword(dataset[0]) != "DATASET" || dataset.size() != 2) fail(path, "the fourth line is not 'DATASET type'");
    if (keyword(dataset[1]) != "STRUCTURED_POINTS")
        fail(path, "DATASET " + shown(dataset[1]) +
                       ": only STRUCTURED_POINTS (an image volume) is read; meshes are read from .stl, .ply or .obj");

    bool have_dims = false;
    std::array<std::vector<double>, 3> axes;
    // EXTENT's first indices, and the spacing with its sign: the first sample lies at
    // ORIGIN + extent_first * spacing.
    std::array<long long, 3> extent_first{0, 0, 0};
    std::array<double, 3> signed_spacing{1, 1, 1};
    for (;;) {
        const std::vector<std::string_view> w = lines.words("POINT_DATA");
        const std::string k = keyword(w[0]);
        if (k == "POINT_DATA") {
            expect_count(path, w, 2);
            if (!have_dims) fail(path, "POINT_DATA comes before DIMENSIONS");
            const std::size_t points = parse_size(path, "POINT_DATA", w[1]);
            sample_bytes(path, info.dims, ScalarType::U8);  // the product is checked first
            if (points != info.dims[0] * info.dims[1] * info.dims[2])
                fail(path, "POINT_DATA " + std::to_string(points) + " does not match DIMENSIONS " +
                               std::to_string(info.dims[0]) + " " + std::to_string(info.dims[1]) + " " +
                               std::to_string(info.dims[2]));
            break;
        }
        if (k == "DIMENSIONS") {
            expect_count(path, w, 4);
            for (std::size_t a = 0; a < 3; ++a) info.dims[a] = parse_size(path, "DIMENSIONS", w[a + 1]);
            extent_first = {0, 0, 0};  // the last of EXTENT and DIMENSIONS holds
            have_dims = true;
        } else if (k == "EXTENT") {  // what vtkStructuredPointsWriter writes with WriteExtent on: it was refused
            expect_count(path, w, 7);
            for (std::size_t a = 0; a < 3; ++a) {
                const long long lo = parse_integer(path, "EXTENT", w[2 * a + 1]);
                const long long hi = parse_integer(path, "EXTENT", w[2 * a + 2]);
                const std::string range = "EXTENT " + shown(w[2 * a + 1]) + " " + shown(w[2 * a + 2]);
                if (lo < std::numeric_limits<std::int32_t>::min() || hi > std::numeric_limits<std::int32_t>::max())
                    fail(path, range + " is out of VTK's int range");  // and hi - lo + 1 cannot overflow
                if (hi < lo) fail(path, range + " is empty");
                info.dims[a] = static_cast<std::size_t>(hi - lo) + 1;
                extent_first[a] = lo;
            }
            have_dims = true;
        } else if (k == "SPACING" || k == "ASPECT_RATIO") {
            expect_count(path, w, 4);
            for (std::size_t a = 0; a < 3; ++a) {
                const double s = parse_double(path, k, w[a + 1]);
                info.spacing[a] = checked_spacing(path, k.c_str(), s);
                signed_spacing[a] = s;  // the last SPACING holds: its sign is applied after the loop
            }
        } else if (k == "ORIGIN") {
            expect_count(path, w, 4);
            for (std::size_t a = 0; a < 3; ++a) info.origin[a] = checked_origin(path, "ORIGIN", parse_double(path, "ORIGIN", w[a + 1]));
        } else if (k == "FIELD") {
            skip_field(lines, path, info.encoding == "raw", std::vector<std::string>(w.begin(), w.end()));
        } else if (k == "CELL_DATA") {
            expect_count(path, w, 2);
            skip_cell_data(lines, path, info.encoding == "raw", parse_size(path, "CELL_DATA", w[1]));
        } else {
            fail(path, "unknown keyword '" + shown(w[0]) + "' in a STRUCTURED_POINTS header");
        }
    }

    // The volume: the point data's first SCALARS, COLOR_SCALARS or FIELD, which must have one
    // component; other attributes before it are skipped, as VTK's reader passes them.
    std::vector<std::string> array;
    std::string k;
    for (;;) {
        array = copied_words(lines, "SCALARS or FIELD");
        k = keyword(array[0]);
        if (k == "SCALARS" || k == "COLOR_SCALARS" || k == "FIELD") break;
        if (!skip_attribute(lines, path, info.encoding == "raw", info.dims[0] * info.dims[1] * info.dims[2], array,
                            "point data"))
            fail(path, "the point data has " + shown(array[0]) +
                           " where the volume's array should be; a volume is read from SCALARS or COLOR_SCALARS "
                           "with one component, or a FIELD array");
    }
    std::size_t data_start = 0;  // where the volume's samples start
    if (k == "SCALARS") {
        if (array.size() != 3 && array.size() != 4) fail(path, "'SCALARS' takes a name, a type and optionally a component count");
        layout.type = parse_type(path, array[2]);
        if (array.size() == 4 && parse_size(path, "SCALARS", array[3]) != 1)
            fail(path, "SCALARS '" + shown(array[1]) + "' has " + shown(array[3]) + " components; a volume needs 1");
        (void)skip_lookup_table_line(lines, info.encoding == "raw", data_start);
    } else if (k == "COLOR_SCALARS") {
        if (array.size() != 3) fail(path, "'COLOR_SCALARS' takes a name and a component count");
        if (parse_size(path, "COLOR_SCALARS", array[2]) != 1)
            fail(path, "COLOR_SCALARS '" + shown(array[1]) + "' has " + shown(array[2]) + " components; a volume needs 1");
        layout.type = ScalarType::U8;
        layout.unit_colors = layout.text;  // ASCII writes byte b as b / 255
    } else if (k == "FIELD") {
        if (array.size() != 3) fail(path, "'FIELD' takes a name and an array count");
        const std::size_t count = parse_size(path, "FIELD", array[2]);
        // The first array that is not VTK's NULL_ARRAY placeholder (a null array has no values).
        std::vector<std::string_view> first;
        for (std::size_t i = 0; first.empty(); ++i) {
            if (i == count)
                fail(path, "FIELD '" + shown(array[1]) + "' has no arrays" + (count ? ", only NULL_ARRAY placeholders" : ""));
            first = lines.words("the FIELD's first array");
            if (first.size() == 1 && keyword(first[0]) == "NULL_ARRAY") first.clear();
        }
        if (first.size() != 4) fail(path, "a FIELD array line is 'name components tuples type'");
        if (parse_size(path, "FIELD array", first[1]) != 1)
            fail(path, "FIELD array '" + shown(first[0]) + "' has " + shown(first[1]) + " components; a volume needs 1");
        if (parse_size(path, "FIELD array", first[2]) != info.dims[0] * info.dims[1] * info.dims[2])
            fail(path, "FIELD array '" + shown(first[0]) + "' has " + shown(first[2]) + " tuples, not POINT_DATA's count");
        layout.type = parse_type(path, first[3]);
    }
    if (k != "SCALARS") data_start = lines.offset();

    info.type = layout.type;
    info.data_file = path;
    for (std::size_t a = 0; a < 3; ++a)
        if (extent_first[a] != 0)
            info.origin[a] = checked_origin(path, "EXTENT",
                                            info.origin[a] + static_cast<double>(extent_first[a]) * signed_spacing[a]);
    for (std::size_t a = 0; a < 3; ++a)
        if (signed_spacing[a] < 0) reverse_direction(axes, a);
    apply_directions(h, axis_directions(axes));
    layout.dims = info.dims;
    layout.big_endian = info.big_endian;
    layout.data_path = path;
    layout.offset = data_start;
    layout.more_may_follow = true;  // further arrays, and the writer's newline after binary data
    return h;
}

}  // namespace voxmesh::io
