// read_obj: write_mesh round trips, the OBJ statements and corner forms it reads, when it keeps
// normals, and the errors (each naming the file and the line).
#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "support/io_scratch.hpp"
#include "support/mesh_checks.hpp"

using Catch::Matchers::Contains;
using namespace voxmesh;

namespace {

using iotest::Scratch;

Mesh read_text(const Scratch& s, const std::string& text) { return read_obj(s.file("m.obj", text)); }

// A file's name, line and problem must all be in the message.
void check_fails(const Scratch& s, const std::string& text, int line, const std::string& what) {
    INFO(text);
    const std::string path = s.file("bad.obj", text);
    CHECK_THROWS_WITH(read_obj(path), Contains("'" + path + "'") && Contains("line " + std::to_string(line) + ": ") &&
                                          Contains(what));
}

const char* const kSquare = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

}  // namespace

TEST_CASE("obj: polygons are fanned from their first corner in file order and winding", "[io][obj]") {
    Scratch s;
    const Mesh m = read_text(s, std::string(kSquare) + "v 0.5 2 0\n"
                                                       "f 1 2 3 4\n"
                                                       "f 5 4 3 2 1\n"
                                                       "f 3 2 1\n");
    CHECK(m.vertex_count() == 5);
    CHECK(m.indices == std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3,            // quad
                                                  4, 3, 2, 4, 2, 1, 4, 1, 0,  // pentagon
                                                  2, 1, 0});
    CHECK(m.normals.empty());
    CHECK(m.positions == std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5f, 2, 0});
}

TEST_CASE("obj: every corner form, mixed, and negative indices", "[io][obj]") {
    Scratch s;
    const std::string head = std::string(kSquare) + "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nvn 0 0 -1\n";
    const Mesh m = read_text(s, head + "f 1 2 3\n"
                                       "f 1/1 2/2 3/3\n"
                                       "f 1/1/1 2/2/1 3/3/2\n"
                                       "f 1//1 2//2 3//1\n"
                                       "f 1 2/3 3/1/2 4//2\n"  // mixed forms in one face
                                       "f -4 -3 -2 -1\n"
                                       "f -4/-3 -3/-2/-1 -2//-2\n");
    CHECK(m.indices == std::vector<std::uint32_t>{0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 2, 3,
                                                  0, 1, 2, 0, 2, 3, 0, 1, 2});
    CHECK(m.normals.empty());  // 2 normals for 4 vertices

    // Negative indices count back from the latest "v" read so far, not from the file's last.
    const Mesh later = read_text(s, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -1 -2 -3\nf 1 -1 2\n");
    CHECK(later.indices == std::vector<std::uint32_t>{0, 1, 2, 3, 2, 1, 0, 3, 1});
}

TEST_CASE("obj: comments, CRLF, continuations, whitespace and skipped statements", "[io][obj]") {
    Scratch s;
    const std::string text = "# a comment line\r\n"
                             "mtllib scene.mtl\r\n"
                             "o object one\r\n"
                             "g group\r\n"
                             "\r\n"
                             "   \t v 0 0 0 # a trailing comment\r\n"
                             "v\t1 0 0 1.0\r\n"        // w
                             "v 1 1 0 0.5 0.25 1\r\n"  // colours
                             "v 0 \\\r\n"              // continued...
                             "  1 \\  \r\n"             // ...with blanks after the '\'...
                             "  +0\r\n"                 // ...over three lines
                             "vt 0.5 0.5\r\n"
                             "vp 0.1 0.2\r\n"
                             "s off\r\n"
                             "usemtl red\r\n"
                             "l 1 2 3\r\n"
                             "p 1\r\n"
                             "cstype bspline\r\n"
                             "unknown_keyword 1 2 3 / // junk\r\n"
                             "f 1 2 3 4 # quad\r\n"
                             "f 1 \\\r\n"
                             "3 4\r\n"
                             "# comment ending in a backslash is not continued \\\r\n"
                             "f 2 3 4\r\n"
                             "#no blank\n"
                             "f 4 3 1";  // no final newline
    const Mesh m = read_text(s, text);
    CHECK(m.positions == std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
    CHECK(m.indices == std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 0, 2, 3, 1, 2, 3, 3, 2, 0});
    CHECK(m.normals.empty());

    // A line number in an error counts physical lines (the statement's first).
    check_fails(s, "v 0 0 \\\n0\nv 1 0 0\n# c\nf 1 2 \\\n 9\n", 5, "out of range");
}

TEST_CASE("obj: normals are kept only when each vertex's corners name its own normal", "[io][obj]") {
    Scratch s;
    const std::string vs = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    const std::string vns = "vn 0 0 1\nvn 0 1 0\nvn 1 0 0\n";
    const std::vector<float> expected{0, 0, 1, 0, 1, 0, 1, 0, 0};

    CHECK(read_text(s, vs + vns + "f 1//1 2//2 3//3\n").normals == expected);
    CHECK(read_text(s, vs + vns + "vt 0 0\nf 1/1/1 2/1/2 3/1/3\n").normals == expected);
    CHECK(read_text(s, vs + vns + "f -3//-3 -2//-2 -1//-1\n").normals == expected);
    // Interleaved "v" and "vn", referred to by negative indices.
    CHECK(read_text(s, "v 0 0 0\nvn 0 0 1\nv 1 0 0\nvn 0 1 0\nv 0 1 0\nvn 1 0 0\nf -3//-3 -2//-2 -1//-1\n").normals ==
          expected);

    // Dropped (no error): a corner with another vertex's normal, one without a normal, a vn
    // count that differs from the v count, a non-finite normal.
    CHECK(read_text(s, vs + vns + "f 1//1 2//3 3//3\n").normals.empty());
    CHECK(read_text(s, vs + vns + "f 1//1 2//2 3//3\nf 1 2 3\n").normals.empty());
    CHECK(read_text(s, vs + vns + "vt 0 0\nf 1//1 2//2 3//3\nf 1/1 2/1 3/1\n").normals.empty());
    CHECK(read_text(s, vs + vns + "vn 0 0 1\nf 1//1 2//2 3//3\n").normals.empty());
    CHECK(read_text(s, vs + "vn 0 0 1\nvn 0 1 0\nf 1//1 2//2 3//2\n").normals.empty());
    CHECK(read_text(s, vs + vns + "v 1 1 1\nf 1//1 2//2 3//3\n").normals.empty());
    CHECK(read_text(s, vs + "vn 0 0 1\nvn nan 1 0\nvn 1 0 inf\nf 1//1 2//2 3//3\n").normals.empty());
}

// Found by a differential review: a lone '\r' did not end a line (the file was one long
// statement), and a UTF-8 byte order mark made the first "v" an unknown statement, silently
// shifting every vertex index after it.
TEST_CASE("obj: lines ending in a lone CR, and a byte order mark, read as with LF", "[io][obj]") {
    Scratch s;
    const std::string lf = std::string(kSquare) + "# quad\no q\nf 1 2 \\\n3 4\nf -4 -2 -1\n";
    const Mesh expected = read_text(s, lf);
    REQUIRE(expected.triangle_count() == 3);
    REQUIRE(expected.positions[0] == 0.0f);
    std::string cr = lf;
    for (char& c : cr)
        if (c == '\n') c = '\r';
    for (const std::string& text : {cr, "\xEF\xBB\xBF" + lf, "\xEF\xBB\xBF" + cr, lf + "\r\r\n\r"}) {
        const Mesh m = read_text(s, text);
        CHECK(m.positions == expected.positions);
        CHECK(m.indices == expected.indices);
    }
    // Line numbers in errors count lone-CR lines.
    check_fails(s, std::string(kSquare) + "\r\rf 1 2 9\r", 7, "out of range");
}

TEST_CASE("obj: bad files are errors naming the file, the line and the problem", "[io][obj][errors]") {
    Scratch s;
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    const std::string uv = tri + "vt 0 0\nvn 0 0 1\n";  // one vt, one vn: lines 4 and 5

    check_fails(s, tri + "f 1 2\n", 4, "face has 2 corners");
    check_fails(s, tri + "f\n", 4, "face has 0 corners");
    check_fails(s, tri + "f 1 2 # 3\n", 4, "face has 2 corners");
    check_fails(s, tri + "f 1 0 2\n", 4, "index 0");
    check_fails(s, tri + "f 1 2 -0\n", 4, "index 0");
    check_fails(s, uv + "f 1/0 2/1 3/1\n", 6, "index 0");
    check_fails(s, uv + "f 1//0 2//1 3//1\n", 6, "index 0");
    check_fails(s, tri + "f 1 2 4\n", 4, "vertex index in face corner '4' is out of range: 3 read so far");
    check_fails(s, tri + "f 1 2 -4\n", 4, "vertex index in face corner '-4' is out of range");
    check_fails(s, "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", 3, "out of range: 2 read so far");  // no forward references
    check_fails(s, tri + "f 1 2 99999999999999999999999\n", 4, "out of range");
    check_fails(s, tri + "f 1 2 -99999999999999999999999\n", 4, "out of range");
    check_fails(s, tri + "f 1 2 -9223372036854775808\n", 4, "out of range");
    check_fails(s, uv + "f 1/2 2/1 3/1\n", 6, "texture index in face corner '1/2' is out of range: 1 read so far");
    check_fails(s, tri + "f 1/1 2/1 3/1\n", 4, "texture index in face corner '1/1' is out of range: 0 read so far");
    check_fails(s, uv + "f 1/1/-2 2/1/1 3/1/1\n", 6, "normal index in face corner '1/1/-2' is out of range");
    check_fails(s, uv + "f 1//2 2//1 3//1\n", 6, "normal index in face corner '1//2' is out of range");
    for (const char* corner : {"1/", "a", "1//", "1/2/3/4", "/1", "//1", "1/a", "1//b", "+1", "1.0", "0x1", "1/1/",
                               "1/-", "-", "1 /2", "1e3"}) {
        INFO(corner);
        check_fails(s, uv + "f 2 3 " + corner + "\n", 6, "is malformed (expected v, v/vt, v/vt/vn or v//vn)");
    }
    check_fails(s, "v 0 0\nf 1 1 1\n", 1, "'v' needs three coordinates, found 2");
    check_fails(s, "v\n", 1, "'v' needs three coordinates, found 0");
    check_fails(s, tri + "v 1 2 x\n", 4, "'x' is not a number");
    check_fails(s, tri + "v 1,5 2 3\n", 4, "'1,5' is not a number");
    check_fails(s, tri + "v 1 2 3 4 5 6 7 8\n", 4, "more than seven numbers");
    check_fails(s, tri + "v 1 2 3 red\n", 4, "'red' is not a number");
    check_fails(s, tri + "v 1 nan 3\n", 4, "non-finite vertex coordinate 'nan'");
    check_fails(s, tri + "v 1 2 -inf\n", 4, "non-finite vertex coordinate '-inf'");
    check_fails(s, tri + "v 1e39 2 3\n", 4, "'1e39' is beyond the range of float");
    check_fails(s, tri + "vn 0 1\n", 4, "'vn' needs three numbers, found 2");
    check_fails(s, tri + "vn 0 1 0 1\n", 4, "'vn' has more than three numbers");
    check_fails(s, tri + "vn 0 x 0\n", 4, "'x' is not a number");
    check_fails(s, tri + "vn 0 -1e40 0\n", 4, "beyond the range of float");

    auto fails_whole = [&](const std::string& text, const std::string& what) {
        const std::string path = s.file("whole.obj", text);
        CHECK_THROWS_WITH(read_obj(path), Contains("'" + path + "'") && Contains(what));
    };
    fails_whole("", "file is empty");
    fails_whole("\x01\x02\x7f binary bytes\n", "no faces ('f' statements), and '\?\?\?' (line 1) is not an OBJ");
    fails_whole(tri + "hello world\n", "'hello' (line 4) is not an OBJ statement");
    CHECK_THROWS_WITH(read_obj(s.dir + "/missing.obj"), Contains("missing.obj") && Contains("does not exist"));

    // Tokens with binary bytes are shown with '?', never cut short.
    check_fails(s, tri + std::string("f 1 2 3\0x\n", 10), 4, "'3?x' is malformed");
    // Large line numbers are counted right.
    check_fails(s, std::string(100000, '\n') + tri + "f 1 2 5\n", 100004, "out of range");
}

TEST_CASE("obj: every truncation of a small file reads or is an Error", "[io][obj][errors]") {
    Scratch s;
    const std::string text = "# tetra\r\nmtllib a.mtl\no t\nv 0 0 0\nv 1 0 0 1\nv 0 1 0 0.1 0.2 0.3\nv 0 0 \\\n1\n"
                             "vt 0 0\nvn 0 0 -1\nvn 0 -1 0\nvn -1 0 0\nvn 1 1 1\ng side\nusemtl m\ns 1\n"
                             "f 1//1 3//3 2//2\nf 1/1/1 2/1/2 4/1/4\nf -4//-4 -1//-1 -2//-2\nf 2 3 4 # last\n";
    REQUIRE(read_text(s, text).triangle_count() == 4);
    std::size_t read = 0, errors = 0;
    for (std::size_t n = 0; n <= text.size(); ++n) {
        INFO(n);
        const std::string path = s.file("cut.obj", text.substr(0, n));
        try {
            const Mesh m = read_obj(path);
            ++read;
            CHECK(vmtest::structural_problem(m).empty());
            CHECK(m.indices.size() % 3 == 0);
            for (std::uint32_t i : m.indices) CHECK(i < m.vertex_count());
        } catch (const Error& e) {
            ++errors;
            CHECK_THAT(e.what(), Contains(path));
        }
    }
    CHECK(read > 10);
    CHECK(errors > 100);
}
