// NRRD (teem's format, http://teem.sourceforge.net/nrrd/format.html): a text header of
// "field: value" lines ended by a blank line (attached data) or by the end of a .nhdr
// (detached, "data file"). Raw and gzip encodings, 3-D scalar volumes: axes beyond three must
// have size 1, and the three kept must be of kind domain, space or unknown.
#include "header_text.hpp"
#include "input_file.hpp"
#include "readers.hpp"

#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <vector>

namespace voxmesh::io {

namespace {

struct TypeName {
    const char* name;
    ScalarType type;
};
constexpr TypeName kTypes[] = {
    {"uchar", ScalarType::U8},         {"unsigned char", ScalarType::U8},   {"uint8", ScalarType::U8},
    {"uint8_t", ScalarType::U8},       {"signed char", ScalarType::I8},     {"int8", ScalarType::I8},
    {"int8_t", ScalarType::I8},        {"short", ScalarType::I16},          {"short int", ScalarType::I16},
    {"signed short", ScalarType::I16}, {"signed short int", ScalarType::I16}, {"int16", ScalarType::I16},
    {"int16_t", ScalarType::I16},      {"ushort", ScalarType::U16},         {"unsigned short", ScalarType::U16},
    {"unsigned short int", ScalarType::U16}, {"uint16", ScalarType::U16},   {"uint16_t", ScalarType::U16},
    {"int", ScalarType::I32},          {"signed int", ScalarType::I32},     {"int32", ScalarType::I32},
    {"int32_t", ScalarType::I32},      {"uint", ScalarType::U32},           {"unsigned int", ScalarType::U32},
    {"uint32", ScalarType::U32},       {"uint32_t", ScalarType::U32},       {"float", ScalarType::F32},
    {"double", ScalarType::F64},
};

ScalarType parse_type(const std::string& path, const std::string& value) {
    for (const TypeName& t : kTypes)
        if (value == t.name) return t.type;
    fail(path, "unsupported NRRD type '" + value +
                   "' (supported: 8/16/32-bit signed and unsigned integers, float, double)");
}

// Without a space, teem places axis a's samples by 'axis mins' (and 'axis maxs'): sample i at
// min + (i + 1/2) * step for cell centering (teem's default), min + i * step for node, where
// step is the axis's 'spacings' value or else (max - min) / (size, or size - 1 for node).
// The origin is sample 0's position; a step found from the extents is the axis's spacing (a
// negative one runs the axis the other way). Without a step the origin is the min itself.
void place_by_axis_extents(const std::string& path, VolumeHeader& h, const std::array<std::size_t, 3>& spatial,
                           const std::vector<std::size_t>& sizes, const std::vector<double>& spacings,
                           const std::vector<double>& mins, const std::vector<double>& maxs,
                           const std::string* centers, std::array<std::vector<double>, 3>& axes) {
    if (mins.empty()) return;
    std::vector<std::string> center;
    if (centers) {
        for (std::string_view word : split_words(*centers)) center.push_back(lower(word));
        if (center.size() != sizes.size())
            fail(path, "'dimension' is " + std::to_string(sizes.size()) + " but 'centers' lists " +
                           std::to_string(center.size()) + " values");
    }
    for (std::size_t k = 0; k < 3; ++k) {
        const std::size_t a = spatial[k];
        if (std::isnan(mins[a])) continue;
        const bool node = !center.empty() && center[a] == "node";
        double step = spacings.empty() ? NAN : spacings[a];
        if (std::isnan(step) && !maxs.empty() && !std::isnan(maxs[a])) {
            const std::size_t intervals = node ? sizes[a] - 1 : sizes[a];
            if (intervals > 0) {
                step = (maxs[a] - mins[a]) / static_cast<double>(intervals);
                h.info.spacing[k] = checked_spacing(path, "axis mins and axis maxs", step);
                if (step < 0) reverse_direction(axes, k);
            }
        }
        const double first = std::isnan(step) || node ? mins[a] : mins[a] + 0.5 * step;
        h.info.origin[k] = checked_origin(path, "axis mins", first);
    }
}

// "(1,0,0)" as numbers; "none" as an empty vector.
std::vector<std::vector<double>> parse_vectors(const std::string& path, const char* field, std::string_view value) {
    std::vector<std::vector<double>> out;
    std::size_t i = 0;
    while (true) {
        while (i < value.size() && (value[i] == ' ' || value[i] == '\t')) ++i;
        if (i >= value.size()) break;
        if (value.substr(i, 4) == "none") {
            out.emplace_back();
            i += 4;
            continue;
        }
        if (value[i] != '(') fail(path, std::string("field '") + field + "': expected '(' or 'none'");
        const std::size_t close = value.find(')', i);
        if (close == std::string_view::npos) fail(path, std::string("field '") + field + "': missing ')'");
        std::vector<double> v;
        std::string_view inner = value.substr(i + 1, close - i - 1);
        while (true) {
            const std::size_t comma = inner.find(',');
            v.push_back(parse_double(path, field, trim(inner.substr(0, comma))));
            if (comma == std::string_view::npos) break;
            inner.remove_prefix(comma + 1);
        }
        out.push_back(std::move(v));
        i = close + 1;
    }
    return out;
}

// A key or value of a "key:=value" line as teem reads it (airUnescape): a backslash-n is a line
// break and a doubled backslash one backslash; any other backslash stays as it is.
std::string unescaped(std::string_view text) {
    std::string out;
    for (std::size_t i = 0; i < text.size(); ++i) {
        if (text[i] == '\\' && i + 1 < text.size() && (text[i + 1] == '\\' || text[i + 1] == 'n')) {
            out += text[++i] == 'n' ? '\n' : '\\';
            continue;
        }
        out += text[i];
    }
    return out;
}

std::size_t space_dimension_of(const std::string& path, const std::string& space) {
    static const std::map<std::string, std::size_t> kSpaces = {
        {"right-anterior-superior", 3}, {"ras", 3}, {"left-anterior-superior", 3}, {"las", 3},
        {"left-posterior-superior", 3}, {"lps", 3}, {"scanner-xyz", 3}, {"3d-right-handed", 3},
        {"3d-left-handed", 3}, {"right-anterior-superior-time", 4}, {"rast", 4},
        {"left-anterior-superior-time", 4}, {"last", 4}, {"left-posterior-superior-time", 4}, {"lpst", 4},
        {"scanner-xyz-time", 4}, {"3d-right-handed-time", 4}, {"3d-left-handed-time", 4}};
    const auto it = kSpaces.find(lower(space));
    if (it == kSpaces.end()) fail(path, "unknown NRRD space '" + space + "'");
    return it->second;
}

// Offset just past `lines` lines from `offset` in the file holding the samples (the header's
// own file for attached data, as teem reads on after the blank line). A line ends at "\n",
// "\r\n" or a lone "\r", as teem's airOneLine reads it. Errors name the header too.
std::size_t skip_lines(const InputFile& header, const SampleLayout& layout, std::size_t lines, std::size_t offset) {
    std::optional<InputFile> detached;
    const InputFile& data = open_data(header, layout, detached);
    std::size_t left = lines;
    bool after_cr = false;  // the last line ended with '\r' at a chunk's end: a '\n' may follow
    for (;;) {
        const std::string chunk = data.read(offset, 1 << 16);
        if (chunk.empty()) {
            if (left == 0) return offset;
            fail(data.path(), "file ends before the " + std::to_string(lines) + " lines 'line skip' asks to skip" +
                                  data_file_note(header.path(), layout));
        }
        std::size_t i = 0;
        if (after_cr) {
            after_cr = false;
            if (chunk[0] == '\n') i = 1;
            if (left == 0) return offset + i;
        }
        for (; i < chunk.size() && left > 0; ++i) {
            if (chunk[i] == '\n') {
                --left;
            } else if (chunk[i] == '\r') {
                --left;
                if (i + 1 == chunk.size()) after_cr = true;
                else if (chunk[i + 1] == '\n') ++i;
            }
        }
        offset += i;
        if (left == 0 && !after_cr) return offset;
    }
}

}  // namespace

VolumeHeader read_nrrd_header(const InputFile& file) {
    const std::string& path = file.path();
    if (file.size() == 0) fail(path, "file is empty");
    const std::string text = file.read(0, kMaxNrrdHeader);
    std::size_t pos = 0;
    std::string_view line;
    next_line(text, pos, line);
    if (line.size() < 8 || line.substr(0, 7) != "NRRD000" || line[7] < '1' || line[7] > '5')
        fail(path, "not a NRRD file (the first line is not NRRD0001..NRRD0005)");

    std::map<std::string, std::string> fields, key_values;
    bool blank_line = false;
    std::size_t line_number = 1;
    while (next_line(text, pos, line)) {
        ++line_number;
        if (line.empty()) {
            blank_line = true;
            break;
        }
        if (line.front() == '#') continue;
        const std::size_t sep = line.find(": ");
        const std::size_t kv = line.find(":=");
        if (kv != std::string_view::npos && (sep == std::string_view::npos || kv < sep)) {  // key/value pair
            key_values[unescaped(line.substr(0, kv))] = unescaped(line.substr(kv + 2));
            continue;
        }
        if (sep == std::string_view::npos)
            fail(path, "header line " + std::to_string(line_number) + " is not 'field: value'");
        std::string name = lower(trim(line.substr(0, sep)));
        // teem's other spellings (_nrrdFieldStrEqv): read as the same field, or "spacedirections"
        // and the rest were ignored, leaving the volume at spacing 1 and origin 0.
        static const std::map<std::string, std::string> kAliases = {
            {"datafile", "data file"}, {"lineskip", "line skip"}, {"byteskip", "byte skip"},
            {"spacedimension", "space dimension"}, {"spacedirections", "space directions"},
            {"spaceorigin", "space origin"}, {"axismins", "axis mins"}, {"axismaxs", "axis maxs"},
            {"centerings", "centers"}, {"blocksize", "block size"}, {"oldmin", "old min"}, {"oldmax", "old max"},
            {"sampleunits", "sample units"}, {"spaceunits", "space units"}, {"measurementframe", "measurement frame"}};
        if (const auto alias = kAliases.find(name); alias != kAliases.end()) name = alias->second;
        if (!fields.emplace(name, std::string(trim(line.substr(sep + 2)))).second)
            fail(path, "header field '" + name + "' appears twice");
        if (name == "data file") {
            const auto words = split_words(fields[name]);  // "LIST" or "LIST 3": file names follow
            if (!words.empty() && words[0] == "LIST")
                fail(path, "'data file: " + fields[name] + "' (a list of data files) is not supported");
        }
    }
    if (!blank_line && text.size() < file.size())
        fail(path, "no blank line ends the header within its first " + std::to_string(kMaxNrrdHeader) + " bytes");
    const std::size_t data_start = pos;

    auto required = [&](const char* name) -> const std::string& {
        const auto it = fields.find(name);
        if (it == fields.end()) fail(path, std::string("header lacks the required field '") + name + "'");
        return it->second;
    };
    auto optional = [&](const char* name) -> const std::string* {
        const auto it = fields.find(name);
        return it == fields.end() ? nullptr : &it->second;
    };

    VolumeHeader h;
    VolumeInfo& info = h.info;
    SampleLayout& layout = h.layout;
    info.format = "nrrd";
    info.file_bytes = file.size();
    info.key_values = std::move(key_values);

    const std::size_t dimension = parse_size(path, "dimension", required("dimension"));
    const std::vector<std::size_t> sizes = parse_sizes(path, "sizes", required("sizes"));
    if (dimension != sizes.size())
        fail(path, "'dimension' is " + std::to_string(dimension) + " but 'sizes' lists " +
                       std::to_string(sizes.size()) + " values");
    std::vector<std::string> kinds;  // per axis; empty without 'kinds'
    if (const std::string* k = optional("kinds")) {
        for (std::string_view word : split_words(*k)) kinds.emplace_back(word);
        if (kinds.size() != dimension)
            fail(path, "'dimension' is " + std::to_string(dimension) + " but 'kinds' lists " +
                           std::to_string(kinds.size()) + " values");
    }
    const std::string* directions = optional("space directions");
    std::vector<std::vector<double>> vectors;  // per axis; "none" is empty
    if (directions) {
        vectors = parse_vectors(path, "space directions", *directions);
        if (vectors.size() != dimension)
            fail(path, "'dimension' is " + std::to_string(dimension) + " but 'space directions' lists " +
                           std::to_string(vectors.size()) + " entries");
    }
    // Kinds (teem's, case-insensitive) that can be a volume's axis; vectors, colours, tensors,
    // lists, time and the rest cannot.
    auto spatial_kind = [&](std::size_t a) {
        const std::string kind = kinds.empty() ? "???" : lower(kinds[a]);
        return kind == "domain" || kind == "space" || kind == "???" || kind == "none";
    };
    auto check_kind = [&](std::size_t a) {
        if (!spatial_kind(a))
            fail(path, "axis " + std::to_string(a) + " (size " + std::to_string(sizes[a]) + ") has kind '" +
                           kinds[a] + "'; only scalar volumes, whose axes are domain or space, are supported");
    };
    // x, y, z: extra axes must have size 1; those not spatial (by kind or a 'none' direction) go first.
    std::vector<bool> not_spatial(dimension);
    for (std::size_t a = 0; a < dimension; ++a) {
        not_spatial[a] = !spatial_kind(a) || (directions && vectors[a].empty());
        if (sizes[a] != 1) check_kind(a);
    }
    const std::array<std::size_t, 3> spatial = volume_axes(path, sizes, not_spatial);
    for (std::size_t k = 0; k < 3; ++k) {
        check_kind(spatial[k]);
        info.dims[k] = sizes[spatial[k]];
    }
    info.type = parse_type(path, lower(required("type")));  // teem's type names are case-insensitive

    const std::string encoding = lower(required("encoding"));
    if (encoding == "raw") {
        info.encoding = "raw";
    } else if (encoding == "gzip" || encoding == "gz") {
        info.encoding = "gzip";
    } else {
        fail(path, "NRRD encoding '" + encoding + "' is not supported (use raw or gzip)");
    }

    if (const std::string* given = optional("endian")) {
        const std::string endian = lower(*given);  // case-insensitive, as teem reads it
        if (endian == "big") info.big_endian = true;
        else if (endian != "little") fail(path, "'endian' must be little or big, not '" + *given + "'");
    } else if (scalar_size(info.type) > 1) {
        fail(path, "header lacks 'endian', required for multi-byte samples");
    }

    const std::string* spacings = optional("spacings");
    std::array<std::vector<double>, 3> axes;  // spatial axes' directions; empty without them
    // Per-axis numbers, "nan" where an axis has none (teem writes "nan" for unknown values).
    auto per_axis = [&](const char* field) {
        std::vector<double> values;
        if (const std::string* given = optional(field)) {
            for (std::string_view word : split_words(*given))
                values.push_back(lower(word) == "nan" ? NAN : parse_double(path, field, word));
            if (values.size() != dimension)
                fail(path, "'dimension' is " + std::to_string(dimension) + " but '" + field + "' lists " +
                               std::to_string(values.size()) + " values");
        }
        return values;
    };
    const std::vector<double> spacing_values = per_axis("spacings");
    // As teem checks it: an axis with a direction vector may not also have a spacing, but "nan"
    // is none ("spacings: 1 nan nan nan" beside "space directions: none (..) (..) (..)").
    if (directions && spacings)
        for (std::size_t a = 0; a < dimension; ++a)
            if (!vectors[a].empty() && !std::isnan(spacing_values[a]))
                fail(path, "axis " + std::to_string(a) +
                               " has both a spacing in 'spacings' and a vector in 'space directions' (contradictory)");
    if (spacings) {
        for (std::size_t k = 0; k < 3; ++k) {
            const double value = spacing_values[spatial[k]];
            info.spacing[k] = std::isnan(value) ? 1.0 : checked_spacing(path, "spacings", value);
            if (value < 0) reverse_direction(axes, k);  // samples run toward lower positions
        }
    }

    std::size_t space_dim = 0;
    if (const std::string* space = optional("space")) space_dim = space_dimension_of(path, *space);
    if (const std::string* sd = optional("space dimension")) {
        const std::size_t given = parse_size(path, "space dimension", *sd);
        if (space_dim != 0 && given != space_dim)
            fail(path, "'space' and 'space dimension' disagree");
        if (given == 0 || given > 16) fail(path, "'space dimension' must be between 1 and 16");
        space_dim = given;
    }
    if (directions) {
        if (space_dim == 0) fail(path, "'space directions' given without 'space' or 'space dimension'");
        for (const std::vector<double>& v : vectors)
            if (!v.empty() && v.size() != space_dim)
                fail(path, "a 'space directions' vector has " + std::to_string(v.size()) +
                               " components but the space has " + std::to_string(space_dim));
        for (std::size_t k = 0; k < 3; ++k) {
            const std::vector<double>& v = vectors[spatial[k]];
            if (v.empty()) fail(path, "'space directions' is 'none' for spatial axis " + std::to_string(spatial[k]));
            info.spacing[k] = checked_spacing(path, "space directions", vector_length(v));
            axes[k] = v;
        }
    }
    if (const std::string* origin = optional("space origin")) {
        if (space_dim == 0) fail(path, "'space origin' given without 'space' or 'space dimension'");
        const auto vectors = parse_vectors(path, "space origin", *origin);
        if (vectors.size() != 1 || vectors[0].size() != space_dim)
            fail(path, "'space origin' must be one vector of " + std::to_string(space_dim) + " components");
        for (std::size_t a = 0; a < 3 && a < space_dim; ++a)
            info.origin[a] = checked_origin(path, "space origin", vectors[0][a]);
    }
    if (space_dim == 0) place_by_axis_extents(path, h, spatial, sizes, spacing_values, per_axis("axis mins"),
                                              per_axis("axis maxs"), optional("centers"), axes);
    apply_directions(h, axis_directions(axes));

    layout.type = info.type;
    layout.dims = info.dims;
    layout.big_endian = info.big_endian;
    layout.compressed = info.encoding == "gzip";
    layout.data_path = path;
    std::size_t line_skip = 0;
    long long byte_skip = 0;
    if (const std::string* v = optional("line skip")) line_skip = parse_size(path, "line skip", *v);
    if (const std::string* v = optional("byte skip")) byte_skip = parse_integer(path, "byte skip", *v);
    if (byte_skip < -1) fail(path, "'byte skip' must be -1 or more");
    if (byte_skip == -1 && layout.compressed) fail(path, "'byte skip: -1' is only allowed with raw encoding");

    std::size_t offset = data_start;
    if (const std::string* data_file = optional("data file")) {
        if (split_words(*data_file).size() > 1 && data_file->find('%') != std::string::npos)
            fail(path, "multi-file 'data file' patterns are not supported");
        layout.data_path = detached_data_path(file, *data_file);
        offset = 0;
    } else if (!blank_line) {
        fail(path, "no blank line after the header and no 'data file': the samples are missing");
    }
    if (line_skip > 0) offset = skip_lines(file, layout, line_skip, offset);
    if (byte_skip == -1) {
        layout.at_end = true;
        layout.min_start = offset;  // the samples end the file but may not reach into the header
    } else if (layout.compressed) {
        layout.skip = static_cast<std::size_t>(byte_skip);
    } else {
        offset += static_cast<std::size_t>(byte_skip);
    }
    layout.offset = offset;
    info.data_file = layout.data_path;
    return h;
}

}  // namespace voxmesh::io
