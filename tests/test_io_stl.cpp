#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "support/io_scratch.hpp"

using Catch::Matchers::Contains;
using namespace voxmesh;

namespace {

using iotest::Scratch;

std::string data(const char* name) { return std::string(VOXMESH_TEST_DATA) + "/" + name; }

// The mesh as ASCII STL, with floats printed so that they read back exactly.
std::string to_ascii(const Mesh& m) {
    std::string out = "solid test\n";
    char line[160];
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
        out += "  facet normal 0 0 0\n    outer loop\n";
        for (int k = 0; k < 3; ++k) {
            const float* p = &m.positions[3 * m.indices[3 * t + static_cast<std::size_t>(k)]];
            std::snprintf(line, sizeof line, "      vertex %.9g %.9g %.9g\n", double(p[0]), double(p[1]), double(p[2]));
            out += line;
        }
        out += "    endloop\n  endfacet\n";
    }
    return out + "endsolid test\n";
}

}  // namespace

TEST_CASE("stl: real binary models weld to the documented counts", "[io][stl]") {
    const Mesh sphere = read_stl(data("unit_sphere.stl"));
    CHECK(sphere.triangle_count() == 1280);
    CHECK(sphere.vertex_count() == 642);
    CHECK(sphere.normals.empty());

    // Binary, although its header starts with "solid torus".
    REQUIRE(iotest::read_file(data("torus.stl")).rfind("solid", 0) == 0);
    const Mesh torus = read_stl(data("torus.stl"));
    CHECK(torus.triangle_count() == 8700);
    CHECK(torus.vertex_count() == 4350);

    const Mesh cube = read_stl(data("20mm-xyz-cube.stl"));
    CHECK(cube.triangle_count() == 260);
    CHECK(cube.vertex_count() == 132);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = 0; i < cube.positions.size(); ++i) {
        lo[i % 3] = std::min(lo[i % 3], cube.positions[i]);
        hi[i % 3] = std::max(hi[i % 3], cube.positions[i]);
    }
    CHECK(lo[0] == Approx(-47.9519).margin(1e-4));
    CHECK(hi[1] == Approx(15.0920).margin(1e-4));
    CHECK(hi[2] == Approx(-10.9815).margin(1e-4));
    for (const Mesh* m : {&sphere, &torus, &cube}) {
        const MeshTopology topo = analyze_topology(*m);
        CHECK(topo.closed());
    }
}

TEST_CASE("stl: ASCII reads to the same welded mesh", "[io][stl]") {
    Scratch s;
    const Mesh binary = read_stl(data("unit_sphere.stl"));
    const Mesh ascii = read_stl(s.file("sphere.stl", to_ascii(binary)));
    CHECK(ascii.triangle_count() == 1280);
    CHECK(ascii.vertex_count() == 642);
    CHECK(ascii.indices == binary.indices);
    CHECK(ascii.positions == binary.positions);

    // Uppercase keywords, CRLF, several solids, a signed exponent.
    const Mesh two = read_stl(s.file("two.stl", "SOLID a\r\nFACET NORMAL 0 0 1\r\nOUTER LOOP\r\nVERTEX 0 0 0\r\n"
                                                "VERTEX 1 0 0\r\nVERTEX 0 1 +0\r\nENDLOOP\r\nENDFACET\r\nENDSOLID a\r\n"
                                                "solid b\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1e+0 1 0\n"
                                                "vertex 0 1 -0\nendloop\nendfacet\nendsolid\n"));
    CHECK(two.triangle_count() == 2);
    CHECK(two.vertex_count() == 4);  // -0 and +0 weld
}

// Found by a differential review: a lone '\r' (classic Mac OS) did not end the solid's name,
// which then ran over the whole file; a UTF-8 byte order mark hid "solid".
TEST_CASE("stl: ASCII lines ending in a lone CR, and a byte order mark, read as with LF", "[io][stl]") {
    Scratch s;
    const std::string lf = "solid My Part facet 1\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                           "vertex 0 1 0\nendloop\nendfacet\nendsolid My Part\nsolid\nendsolid\n";
    const Mesh expected = read_stl(s.file("lf.stl", lf));
    REQUIRE(expected.triangle_count() == 1);
    std::string cr = lf, crlf;
    for (char& c : cr)
        if (c == '\n') c = '\r';
    for (char c : lf) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    for (const std::string& text : {cr, crlf, "\xEF\xBB\xBF" + lf, "\xEF\xBB\xBF" + cr}) {
        const Mesh m = read_stl(s.file("other.stl", text));
        CHECK(m.positions == expected.positions);
        CHECK(m.indices == expected.indices);
    }
    // Errors count lone-CR lines too.
    const std::string path = s.file("bad.stl", "solid x\rfacet normal 0 0 1\router loop\rvertex 0 0 zero\r");
    CHECK_THROWS_WITH(read_stl(path), Contains("ASCII STL line 4: 'zero' is not a number"));
}

TEST_CASE("stl: bad files are errors naming the file", "[io][stl][errors]") {
    Scratch s;
    auto fails = [&](const std::string& name, const std::string& bytes, const std::string& what) {
        const std::string path = s.file(name, bytes);
        CHECK_THROWS_WITH(read_stl(path), Contains(path) && Contains(what));
    };
    std::string binary = iotest::read_file(data("unit_sphere.stl"));
    std::string more = binary;
    const std::uint32_t huge = 0x7fffffff;
    std::memcpy(more.data() + 80, &huge, 4);
    fails("count.stl", more, "2147483647 triangles");
    fails("short.stl", binary.substr(0, binary.size() - 10), "but the file has");
    std::string torus = iotest::read_file(data("torus.stl"));
    fails("torus_cut.stl", torus.substr(0, 5000), "ASCII STL line");  // "solid" header, broken binary
    fails("garbage.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zero\n", "'zero' is not a number");
    fails("garbage.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 0 0\nvertex 0 0 0\n"
                         "vertex 1 1 1\nendloop\nendfacet\nendsolid\n",
          "expected 'endloop'");
    fails("garbage.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "expected 'vertex', found end of file");
    fails("garbage.stl", "solid x\nhello\n", "expected 'facet' or 'endsolid'");
    fails("garbage.stl", "solid x\n", "ends inside a solid");
    // Binary bytes in a token are shown as '?': a NUL used to cut the message short.
    const char nul[] = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 0 0\nvertex 1 1 1\n"
                       "end\0loop\nendfacet\nendsolid\n";
    fails("nul.stl", std::string(nul, sizeof nul - 1), "found 'end?loop' (as binary STL");
    fails("garbage.stl", "\x01\x02 random bytes", "not an STL file");
    fails("nan.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\nvertex 0 0 0\nvertex 1 1 1\n"
                     "endloop\nendfacet\nendsolid\n",
          "non-finite");
    fails("empty.stl", "", "empty");
    std::filesystem::create_directory(s.dir + "/dir.stl");
    CHECK_THROWS_WITH(read_stl(s.dir + "/dir.stl"), Contains("dir.stl") && Contains("directory"));
    CHECK_THROWS_WITH(read_stl(s.dir + "/missing.stl"), Contains("missing.stl") && Contains("does not exist"));
}

TEST_CASE("stl: ASCII numbers beyond float range are errors, underflow reads as zero", "[io][stl][errors]") {
    Scratch s;
    auto triangle = [](const std::string& z) {
        return "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 " + z +
               "\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n";
    };
    for (const char* big : {"1e39", "-1e39", "+3.5e38", "1e400", "0.00001e44", "123456789e31"}) {
        const std::string path = s.file("big.stl", triangle(big));
        const std::string shown = big[0] == '+' ? big + 1 : big;  // the reader drops a leading '+'
        CHECK_THROWS_WITH(read_stl(path), Contains(path) && Contains("'" + shown + "'") &&
                                              Contains("beyond the range of float"));
    }
    for (const char* tiny : {"1e-50", "-1e-50", "1e-400", "0.0001e-44", "1000e-49"}) {
        INFO(tiny);
        const Mesh m = read_stl(s.file("tiny.stl", triangle(tiny)));
        REQUIRE(m.vertex_count() == 3);
        CHECK(m.positions[2] == 0.0f);
        CHECK_FALSE(std::signbit(m.positions[2]));  // -0 welds to +0
    }
    // Denormals and the largest float still read as themselves.
    CHECK(read_stl(s.file("denormal.stl", triangle("1e-40"))).positions[2] == 1e-40f);
    CHECK(read_stl(s.file("max.stl", triangle("3.4028234e38"))).positions[2] == FLT_MAX);
    CHECK_THROWS_WITH(read_stl(s.file("junk.stl", triangle("1e39x"))), Contains("'1e39x' is not a number"));
}
