// read_stl: binary when the size is exactly 84 + 50 * count (the "solid" prefix proves
// nothing: binary headers often start with it), otherwise ASCII. Vertices are welded by
// exact float position.
#include "core/out_of_memory.hpp"
#include "header_text.hpp"
#include "input_file.hpp"
#include "mesh_readers.hpp"
#include "samples.hpp"

#include <voxmesh/io.hpp>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <unordered_map>

namespace voxmesh {

namespace {

using io::fail;

struct KeyHash {
    std::size_t operator()(const std::array<std::uint32_t, 3>& k) const {
        std::uint64_t h = 0x9E3779B97F4A7C15ull;
        for (std::uint32_t v : k) h = (h ^ v) * 0x100000001B3ull;
        return static_cast<std::size_t>(h ^ (h >> 29));
    }
};

class Welder {
public:
    Welder(const std::string& path, Mesh& mesh) : path_(path), mesh_(mesh) {}
    void reserve(std::size_t vertices) { map_.reserve(vertices); }
    void add(const float xyz[3], std::size_t triangle) {
        std::array<float, 3> p{};
        std::array<std::uint32_t, 3> key{};
        for (std::size_t i = 0; i < 3; ++i) {
            if (!std::isfinite(xyz[i]))
                fail(path_, "triangle " + std::to_string(triangle) + " has a non-finite vertex coordinate");
            p[i] = xyz[i] + 0.0f;  // -0 and +0 are the same position
            std::memcpy(&key[i], &p[i], 4);
        }
        const auto [it, inserted] = map_.try_emplace(key, static_cast<std::uint32_t>(mesh_.vertex_count()));
        if (inserted) {
            if (mesh_.vertex_count() >= UINT32_MAX) fail(path_, "too many vertices for 32-bit indices");
            mesh_.positions.insert(mesh_.positions.end(), p.begin(), p.end());
        }
        mesh_.indices.push_back(it->second);
    }

private:
    const std::string& path_;
    Mesh& mesh_;
    std::unordered_map<std::array<std::uint32_t, 3>, std::uint32_t, KeyHash> map_;
};

void read_binary(const std::string& path, const unsigned char* data, std::size_t count, Mesh& mesh) {
    Welder welder(path, mesh);
    welder.reserve(count / 2 + 16);  // a closed mesh has about half as many vertices as triangles
    mesh.indices.reserve(3 * count);
    for (std::size_t t = 0; t < count; ++t) {
        const unsigned char* facet = data + 84 + 50 * t + 12;  // skip the stored normal
        for (int v = 0; v < 3; ++v) {
            float xyz[3];
            std::memcpy(xyz, facet + 12 * v, 12);
            if constexpr (std::endian::native == std::endian::big) io::swap_bytes(xyz, 3, 4);
            welder.add(xyz, t);
        }
    }
}

class Tokens {
public:
    explicit Tokens(std::string_view text) : text_(text) {}
    // The next whitespace-separated word, empty at the end.
    std::string_view next() {
        while (pos_ < text_.size() && is_space(text_[pos_])) {
            if (io::ends_text_line(text_, pos_)) ++line_;
            ++pos_;
        }
        const std::size_t start = pos_;
        while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
        return text_.substr(start, pos_ - start);
    }
    // Up to the line's end: "\n", "\r\n" or a lone "\r" (classic Mac OS exporters).
    void skip_line() {
        while (pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '\r') ++pos_;
    }
    std::size_t line() const { return line_; }

private:
    static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }
    std::string_view text_;
    std::size_t pos_ = 0, line_ = 1;
};

void read_ascii(const std::string& path, std::string_view text, Mesh& mesh) {
    Tokens tokens(text);
    auto where = [&] { return "ASCII STL line " + std::to_string(tokens.line()) + ": "; };
    auto expect = [&](const char* word) {
        const std::string_view got = tokens.next();
        if (io::lower(got) == word) return;
        // Built with append: gcc 12 gives a false -Wrestrict on some operator+ chains.
        std::string found = "'";
        found.append(io::shown(got)).append("'");
        fail(path, where() + "expected '" + word + "', found " + (got.empty() ? std::string("end of file") : found));
    };
    auto number = [&] { return io::parse_float_word(path, where, tokens.next()); };

    Welder welder(path, mesh);
    std::size_t triangle = 0;
    bool in_solid = false;
    while (true) {
        const std::string_view word = tokens.next();
        const std::string keyword = io::lower(word);
        if (word.empty()) {
            if (in_solid) fail(path, where() + "file ends inside a solid (no 'endsolid')");
            break;
        }
        if (!in_solid) {
            if (keyword != "solid") fail(path, where() + "expected 'solid', found '" + io::shown(word) + "'");
            tokens.skip_line();  // the solid's name
            in_solid = true;
        } else if (keyword == "endsolid") {
            tokens.skip_line();
            in_solid = false;
        } else if (keyword == "facet") {
            expect("normal");
            for (int i = 0; i < 3; ++i) number();
            expect("outer");
            expect("loop");
            for (int v = 0; v < 3; ++v) {
                expect("vertex");
                const float xyz[3] = {number(), number(), number()};
                welder.add(xyz, triangle);
            }
            expect("endloop");
            expect("endfacet");
            ++triangle;
        } else {
            fail(path, where() + "expected 'facet' or 'endsolid', found '" + io::shown(word) + "'");
        }
    }
}

bool starts_with_solid(std::string_view text) {
    std::size_t i = io::bom_size(text);
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r' || text[i] == '\n')) ++i;
    return io::lower(text.substr(i, 5)) == "solid";
}

}  // namespace

Mesh io::read_stl_from(const InputFile& input) {
    const std::string& path = input.path();
    const io::MappedFile file = io::map_whole_file(input);
    const std::size_t size = file.text.size();
    const unsigned char* data = file.bytes();

    Mesh mesh;
    std::string binary_problem;
    if (size >= 84) {
        std::uint32_t count = 0;
        std::memcpy(&count, data + 80, 4);
        if constexpr (std::endian::native == std::endian::big) io::swap_bytes(&count, 1, 4);
        const std::uint64_t expected = 84 + 50 * std::uint64_t{count};
        if (expected == size) {
            // Count 0 in 84 bytes: an empty mesh, as write_mesh writes one (and PLY reads one).
            read_binary(path, data, count, mesh);
            return mesh;
        }
        binary_problem = "as binary STL its header says " + std::to_string(count) + " triangles, which need " +
                         std::to_string(expected) + " bytes, but the file has " + std::to_string(size);
    } else {
        binary_problem = "at " + std::to_string(size) + " bytes it is too short for binary STL (84-byte header)";
    }
    const std::string_view text = file.text;
    if (!starts_with_solid(text)) fail(path, "not an STL file: " + binary_problem + ", and it does not start with 'solid'");
    try {
        read_ascii(path, text.substr(io::bom_size(text)), mesh);  // a UTF-8 byte order mark is skipped
    } catch (const Error& e) {
        detail::rethrow_with_message(e, std::string(e.what()) + " (" + binary_problem + ")");
    }
    return mesh;  // "solid x / endsolid x" included: an empty mesh, as in binary STL
}

}  // namespace voxmesh
