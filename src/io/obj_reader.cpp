// read_obj: one pass over the mapped file, one statement per logical line. Only "v", "vn",
// "vt" (counted, for range checks) and "f" are read; every other statement is skipped.
//
// Decisions beyond the OBJ text itself:
//  * A face index must name an item already read (1..count so far, or -count..-1): OBJ has
//    no forward references in practice, and this lets each face be checked as it is read.
//  * '#' starts a comment that runs to the end of its physical line and is never continued:
//    a '\' ending a line (before any comment; trailing blanks allowed) joins it to the next,
//    standing for a blank. The line number in an error is where the statement starts.
//  * "v" takes its three coordinates and at most four more numbers (w, or colours r g b
//    [a]), which must be numbers and are ignored. "vn" takes exactly three numbers; a
//    non-finite one is not an error, but the normals are then dropped.
//  * Keywords are case-sensitive, as the format defines them (lower case).
//  * Lines end with "\n", "\r\n" or a lone "\r"; a UTF-8 byte order mark before the first
//    line is skipped.
#include "header_text.hpp"
#include "input_file.hpp"
#include "mesh_readers.hpp"

#include <voxmesh/io.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace voxmesh {

namespace {

using io::fail;

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// The words of one statement, split on blanks, as views into it.
class Words {
public:
    explicit Words(std::string_view text) : text_(text) {}
    std::string_view next() {  // empty at the end
        while (pos_ < text_.size() && is_blank(text_[pos_])) ++pos_;
        const std::size_t start = pos_;
        while (pos_ < text_.size() && !is_blank(text_[pos_])) ++pos_;
        return text_.substr(start, pos_ - start);
    }

private:
    std::string_view text_;
    std::size_t pos_ = 0;
};

// The physical line without its comment.
std::string_view strip_comment(std::string_view line) {
    const std::size_t hash = line.find('#');
    return hash == std::string_view::npos ? line : line.substr(0, hash);
}

// True when `part` ends with the continuation '\' (blanks after it allowed); it is then
// removed from `part`.
bool continues(std::string_view& part) {
    std::size_t end = part.size();
    while (end > 0 && is_blank(part[end - 1])) --end;
    if (end == 0 || part[end - 1] != '\\') return false;
    part = part.substr(0, end - 1);
    return true;
}

class ObjParser {
public:
    explicit ObjParser(const std::string& path) : path_(path) {}

    void statement(std::string_view text, std::size_t line) {
        line_ = line;
        Words words(text);
        const std::string_view keyword = words.next();
        if (keyword == "v") vertex(words);
        else if (keyword == "f") face(words);
        else if (keyword == "vn") normal(words);
        else if (keyword == "vt") ++texcoords_;
        // Anything else (o, g, s, usemtl, mtllib, l, p, vp, unknown) says nothing we keep.
        else if (unknown_.empty() && !keyword.empty() && !is_obj_keyword(keyword))
            unknown_.append("'").append(io::shown(keyword)).append("' (line ").append(std::to_string(line)).append(")");
    }

    Mesh finish() {
        // No faces is an empty mesh (write_mesh writes one so) where every statement was OBJ;
        // a file of other text is not taken for an empty model.
        if (mesh_.indices.empty() && !unknown_.empty())
            fail(path_, "no faces ('f' statements), and " + unknown_ + " is not an OBJ statement");
        if (normals_paired_ && normals_finite_ && normals_.size() == mesh_.positions.size())
            mesh_.normals = std::move(normals_);
        return std::move(mesh_);
    }

private:
    // The OBJ statements (the spec's, free-form geometry's and the general "call" and "csh"
    // included) other than v, vn, vt, f.
    static bool is_obj_keyword(std::string_view k) {
        static constexpr std::string_view kKnown[] = {
            "o", "g", "s", "usemtl", "mtllib", "l", "p", "vp", "mg", "cstype", "deg", "bmat", "step", "curv",
            "curv2", "surf", "parm", "trim", "hole", "scrv", "sp", "end", "con", "bevel", "c_interp", "d_interp",
            "lod", "maplib", "usemap", "shadow_obj", "trace_obj", "ctech", "stech", "call", "csh"};
        return std::find(std::begin(kKnown), std::end(kKnown), k) != std::end(kKnown);
    }
    std::string unknown_;  // the first statement that is not OBJ's, as shown in errors

    std::string where() const { return "line " + std::to_string(line_) + ": "; }
    [[noreturn]] void error(const std::string& what) const { fail(path_, where() + what); }

    float number(std::string_view word) const {
        return io::parse_float_word(path_, [this] { return where(); }, word);
    }

    void vertex(Words& words) {
        if (mesh_.vertex_count() >= UINT32_MAX) error("more than 4294967295 vertices (indices are 32-bit)");
        float xyz[3];
        for (std::size_t i = 0; i < 3; ++i) {
            const std::string_view word = words.next();
            if (word.empty()) error("'v' needs three coordinates, found " + std::to_string(i));
            xyz[i] = number(word);
            if (!std::isfinite(xyz[i])) error("non-finite vertex coordinate '" + io::shown(word) + "'");
        }
        std::size_t extra = 0;  // w, or colours: checked, then ignored
        for (std::string_view word = words.next(); !word.empty(); word = words.next(), ++extra) {
            if (extra == 4) error("'v' has more than seven numbers (x y z, then w or r g b [a])");
            number(word);
        }
        io::reserve_checked(path_, mesh_.positions, mesh_.positions.size() + 3);
        mesh_.positions.insert(mesh_.positions.end(), xyz, xyz + 3);
    }

    void normal(Words& words) {
        for (std::size_t i = 0; i < 3; ++i) {
            const std::string_view word = words.next();
            if (word.empty()) error("'vn' needs three numbers, found " + std::to_string(i));
            const float value = number(word);
            normals_finite_ = normals_finite_ && std::isfinite(value);
            io::reserve_checked(path_, normals_, normals_.size() + 1);
            normals_.push_back(value);
        }
        if (!words.next().empty()) error("'vn' has more than three numbers");
    }

    // One index of a corner (the whole of `digits`) among `count` items read so far, 0-based.
    std::uint64_t index(std::string_view digits, std::string_view corner, std::uint64_t count, const char* what) {
        std::int64_t value = 0;
        const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        if (ec == std::errc() && end == digits.data() + digits.size()) {
            if (value == 0) error("index 0 in face corner '" + io::shown(corner) + "' (OBJ indices start at 1)");
            if (value > 0 && static_cast<std::uint64_t>(value) <= count) return static_cast<std::uint64_t>(value) - 1;
            if (value < 0 && static_cast<std::uint64_t>(-(value + 1)) < count)  // -1 is the latest
                return count - 1 - static_cast<std::uint64_t>(-(value + 1));
        } else if (ec != std::errc::result_out_of_range || end != digits.data() + digits.size()) {
            malformed(corner);
        }
        error(std::string(what) + " index in face corner '" + io::shown(corner) + "' is out of range: " +
              std::to_string(count) + " read so far");
    }

    [[noreturn]] void malformed(std::string_view corner) {
        error("face corner '" + io::shown(corner) + "' is malformed (expected v, v/vt, v/vt/vn or v//vn)");
    }

    // A corner "v", "v/vt", "v/vt/vn" or "v//vn": its vertex index, 0-based.
    std::uint32_t corner(std::string_view word) {
        const std::size_t slash1 = word.find('/');
        const std::string_view v = word.substr(0, slash1);
        if (v.empty()) malformed(word);
        const std::uint64_t vertex = index(v, word, mesh_.vertex_count(), "vertex");
        if (slash1 == std::string_view::npos) {
            normals_paired_ = false;
            return static_cast<std::uint32_t>(vertex);
        }
        const std::size_t slash2 = word.find('/', slash1 + 1);
        const std::string_view vt = word.substr(slash1 + 1, slash2 - (slash1 + 1));
        if (slash2 == std::string_view::npos) {  // v/vt
            if (vt.empty()) malformed(word);
            index(vt, word, texcoords_, "texture");
            normals_paired_ = false;
            return static_cast<std::uint32_t>(vertex);
        }
        const std::string_view vn = word.substr(slash2 + 1);
        if (vn.empty() || vn.find('/') != std::string_view::npos) malformed(word);
        if (!vt.empty()) index(vt, word, texcoords_, "texture");
        const std::uint64_t normal = index(vn, word, normals_.size() / 3, "normal");
        normals_paired_ = normals_paired_ && normal == vertex;
        return static_cast<std::uint32_t>(vertex);
    }

    // Fanned from the first corner: a b c d -> a b c, a c d.
    void face(Words& words) {
        std::size_t corners = 0;
        std::uint32_t first = 0, previous = 0;
        for (std::string_view word = words.next(); !word.empty(); word = words.next(), ++corners) {
            const std::uint32_t v = corner(word);
            if (corners == 0) first = v;
            if (corners >= 2) {  // growing with the file's content: checked against the memory available
                io::reserve_checked(path_, mesh_.indices, mesh_.indices.size() + 3);
                mesh_.indices.insert(mesh_.indices.end(), {first, previous, v});
            }
            previous = v;
        }
        if (corners < 3) error("face has " + std::to_string(corners) + " corners; at least three are needed");
    }

    const std::string& path_;
    Mesh mesh_;
    std::vector<float> normals_;  // every "vn", three floats each
    std::uint64_t texcoords_ = 0;
    bool normals_paired_ = true;  // every corner so far named its own vertex's normal
    bool normals_finite_ = true;
    std::size_t line_ = 0;
};

}  // namespace

Mesh io::read_obj_from(const InputFile& input) {
    const std::string& path = input.path();
    const io::MappedFile file = io::map_whole_file(input);
    // A byte order mark left in place would hide the first statement's keyword: a first "v"
    // skipped shifts every index after it.
    const std::string_view text = file.text.substr(io::bom_size(file.text));

    ObjParser parser(path);
    std::string joined;  // a statement continued over several lines (rare), reused
    std::size_t pos = 0, line = 0;
    std::string_view raw;
    while (io::next_text_line(text, pos, raw)) {
        const std::size_t first_line = ++line;
        std::string_view part = strip_comment(raw);
        if (!continues(part)) {
            parser.statement(part, first_line);
            continue;
        }
        joined.assign(part).append(" ");
        while (io::next_text_line(text, pos, raw)) {
            ++line;
            part = strip_comment(raw);
            const bool more = continues(part);
            joined.append(part).append(" ");
            if (!more) break;
        }
        parser.statement(joined, first_line);
    }
    return parser.finish();
}

}  // namespace voxmesh
