// MetaImage (ITK's MetaIO): "Key = Value" lines ending with ElementDataFile, which names
// the data file or says LOCAL (samples follow that line: .mha; HeaderSize > 0 puts them that
// many bytes from the start of the file, as in MetaIO, either file). CompressedData is a zlib
// stream. TransformMatrix gives flipped axes (see io.hpp); AnatomicalOrientation is ignored.
#include "header_text.hpp"
#include "input_file.hpp"
#include "readers.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <map>
#include <vector>

namespace voxmesh::io {

namespace {

constexpr std::size_t kMaxHeader = 1 << 20;

ScalarType parse_element_type(const std::string& path, const std::string& value) {
    static const std::map<std::string, ScalarType> kTypes = {
        {"MET_UCHAR", ScalarType::U8},   {"MET_CHAR", ScalarType::I8},  {"MET_USHORT", ScalarType::U16},
        {"MET_SHORT", ScalarType::I16},  {"MET_UINT", ScalarType::U32}, {"MET_INT", ScalarType::I32},
        {"MET_FLOAT", ScalarType::F32},  {"MET_DOUBLE", ScalarType::F64},
        // MetaIO's MET_LONG and MET_ULONG are 4 bytes (MET_ValueTypeSize), whatever C's long is.
        {"MET_LONG", ScalarType::I32},   {"MET_ULONG", ScalarType::U32}};
    const auto it = kTypes.find(value);
    if (it == kTypes.end())
        fail(path, "unsupported ElementType '" + value +
                       "' (supported: MET_UCHAR, MET_CHAR, MET_USHORT, MET_SHORT, MET_UINT, MET_INT, MET_ULONG, "
                       "MET_LONG, MET_FLOAT, MET_DOUBLE)");
    return it->second;
}

bool parse_bool(const std::string& path, const char* field, const std::string& value) {
    const std::string v = lower(value);
    if (v == "true" || v == "1") return true;
    if (v == "false" || v == "0") return false;
    fail(path, std::string("'") + field + "' must be True or False, not '" + value + "'");
}

// Index axes' direction vectors from a TransformMatrix (none: empty vectors). As in ITK,
// the i-th run of NDims values is axis i's direction.
std::array<std::vector<double>, 3> transform_axes(const std::string& path, const std::string* matrix,
                                                 std::size_t ndims) {
    std::array<std::vector<double>, 3> axes;
    if (!matrix) return axes;
    const std::vector<double> m = parse_doubles(path, "TransformMatrix", *matrix, ndims * ndims);
    for (std::size_t a = 0; a < 3; ++a)
        axes[a].assign(m.begin() + static_cast<std::ptrdiff_t>(a * ndims),
                       m.begin() + static_cast<std::ptrdiff_t>((a + 1) * ndims));
    return axes;
}

}  // namespace

VolumeHeader read_metaimage_header(const InputFile& file) {
    const std::string& path = file.path();
    if (file.size() == 0) fail(path, "file is empty");
    const std::string text = file.read(0, kMaxHeader);

    std::map<std::string, std::string> fields;  // keys lower-cased
    std::size_t pos = 0, line_number = 0;
    std::string_view line;
    bool found_data_file = false;
    while (next_line(text, pos, line)) {
        ++line_number;
        if (trim(line).empty()) continue;
        const std::size_t eq = line.find('=');
        if (eq == std::string_view::npos)
            fail(path, "header line " + std::to_string(line_number) + " is not 'Key = Value' (not a MetaImage header?)");
        const std::string key = lower(trim(line.substr(0, eq)));
        if (!fields.emplace(key, std::string(trim(line.substr(eq + 1)))).second)
            fail(path, "header key '" + std::string(trim(line.substr(0, eq))) + "' appears twice");
        if (key == "elementdatafile") {
            found_data_file = true;
            break;  // always the last key; LOCAL data starts on the next byte
        }
    }
    if (!found_data_file) {
        if (text.size() < file.size() && fields.empty()) fail(path, "not a MetaImage header");
        fail(path, "header lacks ElementDataFile (it must be the last key)");
    }
    const std::size_t data_start = pos;

    auto required = [&](const char* key, const char* name) -> const std::string& {
        const auto it = fields.find(key);
        if (it == fields.end()) fail(path, std::string("header lacks the required key '") + name + "'");
        return it->second;
    };
    auto optional = [&](const char* key) -> const std::string* {
        const auto it = fields.find(key);
        return it == fields.end() ? nullptr : &it->second;
    };

    VolumeHeader h;
    VolumeInfo& info = h.info;
    SampleLayout& layout = h.layout;
    info.format = "metaimage";
    info.file_bytes = file.size();

    if (const std::string* object = optional("objecttype"); object && lower(*object) != "image")
        fail(path, "ObjectType is '" + *object + "', not Image");
    const std::size_t ndims = parse_size(path, "NDims", required("ndims", "NDims"));
    const std::vector<std::size_t> sizes = parse_sizes(path, "DimSize", required("dimsize", "DimSize"));
    if (sizes.size() != ndims)
        fail(path, "NDims is " + std::to_string(ndims) + " but DimSize lists " + std::to_string(sizes.size()) +
                       " values");
    info.dims = volume_dims(path, sizes);
    info.type = parse_element_type(path, required("elementtype", "ElementType"));
    if (const std::string* channels = optional("elementnumberofchannels");
        channels && parse_size(path, "ElementNumberOfChannels", *channels) != 1)
        fail(path, "ElementNumberOfChannels is " + *channels + "; only scalar volumes (1) are supported");
    if (const std::string* binary = optional("binarydata"); binary && !parse_bool(path, "BinaryData", *binary))
        fail(path, "BinaryData = False (ASCII samples) is not supported");

    const std::string* spacing = optional("elementspacing");
    if (!spacing) spacing = optional("elementsize");
    std::array<bool, 3> negative_spacing{false, false, false};
    if (spacing) {
        const std::vector<double> s = parse_doubles(path, "ElementSpacing", *spacing, ndims);
        for (std::size_t a = 0; a < 3; ++a) {
            info.spacing[a] = checked_spacing(path, "ElementSpacing", s[a]);
            negative_spacing[a] = s[a] < 0;
        }
    }
    const char* origin_name = nullptr;
    for (const char* key : {"offset", "position", "origin"})
        if (optional(key)) {
            if (origin_name) fail(path, "header gives the origin twice (Offset, Position or Origin)");
            origin_name = key;
        }
    if (origin_name) {
        const std::vector<double> o = parse_doubles(path, "Offset", *optional(origin_name), ndims);
        for (std::size_t a = 0; a < 3; ++a) info.origin[a] = checked_origin(path, "Offset", o[a]);
    }
    const std::string* matrix = optional("transformmatrix");  // MetaIO's other spellings:
    if (!matrix) matrix = optional("rotation");
    if (!matrix) matrix = optional("orientation");
    std::array<std::vector<double>, 3> axes = transform_axes(path, matrix, ndims);
    check_directions(path, axes, [ndims](std::size_t a, std::size_t c) {
        return "TransformMatrix value " + std::to_string(a * ndims + c + 1);
    });
    for (std::size_t a = 0; a < 3; ++a)
        if (negative_spacing[a]) reverse_direction(axes, a);  // position = Offset + M (index * spacing)
    apply_directions(h, axis_directions(axes));

    const std::string* msb = optional("binarydatabyteordermsb");
    const std::string* element_msb = optional("elementbyteordermsb");
    if (msb) info.big_endian = parse_bool(path, "BinaryDataByteOrderMSB", *msb);
    if (element_msb) {
        const bool big = parse_bool(path, "ElementByteOrderMSB", *element_msb);
        if (msb && big != info.big_endian)
            fail(path, "BinaryDataByteOrderMSB and ElementByteOrderMSB disagree");
        info.big_endian = big;
    }

    const std::string* compressed = optional("compresseddata");
    layout.compressed = compressed && parse_bool(path, "CompressedData", *compressed);
    info.encoding = layout.compressed ? "gzip" : "raw";
    if (const std::string* csize = optional("compresseddatasize")) {
        if (!layout.compressed) fail(path, "CompressedDataSize given but CompressedData is not True");
        layout.compressed_size = parse_size(path, "CompressedDataSize", *csize);
        if (layout.compressed_size == 0) fail(path, "CompressedDataSize is 0");
    }
    long long header_size = 0;
    if (const std::string* hs = optional("headersize")) header_size = parse_integer(path, "HeaderSize", *hs);
    if (header_size < -1) fail(path, "HeaderSize must be -1 or more");
    if (header_size == -1 && layout.compressed) fail(path, "HeaderSize = -1 is only allowed for uncompressed data");

    layout.type = info.type;
    layout.dims = info.dims;
    layout.big_endian = info.big_endian;
    const std::string& data_file = fields["elementdatafile"];
    if (data_file == "LOCAL" || data_file == "Local" || data_file == "local") {  // MetaIO's spellings
        layout.data_path = path;
        // MetaIO seeks to HeaderSize from the start of the file, even in a LOCAL one.
        if (header_size > 0 && static_cast<std::size_t>(header_size) < data_start)
            fail(path, "HeaderSize " + std::to_string(header_size) + " points inside the header, which ends at byte " +
                           std::to_string(data_start));
        layout.offset = header_size > 0 ? static_cast<std::size_t>(header_size) : data_start;
        layout.min_start = data_start;  // HeaderSize = -1: the samples end the file, after the header
    } else {
        if (data_file.empty()) fail(path, "ElementDataFile is empty");
        // MetaIO takes LIST (or "LIST 2D") and names holding '%' (printf patterns, "img%03d.raw 1 10 1") as
        // several files; anything else is one file name, spaces included ("my scan.raw").
        const auto words = split_words(data_file);
        if ((!words.empty() && words[0] == "LIST") || data_file.find('%') != std::string::npos)
            fail(path, "ElementDataFile '" + data_file + "': lists and file patterns are not supported");
        layout.data_path = detached_data_path(file, data_file);
        layout.offset = static_cast<std::size_t>(std::max(header_size, 0LL));
    }
    layout.at_end = header_size == -1;
    info.data_file = layout.data_path;
    return h;
}

}  // namespace voxmesh::io
