// Legacy VTK (.vtk, as vtkStructuredPointsWriter and vtkDataSetWriter write it, file versions
// 1.0 to 5.1): DATASET STRUCTURED_POINTS with DIMENSIONS, SPACING (or ASPECT_RATIO) and ORIGIN,
// then POINT_DATA whose first array is the volume: SCALARS with one component, COLOR_SCALARS
// with one (how VTK writes unsigned char: bytes in BINARY, 0..1 in ASCII), or the first array
// of a FIELD. BINARY data is big-endian; ASCII data is numbers as text. The dataset's field data
// before the geometry is skipped, and arrays after the volume's (more point data, cell data)
// are ignored; cell data before the point data (as VTK writes a volume that has both) is an
// error.
#include "header_text.hpp"
#include "input_file.hpp"
#include "readers.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace voxmesh::io {

namespace {

// The most bytes read looking for the end of the header (titles and keywords are short).
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
// skipped.
class Lines {
public:
    Lines(const std::string& path, std::string_view text) : path_(path), text_(text) {}

    // The next line, blank or not; fails at the end of what was read.
    std::string_view raw(const char* wanted) {
        std::string_view line;
        if (!next_line(text_, pos_, line))
            fail(path_, std::string("ends before ") + wanted + " (truncated, or not a volume file)");
        return line;
    }
    // The next non-blank line, as words.
    std::vector<std::string_view> words(const char* wanted) {
        for (;;) {
            const std::string_view line = trim(raw(wanted));
            if (!line.empty()) return split_words(line);
        }
    }
    // Where the line after the last one read starts: the data, after the header.
    std::size_t position() const { return pos_; }
    // Skips `bytes` of binary data from position(), then the writer's line break after them.
    void skip_bytes(std::size_t bytes, const char* what) {
        if (bytes > text_.size() - pos_) past_header_read(what);
        pos_ += bytes;
        if (text_.substr(pos_, 2) == "\r\n") pos_ += 2;
        else if (text_.substr(pos_, 1) == "\n") ++pos_;
    }
    // The byte at position() + at (a binary string's length).
    unsigned char byte_at(std::size_t at, const char* what) const {
        if (at >= text_.size() - pos_) past_header_read(what);
        return static_cast<unsigned char>(text_[pos_ + at]);
    }
    // Past blanks of any kind, as words() reads the line: an indented "  LOOKUP_TABLE default"
    // (or one after a line of spaces) was taken for the first samples, silently in BINARY.
    bool next_starts_with(std::string_view keyword) const {
        std::size_t at = pos_;
        while (at < text_.size() && trim(text_.substr(at, 1)).empty()) ++at;
        return lower(text_.substr(at, keyword.size())) == lower(keyword);
    }
    [[noreturn]] void past_header_read(const char* what) const {
        if (text_.size() < kMaxVtkHeader) fail(path_, std::string("ends inside ") + what + " (truncated)");
        fail(path_, std::string(what) + " runs past the first " + std::to_string(kMaxVtkHeader) +
                        " bytes of the file (a header this long is not read)");
    }

private:
    const std::string& path_;
    std::string_view text_;
    std::size_t pos_ = 0;
};

std::string keyword(std::string_view word) {
    std::string k(word);
    for (char& c : k) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return k;
}

// Bytes of `values` values of a FIELD array's type in BINARY, as vtkDataWriter writes them
// (vtkIdType as 32 bits, long as 64, bits packed eight a byte).
std::size_t field_bytes(const std::string& path, std::string_view type, std::size_t values) {
    const std::string t = lower(type);
    if (t == "bit") return (values + 7) / 8;
    if (t == "vtkidtype") return 4 * values;
    if (t == "long" || t == "unsigned_long" || t == "vtktypeint64" || t == "vtktypeuint64") return 8 * values;
    return values * scalar_size(parse_type(path, type));
}

// The dataset's field data before its geometry (vtkDataWriter writes a time value, a cycle
// there: "FIELD FieldData 2"), skipped array by array: numbers, or strings (ASCII: one a line,
// spaces as %20; BINARY: each after a big-endian length of 1, 2, 4 or 8 bytes whose top two
// bits say which: 11, 10, 01, 00). It was refused, so a file VTK wrote with field data did not
// read. Only what the header read holds is skipped (field data is small).
void skip_field_data(Lines& lines, const std::string& path, const std::vector<std::string_view>& field, bool binary) {
    if (field.size() != 3) fail(path, "'FIELD' takes a name and an array count");
    const std::size_t arrays = parse_size(path, "FIELD", field[2]);
    for (std::size_t i = 0; i < arrays; ++i) {
        const std::vector<std::string_view> a = lines.words("a FIELD array");
        if (a.size() == 1 && keyword(a[0]) == "NULL_ARRAY") continue;  // what VTK writes for a null array
        if (a.size() != 4) fail(path, "a FIELD array line is 'name components tuples type'");
        const std::size_t components = parse_size(path, "FIELD array", a[1]);
        const std::size_t tuples = parse_size(path, "FIELD array", a[2]);
        // A value takes a byte or more (bits aside): a larger count cannot lie in the header read.
        if (components > kMaxVtkHeader || tuples > kMaxVtkHeader || components * tuples > 8 * kMaxVtkHeader)
            lines.past_header_read("the dataset's FIELD array");
        const std::size_t values = components * tuples;
        const bool strings = lower(a[3]) == "string";
        if (!binary && strings) {
            for (std::size_t v = 0; v < values; ++v) (void)lines.raw("a FIELD string");  // one a line, may be empty
        } else if (!binary) {
            for (std::size_t left = values; left > 0;) {
                const std::size_t n = lines.words("a FIELD array's values").size();
                if (n > left)
                    fail(path, "FIELD array '" + shown(a[0]) + "' has more values than its " + std::to_string(values));
                left -= n;
            }
        } else if (strings) {
            std::size_t at = 0;
            for (std::size_t v = 0; v < values; ++v) {
                const unsigned char first = lines.byte_at(at, "a FIELD string");
                const std::size_t prefix = first >= 0xC0 ? 1 : first >= 0x80 ? 2 : first >= 0x40 ? 4 : 8;
                std::uint64_t length = first & 0x3F;
                for (std::size_t b = 1; b < prefix; ++b) length = length << 8 | lines.byte_at(at + b, "a FIELD string");
                if (length > kMaxVtkHeader) lines.past_header_read("a FIELD string");
                at += prefix + static_cast<std::size_t>(length);
            }
            lines.skip_bytes(at, "a FIELD string array");
        } else {
            lines.skip_bytes(field_bytes(path, a[3], values), "a FIELD array");
        }
        if (lines.next_starts_with("METADATA")) {  // version 5.1's block after an array, to a blank line
            std::string_view line;
            do line = lines.raw("the end of a METADATA block");
            while (!trim(line).empty());
        }
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
    const std::string text = file.read(0, kMaxVtkHeader);
    Lines lines(path, text);
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
            have_dims = true;
        } else if (k == "SPACING" || k == "ASPECT_RATIO") {
            expect_count(path, w, 4);
            for (std::size_t a = 0; a < 3; ++a) {
                const double s = parse_double(path, k, w[a + 1]);
                info.spacing[a] = checked_spacing(path, k.c_str(), s);
                if (s < 0) reverse_direction(axes, a);
            }
        } else if (k == "ORIGIN") {
            expect_count(path, w, 4);
            for (std::size_t a = 0; a < 3; ++a) info.origin[a] = checked_origin(path, "ORIGIN", parse_double(path, "ORIGIN", w[a + 1]));
        } else if (k == "FIELD") {
            skip_field_data(lines, path, w, info.encoding == "raw");
        } else if (k == "CELL_DATA") {
            fail(path, "CELL_DATA before POINT_DATA is not supported: the volume is the point data's first array");
        } else {
            fail(path, "unknown keyword '" + shown(w[0]) + "' in a STRUCTURED_POINTS header");
        }
    }

    // The volume: the point data's first array, with one component.
    const std::vector<std::string_view> array = lines.words("SCALARS or FIELD");
    const std::string k = keyword(array[0]);
    if (k == "SCALARS") {
        if (array.size() != 3 && array.size() != 4) fail(path, "'SCALARS' takes a name, a type and optionally a component count");
        layout.type = parse_type(path, array[2]);
        if (array.size() == 4 && parse_size(path, "SCALARS", array[3]) != 1)
            fail(path, "SCALARS '" + shown(array[1]) + "' has " + shown(array[3]) + " components; a volume needs 1");
        if (lines.next_starts_with("LOOKUP_TABLE")) (void)lines.words("LOOKUP_TABLE");
    } else if (k == "COLOR_SCALARS") {
        if (array.size() != 3) fail(path, "'COLOR_SCALARS' takes a name and a component count");
        if (parse_size(path, "COLOR_SCALARS", array[2]) != 1)
            fail(path, "COLOR_SCALARS '" + shown(array[1]) + "' has " + shown(array[2]) + " components; a volume needs 1");
        layout.type = ScalarType::U8;
        layout.unit_colors = layout.text;  // ASCII writes byte b as b / 255
    } else if (k == "FIELD") {
        if (array.size() != 3) fail(path, "'FIELD' takes a name and an array count");
        if (parse_size(path, "FIELD", array[2]) == 0) fail(path, "FIELD '" + shown(array[1]) + "' has no arrays");
        const std::vector<std::string_view> first = lines.words("the FIELD's first array");
        if (first.size() != 4) fail(path, "a FIELD array line is 'name components tuples type'");
        if (parse_size(path, "FIELD array", first[1]) != 1)
            fail(path, "FIELD array '" + shown(first[0]) + "' has " + shown(first[1]) + " components; a volume needs 1");
        if (parse_size(path, "FIELD array", first[2]) != info.dims[0] * info.dims[1] * info.dims[2])
            fail(path, "FIELD array '" + shown(first[0]) + "' has " + shown(first[2]) + " tuples, not POINT_DATA's count");
        layout.type = parse_type(path, first[3]);
    } else {
        fail(path, "the point data's first array is " + shown(array[0]) +
                       "; a volume is read from SCALARS or COLOR_SCALARS with one component, or a FIELD array");
    }

    info.type = layout.type;
    info.data_file = path;
    apply_directions(h, axis_directions(axes));
    layout.dims = info.dims;
    layout.big_endian = info.big_endian;
    layout.data_path = path;
    layout.offset = lines.position();
    layout.more_may_follow = true;  // further arrays, and the writer's newline after binary data
    return h;
}

}  // namespace voxmesh::io
