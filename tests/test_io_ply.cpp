// read_ply: round trips with write_mesh, hand-written ASCII, the same content in all three
// encodings, and every error the reader promises (each naming the file).
#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <algorithm>
#include <bit>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "support/io_scratch.hpp"
#include "support/mesh_checks.hpp"

using Catch::Matchers::Contains;
using namespace voxmesh;

namespace {

using iotest::Scratch;
using vmtest::same_bits;

// A PLY body described value by value, written as ASCII or binary of either byte order.
struct Prop {
    std::string type;        // a list's item type
    std::string name;
    std::string count_type;  // non-empty for a list
};
struct Elem {
    std::string name;
    std::vector<Prop> props;
    std::vector<std::vector<std::vector<double>>> records;  // [record][property]: one value, or a list's items
};

void put_binary(std::string& out, const std::string& type, double v, bool big) {
    unsigned char bytes[8];
    std::size_t n = 0;
    auto store = [&](auto value) {
        n = sizeof value;
        std::memcpy(bytes, &value, n);
    };
    if (type == "char" || type == "int8") store(static_cast<std::int8_t>(v));
    else if (type == "uchar" || type == "uint8") store(static_cast<std::uint8_t>(v));
    else if (type == "short" || type == "int16") store(static_cast<std::int16_t>(v));
    else if (type == "ushort" || type == "uint16") store(static_cast<std::uint16_t>(v));
    else if (type == "int" || type == "int32") store(static_cast<std::int32_t>(v));
    else if (type == "uint" || type == "uint32") store(static_cast<std::uint32_t>(v));
    else if (type == "float" || type == "float32") store(static_cast<float>(v));
    else store(v);
    if (big != (std::endian::native == std::endian::big)) std::reverse(bytes, bytes + n);
    out.append(reinterpret_cast<const char*>(bytes), n);
}

void put_ascii(std::string& out, const std::string& type, double v) {
    char text[64];
    char* end = text;
    if (type == "float" || type == "float32") end = std::to_chars(text, text + sizeof text, static_cast<float>(v)).ptr;
    else if (type == "double" || type == "float64") end = std::to_chars(text, text + sizeof text, v).ptr;
    else end = std::to_chars(text, text + sizeof text, static_cast<long long>(v)).ptr;
    out.append(text, end);
    out += ' ';
}

// format: "ascii", "binary_little_endian" or "binary_big_endian".
std::string encode(const std::vector<Elem>& elements, const std::string& format, const std::string& extra_header = "") {
    std::string out = "ply\nformat " + format + " 1.0\n" + extra_header;
    for (const Elem& e : elements) {
        out += "element " + e.name + " " + std::to_string(e.records.size()) + "\n";
        for (const Prop& p : e.props)
            out += "property " + (p.count_type.empty() ? "" : "list " + p.count_type + " ") + p.type + " " + p.name + "\n";
    }
    out += "end_header\n";
    const bool ascii = format == "ascii";
    const bool big = format == "binary_big_endian";
    for (const Elem& e : elements)
        for (const auto& record : e.records) {
            for (std::size_t k = 0; k < e.props.size(); ++k) {
                const Prop& p = e.props[k];
                if (!p.count_type.empty()) {
                    const double n = static_cast<double>(record[k].size());
                    ascii ? put_ascii(out, p.count_type, n) : put_binary(out, p.count_type, n, big);
                }
                for (double v : record[k]) ascii ? put_ascii(out, p.type, v) : put_binary(out, p.type, v, big);
            }
            if (ascii) out += '\n';
        }
    return out;
}

// An extra element with a list before the vertices, mixed coordinate types, colours, a face
// property before the index list, a quad, and a fixed-size element after the faces.
std::vector<Elem> mixed_content() {
    Elem material{"material", {{"int", "ids", "uchar"}, {"float", "shininess", ""}}, {{{1, 2, 3}, {0.5}}, {{}, {1.5}}}};
    Elem vertex{"vertex",
                {{"double", "x", ""}, {"int", "y", ""}, {"float", "z", ""}, {"uchar", "red", ""}, {"uchar", "green", ""},
                 {"uchar", "blue", ""}},
                {}};
    const double xyz[5][3] = {{0.1, 0, -0.0}, {1, 0, 0}, {1, 1, 0}, {-3.5, 1, 1e-3}, {0.25, -7, 2}};
    for (const auto& p : xyz) vertex.records.push_back({{p[0]}, {p[1]}, {p[2]}, {255}, {0}, {128}});
    Elem face{"face", {{"int", "flags", ""}, {"int", "vertex_indices", "uchar"}}, {{{7}, {0, 1, 2, 3}}, {{8}, {0, 1, 4}}}};
    Elem edge{"edge", {{"int", "vertex1", ""}, {"int", "vertex2", ""}}, {{{0}, {1}}, {{1}, {2}}}};
    return {material, vertex, face, edge};
}

const std::vector<float> kMixedPositions = {0.1f, 0, -0.0f, 1, 0, 0, 1, 1, 0, -3.5f, 1, 1e-3f, 0.25f, -7, 2};
const std::vector<std::uint32_t> kMixedIndices = {0, 1, 2, 0, 2, 3, 0, 1, 4};

}  // namespace

TEST_CASE("ply: hand-written ASCII with quads, CRLF, comments and extra properties", "[io][ply]") {
    Scratch s;
    const std::string text =
        "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info anything at all\r\n"
        "element material 1\r\nproperty list uchar int ids\r\nproperty float shininess\r\n"
        "element vertex 6\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n"
        "property uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\n"
        "element face 3\r\nproperty list uchar uint vertex_indices\r\ncomment between elements\r\nend_header\r\n"
        "3 4 5 6 0.25\r\n"
        "0 0 0 255 0 0\r\n1 0 0 0 255 0\r\n1 1 0 0 0 255\r\n0 1 0 1 2 3\r\n"
        "+2 1e0 -0 9 9 9\r\n2.5 0.5 1E-1 0 0 0\r\n"
        "4 0 1 2 3\r\n3 1 4 2\r\n5 0 1 4 5 3\r\n\r\n  \t\r\n";
    const Mesh m = read_ply(s.file("hand.ply", text));
    CHECK(m.positions == std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 1, -0.0f, 2.5f, 0.5f, 0.1f});
    CHECK(std::signbit(m.positions[14]));
    CHECK(m.indices == std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 1, 4, 2, 0, 1, 4, 0, 4, 5, 0, 5, 3});
    CHECK(m.normals.empty());

    // Records need not keep to lines: the data is a stream of words.
    const Mesh joined = read_ply(s.file("joined.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                                       "property float y\nproperty float z\nelement face 1\n"
                                                       "property list uchar int vertex_indices\nend_header\n"
                                                       "0 0 0 1 0\n0 0 1 0 3\n0 1 2"));
    CHECK(joined.positions == std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0});
    CHECK(joined.indices == std::vector<std::uint32_t>{0, 1, 2});
}

TEST_CASE("ply: ASCII, little- and big-endian binary of the same content read alike", "[io][ply]") {
    Scratch s;
    const std::vector<Elem> content = mixed_content();
    const Mesh ascii = read_ply(s.file("a.ply", encode(content, "ascii", "comment x\n")));
    const Mesh little = read_ply(s.file("le.ply", encode(content, "binary_little_endian")));
    const Mesh big = read_ply(s.file("be.ply", encode(content, "binary_big_endian")));
    CHECK(same_bits(ascii.positions, kMixedPositions));
    CHECK(ascii.indices == kMixedIndices);
    CHECK(ascii.normals.empty());
    for (const Mesh* m : {&little, &big}) {
        CHECK(same_bits(m->positions, ascii.positions));
        CHECK(m->indices == ascii.indices);
        CHECK(m->normals.empty());
    }
}

TEST_CASE("ply: every scalar type reads as float coordinates and indices", "[io][ply]") {
    Scratch s;
    const char* types[] = {"char",  "int8",  "uchar",   "uint8",  "short",  "int16",   "ushort", "uint16",
                           "int",   "int32", "uint",    "uint32", "float",  "float32", "double", "float64"};
    for (const char* type : types) {
        const std::string t = type;
        const bool is_signed = t == "char" || t == "int8" || t == "short" || t == "int16" || t == "int" ||
                               t == "int32" || t.find("float") == 0 || t == "double";
        const double low = is_signed ? -5 : 0;
        Elem vertex{"vertex", {{t, "x", ""}, {t, "y", ""}, {t, "z", ""}, {t, "nx", ""}, {t, "ny", ""}, {t, "nz", ""}},
                    {{{low}, {1}, {2}, {0}, {0}, {1}}, {{3}, {low}, {100}, {1}, {0}, {0}}, {{7}, {8}, {low}, {0}, {1}, {0}}}};
        const bool integer_index = t.find("float") != 0 && t != "double";
        Elem face{"face", {{integer_index ? t : "int", "vertex_indices", integer_index ? t : "uchar"}}, {{{2, 1, 0}}}};
        for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
            INFO(type << " " << format);
            const Mesh m = read_ply(s.file("types.ply", encode({vertex, face}, format)));
            const float l = static_cast<float>(low);
            CHECK(m.positions == std::vector<float>{l, 1, 2, 3, l, 100, 7, 8, l});
            CHECK(m.normals == std::vector<float>{0, 0, 1, 1, 0, 0, 0, 1, 0});
            CHECK(m.indices == std::vector<std::uint32_t>{2, 1, 0});
        }
    }
}

TEST_CASE("ply: normals need all of nx, ny, nz; 'vertex_index' names the corners too", "[io][ply]") {
    Scratch s;
    Elem vertex{"vertex", {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}, {"float", "nx", ""}, {"float", "nz", ""}},
                {{{0}, {0}, {0}, {1}, {0}}, {{1}, {0}, {0}, {1}, {0}}, {{0}, {1}, {0}, {1}, {0}}}};
    Elem face{"face", {{"int", "vertex_index", "uchar"}}, {{{0, 2, 1}}}};
    for (const char* format : {"ascii", "binary_little_endian"}) {
        const Mesh m = read_ply(s.file("partial.ply", encode({vertex, face}, format)));
        CHECK(m.normals.empty());
        CHECK(m.positions.size() == 9);
        CHECK(m.indices == std::vector<std::uint32_t>{0, 2, 1});
    }
    // Both names: vertex_indices is the one read.
    Elem both{"face", {{"int", "vertex_index", "uchar"}, {"int", "vertex_indices", "uchar"}}, {{{0, 0, 0}, {1, 2, 0}}}};
    CHECK(read_ply(s.file("both.ply", encode({vertex, both}, "ascii"))).indices == std::vector<std::uint32_t>{1, 2, 0});
}

TEST_CASE("ply: a NaN or infinite normal drops the normals, as in read_obj; the mesh is kept", "[io][ply]") {
    Scratch s;
    for (const double bad : {double(NAN), double(INFINITY), -double(INFINITY)}) {
        for (const char* type : {"float", "double"}) {
            const std::string t = type;
            Elem vertex{"vertex", {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}, {t, "nx", ""}, {t, "ny", ""}, {t, "nz", ""}},
                        {{{0}, {0}, {0}, {0}, {0}, {1}}, {{1}, {0}, {0}, {0}, {bad}, {1}}, {{0}, {1}, {0}, {0}, {0}, {1}}}};
            Elem face{"face", {{"int", "vertex_indices", "uchar"}}, {{{0, 1, 2}}}};
            for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
                INFO(bad << " " << type << " " << format);
                const Mesh m = read_ply(s.file("nan-normal.ply", encode({vertex, face}, format)));
                CHECK(m.normals.empty());
                CHECK(m.positions == std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0});
                CHECK(m.indices == std::vector<std::uint32_t>{0, 1, 2});
            }
        }
    }
}

// Found by a differential review: a header whose lines end in a lone '\r' (classic Mac OS
// exporters) was "not a PLY file", and so was one after a UTF-8 byte order mark.
TEST_CASE("ply: header lines ending in a lone CR, and a byte order mark, read as with LF", "[io][ply]") {
    Scratch s;
    // The first body byte is '\n' (flags 10): after "end_header\r" it is data, not a CRLF's end.
    Elem vertex{"vertex", {{"uchar", "flags", ""}, {"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}},
                {{{10}, {0}, {0}, {0}}, {{13}, {1}, {0}, {0}}, {{10}, {0}, {1}, {0}}, {{13}, {1}, {1}, {0}}}};
    Elem face{"face", {{"int", "vertex_indices", "uchar"}}, {{{0, 1, 3, 2}}}};
    for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
        INFO(format);
        const std::string lf = encode({vertex, face}, format, "comment made on a Mac\nobj_info x\n");
        const Mesh expected = read_ply(s.file("lf.ply", lf));
        REQUIRE(expected.indices == std::vector<std::uint32_t>{0, 1, 3, 0, 3, 2});
        const std::size_t body = lf.find("end_header\n") + 11;
        std::string cr = lf;
        std::replace(cr.begin(), cr.begin() + static_cast<std::ptrdiff_t>(body), '\n', '\r');
        if (std::string(format) == "ascii") std::replace(cr.begin(), cr.end(), '\n', '\r');
        for (const std::string& text : {cr, "\xEF\xBB\xBF" + lf, "\xEF\xBB\xBF" + cr}) {
            const Mesh m = read_ply(s.file("other.ply", text));
            CHECK(same_bits(m.positions, expected.positions));
            CHECK(m.indices == expected.indices);
        }
    }
    // Errors count lone-CR lines, in the header and in ASCII data.
    const std::string header = "ply\rformat ascii 1.0\relement vertex 1\rproperty float x\rproperty float y\r"
                               "property float z\r";
    CHECK_THROWS_WITH(read_ply(s.file("bad.ply", header + "bogus\rend_header\r0 0 0\r")),
                      Contains("line 7: unknown header line"));
    CHECK_THROWS_WITH(read_ply(s.file("bad.ply", header + "end_header\r\r0 0 q\r")),
                      Contains("line 9: vertex 0: property 'z': 'q'"));
}

TEST_CASE("ply: point clouds and empty meshes", "[io][ply]") {
    Scratch s;
    Elem vertex{"vertex", {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}}, {{{1}, {2}, {3}}, {{4}, {5}, {6}}}};
    for (const char* format : {"ascii", "binary_big_endian"}) {
        INFO(format);
        const Mesh cloud = read_ply(s.file("cloud.ply", encode({vertex}, format)));
        CHECK(cloud.positions == std::vector<float>{1, 2, 3, 4, 5, 6});
        CHECK(cloud.indices.empty());
        const Mesh no_faces = read_ply(s.file("nofaces.ply", encode({vertex, Elem{"face", {}, {}}}, format)));
        CHECK(no_faces.positions.size() == 6);
        CHECK(no_faces.indices.empty());
        const Mesh empty = read_ply(s.file("empty.ply", encode({Elem{"vertex", vertex.props, {}}}, format)));
        CHECK(empty.positions.empty());
        CHECK(empty.indices.empty());
    }
    // Elements that declare no properties take no bytes, however many records they claim.
    const Mesh hollow = read_ply(s.file("hollow.ply", "ply\nformat binary_little_endian 1.0\nelement nothing 18446744073709551615\n"
                                                      "element vertex 0\nproperty float x\nproperty float y\n"
                                                      "property float z\nend_header\n"));
    CHECK(hollow.positions.empty());
}

TEST_CASE("ply: values at the float range's edges", "[io][ply]") {
    Scratch s;
    auto one_vertex = [](const std::string& type, double z) {
        return std::vector<Elem>{Elem{"vertex", {{"float", "x", ""}, {"float", "y", ""}, {type, "z", ""}}, {{{0}, {0}, {z}}}}};
    };
    // A double too small for a float reads as zero, in binary as in ASCII.
    for (const char* format : {"binary_little_endian", "binary_big_endian"})
        CHECK(read_ply(s.file("tiny.ply", encode(one_vertex("double", 1e-300), format))).positions[2] == 0.0f);
    const std::string header = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty double z\nend_header\n";
    CHECK(read_ply(s.file("tiny.ply", header + "0 0 1e-50\n")).positions[2] == 0.0f);
    CHECK(read_ply(s.file("max.ply", header + "0 0 3.4028234e38\n")).positions[2] == FLT_MAX);
    CHECK(read_ply(s.file("max.ply", encode(one_vertex("double", FLT_MAX), "binary_little_endian"))).positions[2] == FLT_MAX);
    CHECK(read_ply(s.file("denormal.ply", header + "0 0 1e-40\n")).positions[2] == 1e-40f);
}

TEST_CASE("ply: bad files are errors naming the file and the problem", "[io][ply][errors]") {
    Scratch s;
    auto fails = [&](const std::string& bytes, const std::string& what) {
        const std::string path = s.file("bad.ply", bytes);
        CHECK_THROWS_WITH(read_ply(path), Contains(path) && Contains(what));
    };
    const std::string xyz = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    const std::string ascii = "ply\nformat ascii 1.0\n";
    const std::string faces = "element face 1\nproperty list uchar int vertex_indices\n";
    const std::string verts = "0 0 0\n1 0 0\n0 1 0\n";

    fails("", "file is empty");
    fails("plx\nformat ascii 1.0\nend_header\n", "not a PLY file");
    fails("\x89PNG\r\n", "not a PLY file");
    fails("ply\nformat binary_middle_endian 1.0\n" + xyz + "end_header\n", "unknown format 'binary_middle_endian'");
    fails("ply\nformat ascii 2.0\n" + xyz + "end_header\n", "unknown PLY version '2.0'");
    fails("ply\nformat ascii\n" + xyz + "end_header\n", "malformed format line");
    fails("ply\n" + xyz + "end_header\n" + verts, "no 'format' line");
    fails(ascii + ascii.substr(4) + xyz + "end_header\n", "a second 'format' line");
    fails(ascii + "element vertex 1\nproperty float128 x\nend_header\n", "line 4: unknown type 'float128'");
    fails(ascii + "element vertex\nend_header\n", "line 3: malformed element line");
    fails(ascii + "element vertex -3\nend_header\n", "'-3' is not a non-negative integer");
    fails(ascii + "element vertex 99999999999999999999999\nend_header\n", "is too large");
    fails(ascii + "element vertex 1\nproperty float\nend_header\n", "malformed property line");
    fails(ascii + "element vertex 1\nproperty list uchar x\nend_header\n", "malformed property line");
    fails(ascii + "element vertex 1\nproperty float x extra\nend_header\n", "malformed property line");
    fails(ascii + "property float x\n" + xyz + "end_header\n", "a property before any element");
    fails(ascii + xyz + "elephant 3\nend_header\n", "line 7: unknown header line 'elephant 3'");
    fails(ascii + xyz + "end_header now\n", "malformed 'end_header' line");
    fails(ascii + xyz, "no 'end_header' line");
    fails(ascii + xyz + "end_head", "unknown header line 'end_head'");
    fails(ascii + "element vertex 1\nproperty float x\nproperty float x\nend_header\n", "property 'x' appears twice");
    fails(ascii + xyz + xyz + "end_header\n", "element 'vertex' is declared twice");
    fails(ascii + "element face 0\nproperty list uchar int vertex_indices\nend_header\n", "no 'vertex' element");
    fails(ascii + "element vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n", "no scalar property 'z'");
    fails(ascii + "element vertex 1\nproperty float x\nproperty float y\nproperty list uchar float z\nend_header\n",
          "no scalar property 'z'");
    fails(ascii + xyz + "element face 1\nproperty list float int vertex_indices\nend_header\n",
          "count type must be an integer type, not 'float'");
    fails(ascii + xyz + "element face 1\nproperty list uchar float vertex_indices\nend_header\n" + verts + "3 0 1 2\n",
          "'vertex_indices' must be a list of an integer type");
    fails(ascii + xyz + "element face 1\nproperty int vertex_indices\nend_header\n" + verts + "0\n",
          "'vertex_indices' must be a list of an integer type");
    fails(ascii + xyz + "element face 1\nproperty list uchar int corners\nend_header\n" + verts + "3 0 1 2\n",
          "no 'vertex_indices' list");
    fails(ascii + "element vertex 5000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
          "5000000000 vertices are too many for 32-bit indices");

    // The data.
    fails(ascii + xyz + faces + "end_header\n" + verts + "2 0 1\n", "line 13: face 0: a face has 2 corners");
    fails(ascii + xyz + faces + "end_header\n" + verts + "3 0 1 3\n", "face 0: vertex index 3 is outside the 3 vertices");
    fails(ascii + xyz + faces + "end_header\n" + verts + "3 0 -1 2\n", "negative vertex index -1");
    fails(ascii + xyz + "element face 1\nproperty list char int vertex_indices\nend_header\n" + verts + "-1 0 1 2\n",
          "negative list count -1");
    fails(ascii + xyz + faces + "end_header\n" + verts + "-1 0 1 2\n", "'-1' is out of range for uchar");
    fails(ascii + xyz + faces + "end_header\n" + verts + "3 0 1 2.0\n", "'2.0' is not an integer");
    fails(ascii + xyz + faces + "end_header\n" + verts + "3 0 1 99999999999999999999\n", "out of range for int");
    fails(ascii + xyz + faces + "end_header\n" + verts + "3 0 1\n", "file ends inside face 0 of 1 (too few values)");
    fails(ascii + xyz + "end_header\n0 0 0\n1 0 0\n0  1\n", "line 11: file ends inside vertex 2 of 3");
    fails(ascii + xyz + "end_header\n" + verts + "7\n", "line 11: unexpected '7' after the last element");
    fails(ascii + xyz + "end_header\n0 0 0\n1 0 x\n0 1 0\n", "line 9: vertex 1: property 'z': 'x' is not a number");
    fails(ascii + xyz + "end_header\n0 0 0\n1 0 nan\n0 1 0\n", "vertex 1: property 'z' is not finite");
    fails(ascii + xyz + "end_header\n0 0 0\n1 0 -inf\n0 1 0\n", "property 'z' is not finite");
    fails(ascii + xyz + "end_header\n0 0 0\n1 0 1e39\n0 1 0\n", "'1e39' is beyond the range of float");
    fails(ascii + "element vertex 1\nproperty double x\nproperty float y\nproperty float z\nend_header\n1e300 0 0\n",
          "'1e300' is beyond the range of float");
    fails(ascii + "element vertex 1\nproperty int x\nproperty float y\nproperty float z\nend_header\n1.5 0 0\n",
          "'1.5' is not an integer");
    fails(ascii + "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
                  "end_header\n0 0 0 256\n",
          "'256' is out of range for uchar");
    fails(ascii + "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float w\n"
                  "end_header\n0 0 0 w\n",
          "'w' is not a number");
    fails(ascii + "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n"
                  "property float ny\nproperty float nz\nend_header\n0 0 1e39 0 0 1\n",
          "'1e39' is beyond the range of float");
    fails(ascii + "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n"
                  "property float ny\nproperty float nz\nend_header\n0 0 0 0 1e39 1\n",
          "'1e39' is beyond the range of float");

    // Binary.
    Elem vertex{"vertex", {{"float", "x", ""}, {"float", "y", ""}, {"double", "z", ""}}, {{{0}, {0}, {0}}, {{1}, {0}, {0}}, {{0}, {1}, {0}}}};
    Elem face{"face", {{"int", "vertex_indices", "char"}}, {{{0, 1, 2}}}};
    const std::string good = encode({vertex, face}, "binary_little_endian");
    REQUIRE(read_ply(s.file("good.ply", good)).indices.size() == 3);
    fails(good + '\0', "1 bytes of unexpected data after the last element");
    fails(good.substr(0, good.size() - 1), "file ends inside face 0 of 1 (truncated)");
    auto with_vertex = [&](double x, const std::string& z_type, double z) {
        Elem v = vertex;
        v.props[2].type = z_type;
        v.records[1] = {{x}, {0}, {z}};
        return encode({v, face}, "binary_big_endian");
    };
    fails(with_vertex(NAN, "double", 0), "vertex 1: property 'x' is not finite");
    fails(with_vertex(0, "double", INFINITY), "property 'z' is not finite");
    fails(with_vertex(0, "float", -INFINITY), "property 'z' is not finite");
    fails(with_vertex(0, "double", 1e300), "vertex 1: property 'z' is beyond the range of float");
    fails(with_vertex(0, "double", -3.5e38), "property 'z' is beyond the range of float");
    Elem bad_face = face;
    bad_face.records = {{{0, 1, 3}}};
    fails(encode({vertex, bad_face}, "binary_little_endian"), "face 0: vertex index 3 is outside the 3 vertices");
    bad_face.records = {{{0, -2, 1}}};
    fails(encode({vertex, bad_face}, "binary_little_endian"), "negative vertex index -2");
    bad_face.records = {{{0, 1}}};
    fails(encode({vertex, bad_face}, "binary_little_endian"), "a face has 2 corners");
    std::string negative_count = good;
    negative_count[good.size() - 13] = '\xff';  // the char count before the three int indices
    fails(negative_count, "face 0: negative list count -1");
    // A huge list count in a skipped list is refused before reading past the end.
    Elem extra{"extra", {{"int", "items", "uint"}}, {{{1, 2}}}};
    std::string huge_list = encode({extra, vertex, face}, "binary_little_endian");
    const std::size_t body = huge_list.find("end_header\n") + 11;
    std::memset(huge_list.data() + body, 0xff, 4);
    fails(huge_list, "file ends inside extra 0 of 1");
    // A fixed-size element cut short.
    Elem edge{"edge", {{"int", "vertex1", ""}, {"int", "vertex2", ""}}, {{{0}, {1}}, {{1}, {2}}}};
    const std::string edges = encode({vertex, face, edge}, "binary_little_endian");
    REQUIRE(read_ply(s.file("edges.ply", edges)).indices.size() == 3);
    fails(edges.substr(0, edges.size() - 4), "file ends inside edge 1 of 2");

    std::filesystem::create_directory(s.dir + "/dir.ply");
    CHECK_THROWS_WITH(read_ply(s.dir + "/dir.ply"), Contains("dir.ply") && Contains("directory"));
    CHECK_THROWS_WITH(read_ply(s.dir + "/missing.ply"), Contains("missing.ply") && Contains("does not exist"));
}

TEST_CASE("ply: header counts are checked against the file before allocating", "[io][ply][errors]") {
    Scratch s;
    const std::string props = "property float x\nproperty float y\nproperty float z\n";
    for (const char* format : {"ascii", "binary_little_endian"}) {
        INFO(format);
        const std::string head = std::string("ply\nformat ") + format + " 1.0\n";
        // 4e9 vertices in a tiny file: a 48 GB allocation if trusted.
        const std::string path = s.file("huge.ply", head + "element vertex 4000000000\n" + props + "end_header\n0 0 0\n");
        CHECK_THROWS_WITH(read_ply(path), Contains(path) && Contains("file too short") &&
                                              Contains("element 'vertex' declares 4000000000 records"));
        // The same for faces, and for elements that are only skipped.
        CHECK_THROWS_WITH(read_ply(s.file("faces.ply", head + "element vertex 0\n" + props + "element face 3000000000\n"
                                                           "property list uchar int vertex_indices\nend_header\n")),
                          Contains("element 'face' declares 3000000000 records"));
        CHECK_THROWS_WITH(read_ply(s.file("skip.ply", head + "element junk 18446744073709551615\nproperty uchar a\n"
                                                          "element vertex 0\n" + props + "end_header\n")),
                          Contains("element 'junk' declares 18446744073709551615 records"));
    }
    // ASCII: 3 vertices of 3 values need at least 17 bytes ("0 0 0 0 0 0 0 0 0").
    const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 3\n" + props + "end_header\n";
    CHECK_THROWS_WITH(read_ply(s.file("short.ply", ascii + "0 0 0 0 0 0 0 0")), Contains("file too short"));
    CHECK(read_ply(s.file("exact.ply", ascii + "0 0 0 0 0 0 0 0 0")).positions.size() == 9);
    // A face's list count, in either body: 4e9 corners would reserve 48 GB of indices if
    // trusted; the rest of the file cannot hold them, which is the error.
    const std::string faces = "element face 2\nproperty list uint int vertex_indices\nend_header\n";
    const std::string text_head = "ply\nformat ascii 1.0\nelement vertex 3\n" + props + faces;
    CHECK_THROWS_WITH(read_ply(s.file("list.ply", text_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n4000000000 0 1 2\n")),
                      Contains("line 14: file ends inside face 1 of 2 (too few values)"));
    CHECK(read_ply(s.file("list_exact.ply", text_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0")).indices.size() == 6);
    std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n" + props + faces;
    binary.append(36, '\0');  // three vertices at the origin
    const auto u32 = [&](std::uint32_t v) { binary.append(reinterpret_cast<const char*>(&v), 4); };
    for (std::uint32_t v : {3u, 0u, 1u, 2u, 4000000000u, 0u, 1u, 2u}) u32(v);
    CHECK_THROWS_WITH(read_ply(s.file("blist.ply", binary)), Contains("file ends inside face 1 of 2 (truncated)"));
}

TEST_CASE("ply: a header declaring tens of thousands of properties reads quickly", "[io][ply]") {
    Scratch s;
    std::string header = "ply\nformat binary_little_endian 1.0\nelement wide 1\n";
    for (int i = 0; i < 40000; ++i) header += "property uchar p" + std::to_string(i) + "\n";
    const std::string xyz = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    const float one[3] = {1, 2, 3};
    const std::string body = std::string(40000, '\x07') + std::string(reinterpret_cast<const char*>(one), 12);
    CHECK(read_ply(s.file("wide.ply", header + xyz + body)).positions == std::vector<float>{1, 2, 3});
    CHECK_THROWS_WITH(read_ply(s.file("twice.ply", header + "property uchar p39999\n" + xyz + body)),
                      Contains("property 'p39999' appears twice in element 'wide'"));
}

TEST_CASE("ply: a header with no end within 1 MiB is refused", "[io][ply][errors]") {
    Scratch s;
    std::string comments = "ply\nformat ascii 1.0\n";
    while (comments.size() <= (1u << 20)) comments += "comment " + std::string(100, 'c') + "\n";
    const std::string path = s.file("long.ply", comments + "element vertex 0\nproperty float x\nproperty float y\n"
                                                           "property float z\nend_header\n");
    CHECK_THROWS_WITH(read_ply(path), Contains(path) && Contains("header too long"));
    // One line running past the limit.
    const std::string line = s.file("line.ply", "ply\ncomment " + std::string(1u << 20, 'x') + "\nend_header\n");
    CHECK_THROWS_WITH(read_ply(line), Contains("header too long"));
    // "end_header" cut by the limit (the file goes on) is not an end.
    std::string cut = "ply\nformat ascii 1.0\ncomment ";
    cut += std::string((1u << 20) - cut.size() - 11, 'y') + "\nend_header";
    REQUIRE(cut.size() == (1u << 20));
    CHECK_THROWS_WITH(read_ply(s.file("cut.ply", cut + "s\n")), Contains("header too long"));
}

TEST_CASE("ply: every truncation of a binary file is an error, never a crash", "[io][ply][errors]") {
    Scratch s;
    std::vector<Elem> content = mixed_content();
    content[1].props.push_back({"float", "nx", ""});
    content[1].props.push_back({"double", "ny", ""});
    content[1].props.push_back({"short", "nz", ""});
    for (auto& record : content[1].records) record.insert(record.end(), {{0.5}, {0.25}, {-1}});
    for (const char* format : {"binary_little_endian", "binary_big_endian"}) {
        const std::string whole = encode(content, format);
        const Mesh full = read_ply(s.file("whole.ply", whole));
        CHECK(same_bits(full.positions, kMixedPositions));
        CHECK(full.normals.size() == 15);
        CHECK(full.indices == kMixedIndices);
        for (std::size_t n = 0; n < whole.size(); ++n) {
            INFO(format << " prefix of " << n << " bytes");
            CHECK_THROWS_AS(read_ply(s.file("cut.ply", whole.substr(0, n))), Error);
        }
    }
    // ASCII prefixes may still be valid (a number cut to fewer digits), but never crash.
    const std::string text = encode(content, "ascii");
    std::size_t refused = 0;
    for (std::size_t n = 0; n < text.size(); ++n) {
        try {
            const Mesh m = read_ply(s.file("cut.ply", text.substr(0, n)));
            CHECK(m.indices.size() == kMixedIndices.size());
        } catch (const Error&) {
            ++refused;
        }
    }
    CHECK(refused + 8 > text.size());
}
