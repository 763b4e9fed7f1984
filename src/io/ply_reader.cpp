// read_ply: the header becomes a list of elements and their properties; their counts are
// checked against the bytes after the header; then one pass reads the body, ASCII or binary,
// through the same record loop (templated on the body, so no per-value virtual call).
//
// Decisions beyond the PLY text itself:
//  * Keywords, type names and property names are case-sensitive, as the format defines them;
//    blank header lines are skipped; the version must be "1.0" (or "1").
//  * Header lines end with "\n", "\r\n", or a lone "\r" when the first line does; a UTF-8
//    byte order mark before "ply" is skipped.
//  * ASCII data is a stream of whitespace-separated words: line breaks are not significant
//    (records split or joined across lines read the same). After the last element only
//    whitespace may follow; binary data must end exactly at the file's end.
//  * Integer-typed values in ASCII must be whole integers in their type's range; float-typed
//    ones that are skipped must be numbers (any magnitude).
//  * A PLY with vertices and no faces (a point cloud) reads as vertices with no indices, and
//    one with no vertices at all as an empty mesh; only a missing "vertex" element is an error.
//  * "vertex_indices" is used when the face element has both it and "vertex_index".
//  * Normals are kept when nx, ny and nz are all scalar properties of the vertex element, and
//    dropped, not an error, when one is NaN or infinite (scanners write NaN where they have
//    none), as read_obj does; a coordinate so is an error.
#include "header_text.hpp"
#include "input_file.hpp"
#include "mesh_readers.hpp"

#include <voxmesh/io.hpp>

#include <algorithm>
#include <bit>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace voxmesh {

namespace {

using io::fail;

// The most bytes read looking for "end_header".
constexpr std::size_t kMaxHeader = std::size_t{1} << 20;

using Type = ScalarType;  // PLY's eight scalar types are the volumes' eight

struct TypeName {
    const char* name;
    Type type;
};
constexpr TypeName kTypeNames[] = {{"char", Type::I8},    {"int8", Type::I8},     {"uchar", Type::U8},
                                   {"uint8", Type::U8},   {"short", Type::I16},   {"int16", Type::I16},
                                   {"ushort", Type::U16}, {"uint16", Type::U16},  {"int", Type::I32},
                                   {"int32", Type::I32},  {"uint", Type::U32},    {"uint32", Type::U32},
                                   {"float", Type::F32},  {"float32", Type::F32}, {"double", Type::F64},
                                   {"float64", Type::F64}};

bool is_integer(Type t) { return t != Type::F32 && t != Type::F64; }

const char* name_of(Type t) {
    for (const TypeName& n : kTypeNames)
        if (n.type == t) return n.name;
    return "?";
}

// The range of an integer type, for values read as text.
void integer_range(Type t, long long& lo, long long& hi) {
    const int bits = static_cast<int>(8 * scalar_size(t));
    const bool is_signed = t == Type::I8 || t == Type::I16 || t == Type::I32;
    lo = is_signed ? -(1LL << (bits - 1)) : 0;
    hi = is_signed ? (1LL << (bits - 1)) - 1 : (1LL << bits) - 1;
}

// Kept scalar properties land in slot 0..2 (x, y, z) or 3..5 (nx, ny, nz) of a vertex.
constexpr int kSkip = -1;

struct Property {
    std::string name;
    Type type = Type::U8;  // a list's item type
    bool list = false;
    Type count_type = Type::U8;
    std::size_t size = 1, count_size = 1;  // bytes of `type` and `count_type`, looked up once
    int slot = kSkip;
    bool corners = false;  // the face element's index list
};

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::vector<Property> properties;
};

struct Header {
    enum class Format { Ascii, LittleEndian, BigEndian } format = Format::Ascii;
    std::vector<Element> elements;
    std::size_t body = 0;  // offset of the first byte after the "end_header" line
    std::size_t vertex = SIZE_MAX, face = SIZE_MAX;  // indices into `elements` (SIZE_MAX: none)
    bool normals = false;
};

Property* find_property(Element& e, std::string_view name) {
    for (Property& p : e.properties)
        if (p.name == name) return &p;
    return nullptr;
}

Type parse_type(const std::string& path, const std::string& at, std::string_view word) {
    for (const TypeName& n : kTypeNames)
        if (word == n.name) return n.type;
    fail(path, at + "unknown type '" + io::shown(word) + "'");
}

void parse_property(const std::string& path, const std::string& at, const std::vector<std::string_view>& words,
                    Element& element) {
    Property p;
    if (words.size() == 5 && words[1] == "list") {
        p.list = true;
        p.count_type = parse_type(path, at, words[2]);
        if (!is_integer(p.count_type))
            fail(path, at + "a list's count type must be an integer type, not '" + io::shown(words[2]) + "'");
        p.type = parse_type(path, at, words[3]);
    } else if (words.size() == 3 && words[1] != "list") {
        p.type = parse_type(path, at, words[1]);
    } else {
        fail(path, at + "malformed property line (expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME')");
    }
    p.name = std::string(words.back());
    p.size = scalar_size(p.type);
    p.count_size = scalar_size(p.count_type);
    element.properties.push_back(std::move(p));
}

// Sorted, not searched per line: a 1 MiB header can declare 65536 properties.
void check_unique_names(const std::string& path, const Element& element) {
    std::vector<std::string_view> names;
    for (const Property& p : element.properties) names.push_back(p.name);
    std::sort(names.begin(), names.end());
    const auto twice = std::adjacent_find(names.begin(), names.end());
    if (twice != names.end())
        fail(path, "property '" + io::shown(*twice) + "' appears twice in element '" + io::shown(element.name) + "'");
}

// Marks the vertex element's coordinates and normals and the face element's index list.
void assign_roles(const std::string& path, Header& h) {
    for (std::size_t i = 0; i < h.elements.size(); ++i) {
        check_unique_names(path, h.elements[i]);
        const std::string& name = h.elements[i].name;
        std::size_t* slot = name == "vertex" ? &h.vertex : name == "face" ? &h.face : nullptr;
        if (!slot) continue;
        if (*slot != SIZE_MAX) fail(path, "element '" + name + "' is declared twice");
        *slot = i;
    }
    if (h.vertex == SIZE_MAX) fail(path, "no 'vertex' element in the header");
    Element& vertex = h.elements[h.vertex];
    if (vertex.count > UINT32_MAX)
        fail(path, std::to_string(vertex.count) + " vertices are too many for 32-bit indices");
    const char* axes[] = {"x", "y", "z", "nx", "ny", "nz"};
    Property* found[6] = {};
    for (int k = 0; k < 6; ++k) {
        found[k] = find_property(vertex, axes[k]);
        if (k < 3 && (!found[k] || found[k]->list))
            fail(path, std::string("the vertex element has no scalar property '") + axes[k] + "'");
    }
    h.normals = found[3] && found[4] && found[5] && !found[3]->list && !found[4]->list && !found[5]->list;
    for (int k = 0; k < (h.normals ? 6 : 3); ++k) found[k]->slot = k;

    if (h.face == SIZE_MAX) return;
    Element& face = h.elements[h.face];
    Property* corners = find_property(face, "vertex_indices");
    if (!corners) corners = find_property(face, "vertex_index");
    if (!corners) {
        if (face.count == 0) return;
        fail(path, "the face element has no 'vertex_indices' list");
    }
    if (!corners->list || !is_integer(corners->type))
        fail(path, "the face element's '" + corners->name + "' must be a list of an integer type");
    corners->corners = true;
}

Header parse_header(const std::string& path, std::string_view file) {
    const std::string_view text = file.substr(0, kMaxHeader);
    std::size_t pos = io::bom_size(text), line_number = 1;
    // The first line's end says how every header line ends: a lone '\r' (classic Mac OS) or
    // '\n' (or "\r\n"). Decided once, so that "end_header\r" before a binary body whose first
    // byte is '\n' is not taken for a "\r\n".
    std::size_t first_end = pos;
    while (first_end < text.size() && text[first_end] != '\n' && text[first_end] != '\r') ++first_end;
    const bool lone_cr = first_end < text.size() && text[first_end] == '\r' && io::ends_text_line(text, first_end);
    const char line_end = lone_cr ? '\r' : '\n';
    std::string_view line;
    auto next = [&] {
        if (!lone_cr) return io::next_line(text, pos, line);
        if (pos >= text.size()) return false;
        const std::size_t end = std::min(text.find('\r', pos), text.size());
        line = text.substr(pos, end - pos);
        pos = std::min(end + 1, text.size());
        return true;
    };
    if (!next() || io::trim(line) != "ply")
        fail(path, "not a PLY file (the first line is not 'ply')");
    Header h;
    bool have_format = false;
    while (true) {
        if (!next()) {
            if (file.size() > kMaxHeader) fail(path, "header too long: no 'end_header' in its first 1 MiB");
            fail(path, "no 'end_header' line: the header is incomplete");
        }
        ++line_number;
        if (pos == text.size() && text.back() != line_end && text.size() < file.size())
            fail(path, "header too long: no 'end_header' in its first 1 MiB");  // a line cut by the cap
        const std::string at = "line " + std::to_string(line_number) + ": ";
        const std::vector<std::string_view> words = io::split_words(line);
        if (words.empty()) continue;
        const std::string_view keyword = words[0];
        if (keyword == "comment" || keyword == "obj_info") continue;
        if (keyword == "end_header") {
            if (words.size() != 1) fail(path, at + "malformed 'end_header' line");
            break;
        }
        if (keyword == "format") {
            if (have_format) fail(path, at + "a second 'format' line");
            if (words.size() != 3) fail(path, at + "malformed format line (expected 'format FORMAT 1.0')");
            if (words[1] == "ascii") h.format = Header::Format::Ascii;
            else if (words[1] == "binary_little_endian") h.format = Header::Format::LittleEndian;
            else if (words[1] == "binary_big_endian") h.format = Header::Format::BigEndian;
            else fail(path, at + "unknown format '" + io::shown(words[1]) + "'");
            if (words[2] != "1.0" && words[2] != "1")
                fail(path, at + "unknown PLY version '" + io::shown(words[2]) + "' (only 1.0 is read)");
            have_format = true;
        } else if (keyword == "element") {
            if (words.size() != 3) fail(path, at + "malformed element line (expected 'element NAME COUNT')");
            Element e;
            e.name = std::string(words[1]);
            e.count = io::parse_size(path, at + "element " + io::shown(e.name), words[2]);
            h.elements.push_back(std::move(e));
        } else if (keyword == "property") {
            if (h.elements.empty()) fail(path, at + "a property before any element");
            parse_property(path, at, words, h.elements.back());
        } else {
            fail(path, at + "unknown header line '" + io::shown(line) + "'");
        }
    }
    if (!have_format) fail(path, "no 'format' line in the header");
    h.body = pos;
    assign_roles(path, h);
    return h;
}

// Nothing is allocated until the header's counts fit the body: each binary record takes at
// least its scalars' and list counts' bytes; each ASCII value at least one character, with a
// blank between two, so n values need 2n - 1 bytes. Returns an upper bound on the faces a
// file of this size can really hold (for reserving indices).
std::uint64_t check_counts(const std::string& path, const Header& h, std::size_t body_bytes) {
    const bool ascii = h.format == Header::Format::Ascii;
    std::uint64_t left = ascii ? (std::uint64_t{body_bytes} + 1) / 2 : body_bytes;  // values or bytes
    std::uint64_t face_minimum = 1;
    for (std::size_t i = 0; i < h.elements.size(); ++i) {
        const Element& e = h.elements[i];
        std::uint64_t record = 0;
        for (const Property& p : e.properties) record += ascii ? 1 : p.list ? p.count_size : p.size;
        if (record == 0) continue;
        if (e.count > left / record)
            fail(path, "file too short: element '" + io::shown(e.name) + "' declares " + std::to_string(e.count) +
                           " records of at least " + std::to_string(record) + (ascii ? " values" : " bytes") +
                           " each, but the " + std::to_string(body_bytes) + " bytes after the header cannot hold them");
        left -= e.count * record;
        if (i != h.face) continue;
        for (const Property& p : e.properties)  // a usable face has at least three corners
            if (p.corners) record += 3 * (ascii ? 1 : p.size);
        face_minimum = ascii ? 2 * record - 1 : record;
    }
    return h.face == SIZE_MAX ? 0 : std::min<std::uint64_t>(h.elements[h.face].count, body_bytes / face_minimum);
}

// ------------------------------------------------------------------ binary body

std::uint16_t byte_swapped(std::uint16_t v) { return static_cast<std::uint16_t>((v >> 8) | (v << 8)); }
std::uint32_t byte_swapped(std::uint32_t v) {
    return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}
std::uint64_t byte_swapped(std::uint64_t v) {
    return (std::uint64_t{byte_swapped(static_cast<std::uint32_t>(v))} << 32) |
           byte_swapped(static_cast<std::uint32_t>(v >> 32));
}

// A value of type T stored as the bits U, in the file's byte order.
template <class T, class Bits>
T load(const unsigned char* p, bool swap) {
    Bits bits;
    std::memcpy(&bits, p, sizeof bits);
    if constexpr (sizeof(Bits) > 1)
        if (swap) bits = byte_swapped(bits);
    T value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
}

// Where a record error happened: "vertex 12: ".
std::string record_text(const Element* e, std::uint64_t index) {
    return e ? io::shown(e->name) + " " + std::to_string(index) + ": " : std::string();
}

class BinaryBody {
public:
    BinaryBody(const std::string& path, const unsigned char* data, std::size_t size, std::size_t at, bool big_endian)
        : path_(path), begin_(data), p_(data + at), end_(data + size),
          swap_(big_endian != (std::endian::native == std::endian::big)) {}

    void record(const Element& e, std::uint64_t index) {
        element_ = &e;
        index_ = index;
    }
    // Skips a whole element of fixed-size records that keeps nothing, in one step.
    bool skip_element(const Element& e) {
        std::size_t bytes = 0;
        for (const Property& p : e.properties) {
            if (p.list || p.slot != kSkip) return false;
            bytes += p.size;
        }
        if (e.count > remaining() / bytes) {
            record(e, remaining() / bytes);
            truncated();
        }
        p_ += e.count * bytes;
        return true;
    }
    double number(const Property& p) { return next(p.type, p.size); }
    void skip(const Property& p) {
        need(p.size);
        p_ += p.size;
    }
    // A list's count, and one of its items (both of integer types: exact in a double).
    long long count(const Property& p) { return static_cast<long long>(next(p.count_type, p.count_size)); }
    long long item(const Property& p) { return static_cast<long long>(next(p.type, p.size)); }
    // Checks that `n` items fit before reading them one by one.
    void expect_items(const Property& p, std::uint64_t n) {
        if (n > remaining() / p.size) truncated();
    }
    void skip_items(const Property& p, std::uint64_t n) {
        expect_items(p, n);
        p_ += n * p.size;
    }
    [[noreturn]] void error(const std::string& what) const {
        fail(path_, record_text(element_, index_) + what + " (byte " + std::to_string(p_ - begin_) + ")");
    }
    const std::string& path() const { return path_; }
    void finish() const {
        if (p_ != end_)
            fail(path_, std::to_string(end_ - p_) + " bytes of unexpected data after the last element");
    }

private:
    std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }
    void need(std::size_t bytes) {
        if (bytes > remaining()) truncated();
    }
    [[noreturn]] void truncated() const {
        fail(path_, "file ends inside " + io::shown(element_->name) + " " + std::to_string(index_) + " of " +
                        std::to_string(element_->count) + " (truncated)");
    }
    // Every PLY scalar fits a double exactly.
    double next(Type t, std::size_t size) {
        need(size);
        const unsigned char* at = p_;
        p_ += size;
        return value(t, at);
    }
    double value(Type t, const unsigned char* at) const {
        switch (t) {
            case Type::I8: return load<std::int8_t, std::uint8_t>(at, swap_);
            case Type::U8: return load<std::uint8_t, std::uint8_t>(at, swap_);
            case Type::I16: return load<std::int16_t, std::uint16_t>(at, swap_);
            case Type::U16: return load<std::uint16_t, std::uint16_t>(at, swap_);
            case Type::I32: return load<std::int32_t, std::uint32_t>(at, swap_);
            case Type::U32: return load<std::uint32_t, std::uint32_t>(at, swap_);
            case Type::F32: return load<float, std::uint32_t>(at, swap_);
            case Type::F64: return load<double, std::uint64_t>(at, swap_);
        }
        return 0;
    }

    const std::string& path_;
    const unsigned char* begin_;
    const unsigned char* p_;
    const unsigned char* end_;
    bool swap_;
    const Element* element_ = nullptr;
    std::uint64_t index_ = 0;
};

// ------------------------------------------------------------------ ASCII body

class AsciiBody {
public:
    AsciiBody(const std::string& path, std::string_view text, std::size_t at) : path_(path), text_(text), pos_(at) {}

    void record(const Element& e, std::uint64_t index) {
        element_ = &e;
        index_ = index;
    }
    bool skip_element(const Element&) { return false; }  // words must be read to be skipped
    double number(const Property& p) {
        const std::string_view w = word();
        if (!is_integer(p.type))
            return io::parse_float_word(path_, [&] { return where() + "property '" + io::shown(p.name) + "': "; }, w);
        return static_cast<double>(whole(w, p.type));
    }
    void skip(const Property& p) { skip_value(p.type); }
    long long count(const Property& p) { return whole(word(), p.count_type); }
    long long item(const Property& p) { return whole(word(), p.type); }
    // Each item is a word and a blank after it (but the file's last): a count the rest of the
    // text cannot hold is refused before anything is sized from it.
    void expect_items(const Property&, std::uint64_t n) {
        if (n > (text_.size() - pos_ + 1) / 2) ends_inside();
    }
    void skip_items(const Property& p, std::uint64_t n) {
        for (std::uint64_t i = 0; i < n; ++i) skip_value(p.type);
    }
    [[noreturn]] void error(const std::string& what) const { fail(path_, where() + what); }
    const std::string& path() const { return path_; }
    void finish() {
        skip_blanks();
        word_ = pos_;
        if (pos_ < text_.size()) {
            std::size_t end = pos_;
            while (end < text_.size() && !is_blank(text_[end])) ++end;
            fail(path_, "line " + std::to_string(line()) + ": unexpected '" + io::shown(text_.substr(pos_, end - pos_)) +
                            "' after the last element");
        }
    }

private:
    static bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }
    void skip_blanks() {
        while (pos_ < text_.size() && is_blank(text_[pos_])) ++pos_;
    }
    std::string_view word() {
        skip_blanks();
        word_ = pos_;
        if (pos_ == text_.size()) ends_inside();
        while (pos_ < text_.size() && !is_blank(text_[pos_])) ++pos_;
        return text_.substr(word_, pos_ - word_);
    }
    [[noreturn]] void ends_inside() const {
        fail(path_, "line " + std::to_string(line()) + ": file ends inside " + io::shown(element_->name) + " " +
                        std::to_string(index_) + " of " + std::to_string(element_->count) + " (too few values)");
    }
    // The line of the latest word, counted only when an error needs it.
    std::size_t line() const {
        std::size_t n = 1;
        for (std::size_t i = 0; i < word_; ++i) n += io::ends_text_line(text_, i);
        return n;
    }
    // A value nothing keeps must still be one of its type: an integer in range, or a number
    // (of any magnitude).
    void skip_value(Type t) {
        const std::string_view w = word();
        if (is_integer(t)) {
            whole(w, t);
            return;
        }
        const std::string_view digits = !w.empty() && w.front() == '+' ? w.substr(1) : w;
        double value = 0;
        const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        if (end != digits.data() + digits.size() || digits.empty() || (ec != std::errc() && ec != std::errc::result_out_of_range))
            bad_word(w, "is not a number");
    }
    // Built with append: gcc 12 gives a false -Wrestrict on some operator+ chains.
    [[noreturn]] void bad_word(std::string_view w, const char* problem, const char* type = "") const {
        std::string what = "'";
        what.append(io::shown(w)).append("' ").append(problem).append(type);
        error(what);
    }
    std::string where() const { return "line " + std::to_string(line()) + ": " + record_text(element_, index_); }
    long long whole(std::string_view w, Type t) const {
        long long value = 0, lo = 0, hi = 0;
        const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), value);
        integer_range(t, lo, hi);
        if (end != w.data() + w.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
            bad_word(w, "is not an integer");
        if (ec != std::errc() || value < lo || value > hi) bad_word(w, "is out of range for ", name_of(t));
        return value;
    }

    const std::string& path_;
    std::string_view text_;
    std::size_t pos_ = 0, word_ = 0;
    const Element* element_ = nullptr;
    std::uint64_t index_ = 0;
};

// ------------------------------------------------------------------ records

// A coordinate or normal as a float: finite, and within the float range.
float to_float(double value, const Property& p, auto& body) {
    if (!std::isfinite(value)) body.error("property '" + io::shown(p.name) + "' is not finite");
    if (std::fabs(value) > FLT_MAX)
        body.error("property '" + io::shown(p.name) + "' is beyond the range of float (about 3.4e38)");
    return static_cast<float>(value);
}

// One polygon of `n` corners, fanned from its first: (a,b,c,d) -> abc, acd.
template <class Body>
void read_polygon(Body& body, const Property& p, long long n, std::uint64_t vertices, std::vector<std::uint32_t>& out) {
    if (n < 3) body.error("a face has " + std::to_string(n) + " corners (at least 3 are needed)");
    body.expect_items(p, static_cast<std::uint64_t>(n));
    // Reserved for triangles from the face count; a polygon of many corners makes more.
    io::reserve_checked(body.path(), out, out.size() + 3 * static_cast<std::size_t>(n - 2));
    auto corner = [&]() -> std::uint32_t {
        const long long i = body.item(p);
        if (i < 0) body.error("negative vertex index " + std::to_string(i));
        if (static_cast<std::uint64_t>(i) >= vertices)
            body.error("vertex index " + std::to_string(i) + " is outside the " + std::to_string(vertices) + " vertices");
        return static_cast<std::uint32_t>(i);
    };
    const std::uint32_t first = corner();
    std::uint32_t previous = corner();
    for (long long k = 2; k < n; ++k) {
        const std::uint32_t current = corner();
        out.push_back(first);  // not insert({...}): that is a memmove call per triangle
        out.push_back(previous);
        out.push_back(current);
        previous = current;
    }
}

template <class Body>
void read_elements(Body& body, const Header& h, Mesh& mesh) {
    const std::uint64_t vertices = h.elements[h.vertex].count;
    bool finite_normals = true;
    for (const Element& e : h.elements) {
        if (e.properties.empty() || e.count == 0 || body.skip_element(e)) continue;
        const bool is_vertex = &e == &h.elements[h.vertex];
        for (std::uint64_t i = 0; i < e.count; ++i) {
            body.record(e, i);
            float kept[6] = {};
            for (const Property& p : e.properties) {
                if (p.list) {
                    const long long n = body.count(p);
                    if (n < 0) body.error("negative list count " + std::to_string(n) + " for '" + io::shown(p.name) + "'");
                    if (p.corners) read_polygon(body, p, n, vertices, mesh.indices);
                    else body.skip_items(p, static_cast<std::uint64_t>(n));
                } else if (p.slot != kSkip) {
                    const double value = body.number(p);
                    if (p.slot >= 3 && !std::isfinite(value)) finite_normals = false;
                    else kept[p.slot] = to_float(value, p, body);
                } else {
                    body.skip(p);
                }
            }
            if (!is_vertex) continue;
            std::memcpy(&mesh.positions[3 * i], kept, 3 * sizeof(float));
            if (h.normals) std::memcpy(&mesh.normals[3 * i], kept + 3, 3 * sizeof(float));
        }
    }
    body.finish();
    if (!finite_normals) mesh.normals = {};
}

}  // namespace

Mesh io::read_ply_from(const InputFile& input) {
    const std::string& path = input.path();
    const io::MappedFile file = io::map_whole_file(input);
    const std::size_t size = file.text.size();
    const unsigned char* data = file.bytes();
    const std::string_view text = file.text;

    const Header h = parse_header(path, text);
    const std::uint64_t faces = check_counts(path, h, size - h.body);
    const std::size_t vertices = static_cast<std::size_t>(h.elements[h.vertex].count);
    const std::size_t floats = 3 * vertices * (h.normals ? 2 : 1);
    io::check_memory(path, floats * sizeof(float) + static_cast<std::size_t>(faces) * 3 * sizeof(std::uint32_t));

    Mesh mesh;
    mesh.positions.resize(3 * vertices);
    if (h.normals) mesh.normals.resize(3 * vertices);
    mesh.indices.reserve(3 * static_cast<std::size_t>(faces));
    if (h.format == Header::Format::Ascii) {
        AsciiBody body(path, text, h.body);
        read_elements(body, h, mesh);
    } else {
        BinaryBody body(path, data, size, h.body, h.format == Header::Format::BigEndian);
        read_elements(body, h, mesh);
    }
    return mesh;
}

}  // namespace voxmesh
