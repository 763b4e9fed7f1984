// Sculpting: stroke scripts, the stroke runner, the built-in path and the benchmark driver.
#include <catch2/catch.hpp>

#include <voxmesh/sculpt.hpp>
#include "core/parallel.hpp"
#include <algorithm>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace {

std::vector<voxmesh::ScriptDab> parse(const std::string& text) {
    std::istringstream in(text);
    return voxmesh::parse_stroke_script(in, "s.txt");
}

}  // namespace

TEST_CASE("sculpt strokes: parsing", "[sculpt]") {
    const auto dabs = parse(
        "# a stroke\n"
        "\n"
        "add 1 2 3 4 0.5\n"
        "   subtract  -1.5 2e1 +3 8 1   # trailing comment\n"
        "units world\n"
        "smooth 0 0 0 2 0.25\n"
        "set 5 5 5 1 -2\n"
        "units samples\n"
        "add 0 0 0 1 1\n");
    REQUIRE(dabs.size() == 5);
    CHECK(dabs[0].dab.op == voxmesh::BrushOp::Add);
    CHECK(dabs[0].line == 3);
    CHECK(dabs[0].dab.center == std::array<double, 3>{1, 2, 3});
    CHECK(dabs[0].dab.radius == 4);
    CHECK(dabs[0].dab.strength == 0.5);
    CHECK(dabs[0].units == voxmesh::Units::Samples);
    CHECK(dabs[1].dab.op == voxmesh::BrushOp::Subtract);
    CHECK(dabs[1].dab.center == std::array<double, 3>{-1.5, 20, 3});
    CHECK(dabs[2].dab.op == voxmesh::BrushOp::Smooth);
    CHECK(dabs[2].units == voxmesh::Units::World);
    CHECK(dabs[3].dab.op == voxmesh::BrushOp::Set);
    CHECK(dabs[3].dab.strength == -2);
    CHECK(dabs[4].units == voxmesh::Units::Samples);
    CHECK(dabs[4].line == 9);
    CHECK(parse("").empty());
    CHECK(parse("# only\n   \n").empty());
}

TEST_CASE("sculpt strokes: errors name the line", "[sculpt]") {
    REQUIRE_THROWS_WITH(parse("add 1 2 3 4 1\ncarve 1 2 3 4 1\n"), Catch::Contains("s.txt:2:") && Catch::Contains("carve"));
    REQUIRE_THROWS_WITH(parse("\n\nadd 1 2 3 4\n"), Catch::Contains("s.txt:3:") && Catch::Contains("5 fields"));
    REQUIRE_THROWS_WITH(parse("add 1 2 3 4 1 9\n"), Catch::Contains("s.txt:1:"));
    REQUIRE_THROWS_WITH(parse("add 1 two 3 4 1\n"), Catch::Contains("s.txt:1:") && Catch::Contains("'two'"));
    REQUIRE_THROWS_WITH(parse("add 1 2 3 0 1\n"), Catch::Contains("radius must be positive"));
    REQUIRE_THROWS_WITH(parse("add 1 2 3 -4 1\n"), Catch::Contains("radius must be positive"));
    REQUIRE_THROWS_WITH(parse("add 1 2 3 4 inf\n"), Catch::Contains("s.txt:1:"));
    REQUIRE_THROWS_WITH(parse("add 1 2 3 4 nan\n"), Catch::Contains("s.txt:1:"));
    // A control byte is refused by its value: quoted in a message, a NUL cut it short.
    REQUIRE_THROWS_WITH(parse(std::string("add 1 2 3 4 1\nbogus\0line 1 2 3 4 1\n", 35)),
                        Catch::Equals("s.txt:2: control byte 0x00 in the script (not a text file?)"));
    REQUIRE_THROWS_WITH(parse("add 1 2 3 4 1\x1b[0m\n"), Catch::Contains("s.txt:1: control byte 0x1b"));
    REQUIRE_THROWS_WITH(parse("# \x7f\n"), Catch::Contains("control byte 0x7f"));
    CHECK(parse("add\t1 2 3 4 1\r\n").size() == 1);  // tabs and CRLF line ends are text
    REQUIRE_THROWS_WITH(parse("add 1 2 3 4 1e999\n"), Catch::Contains("s.txt:1:"));
    REQUIRE_THROWS_WITH(parse("units parsecs\n"), Catch::Contains("s.txt:1:") && Catch::Contains("units"));
    REQUIRE_THROWS_WITH(voxmesh::read_stroke_script("/nonexistent/strokes.txt"), Catch::Contains("/nonexistent/strokes.txt"));
    // Found by a review: "+-3" was read as -3, an out-of-range number was "not a number", a
    // byte order mark made the first op unknown, a directory was a "read error".
    REQUIRE_THROWS_WITH(parse("add +-3 1 1 1 1\n"), Catch::Equals("s.txt:1: coordinate '+-3' is not a number"));
    REQUIRE_THROWS_WITH(parse("add ++3 1 1 1 1\n"), Catch::Equals("s.txt:1: coordinate '++3' is not a number"));
    REQUIRE_THROWS_WITH(parse("add 1e400 1 1 1 1\n"),
                        Catch::Equals("s.txt:1: coordinate '1e400' is out of range (too large or too small for a double)"));
    REQUIRE_THROWS_WITH(parse("add 1 1 1 1e-400 1\n"), Catch::Contains("radius '1e-400' is out of range"));
    const auto bom = parse("\xEF\xBB\xBF" "add 1 2 3 4 1\n");
    REQUIRE(bom.size() == 1);
    CHECK(bom[0].dab.op == voxmesh::BrushOp::Add);
    REQUIRE_THROWS_WITH(parse("add 1 2 3 4 1\n\xEF\xBB\xBF" "add 1 2 3 4 1\n"), Catch::Contains("s.txt:2: unknown op"));
    REQUIRE_THROWS_WITH(voxmesh::read_stroke_script("/tmp"), Catch::Equals("'/tmp': is a directory, not a stroke script"));
}

TEST_CASE("sculpt strokes: run_stroke_script applies every dab and reports frames", "[sculpt]") {
    char dir[] = "/tmp/voxmesh-sculpt-XXXXXX";
    REQUIRE(mkdtemp(dir) != nullptr);
    const std::string path = std::string(dir) + "/strokes.txt";
    {
        std::ofstream out(path);
        out << "# carve and build\nsubtract 20 20 34 6 3\nadd 20 20 6 5 2\nsmooth 20 20 34 6 1\n"
               "set -5 -5 -5 2 1\n"  // outside: clipped away
               "add 100 100 100 3 1\n";
    }
    voxmesh::SculptOptions o;
    o.block_size = 8;
    voxmesh::Sculpt s = voxmesh::make_sculpt_sphere(40, o);
    s.update();
    std::vector<voxmesh::StrokeFrame> frames;
    voxmesh::run_stroke_script(s, path, [&](const voxmesh::StrokeFrame& f) { frames.push_back(f); });
    std::remove(path.c_str());
    rmdir(dir);
    REQUIRE(frames.size() == 5);
    for (std::size_t i = 0; i < frames.size(); ++i) {
        CHECK(frames[i].frame == i);
        CHECK(frames[i].update_seconds >= 0);
    }
    CHECK(frames[0].dab.line == 2);
    CHECK(frames[0].blocks_changed > 0);
    CHECK(frames[3].blocks_remeshed == 0);
    CHECK(frames[4].blocks_remeshed == 0);
    voxmesh::Options eo;
    eo.backend = voxmesh::Backend::Cpu;
    const voxmesh::Mesh want = voxmesh::extract(s.view(), eo);
    REQUIRE(s.mesh().indices == want.indices);
    REQUIRE(voxmesh::analyze_topology(want).closed());
}

TEST_CASE("sculpt strokes: the built-in path winds over the sphere model", "[sculpt]") {
    const auto path = voxmesh::builtin_stroke_path(300, {256, 256, 256});
    REQUIRE(path.size() == 300);
    int ops[4] = {0, 0, 0, 0};
    for (const auto& d : path) {
        const double dx = d.dab.center[0] - 127.5, dy = d.dab.center[1] - 127.5, dz = d.dab.center[2] - 127.5;
        CHECK(std::abs(std::sqrt(dx * dx + dy * dy + dz * dz) - 0.35 * 256) < 1e-6);
        CHECK(d.dab.radius >= 8 - 1e-9);
        CHECK(d.dab.radius <= 16 + 1e-9);
        ++ops[static_cast<int>(d.dab.op)];
    }
    CHECK(ops[0] > 50);
    CHECK(ops[1] > 50);
    CHECK(ops[2] == 60);
    REQUIRE_THROWS_AS(voxmesh::builtin_stroke_path(0, {64, 64, 64}), voxmesh::Error);
    // Too few samples to sculpt: an error naming the dims, not centres near 2^63 (dims - 1 wrapped).
    REQUIRE_THROWS_WITH(voxmesh::builtin_stroke_path(10, {0, 0, 0}), Catch::Contains("0x0x0"));
    REQUIRE_THROWS_WITH(voxmesh::builtin_stroke_path(10, {64, 1, 64}), Catch::Contains("at least 2 samples"));
    for (const auto& d : voxmesh::builtin_stroke_path(10, {5, 5, 5}))  // small but valid: inside the volume
        for (double c : d.dab.center) CHECK((c >= 0 && c <= 4));
    // Found by a review: counts no vector can hold let std::length_error out, not an Error.
    REQUIRE_THROWS_AS(voxmesh::builtin_stroke_path(SIZE_MAX, {64, 64, 64}), voxmesh::Error);
    REQUIRE_THROWS_AS(voxmesh::make_sculpt_sphere(SIZE_MAX / 2), voxmesh::Error);

    const auto s = voxmesh::summarize_latencies({5, 1, 4, 2, 3});
    CHECK(s.p50 == 3);
    CHECK(s.p95 == 5);
    CHECK(s.max == 5);
    CHECK(s.mean == 3);
    CHECK(voxmesh::summarize_latencies({}).count == 0);
}

namespace {
// A benchmark small enough for a test: an n^3 sphere, blocks of 8, brushes of radius 3..5.
voxmesh::SculptBenchOptions small_benchmark(std::size_t n, std::size_t dabs, unsigned threads, std::size_t extracts) {
    voxmesh::SculptBenchOptions o;
    o.resolution = n;
    o.dabs = dabs;
    o.threads = threads;
    o.block_size = 8;
    o.radius_min = 3;
    o.radius_max = 5;
    o.extract_repeats = extracts;
    return o;
}
}  // namespace

TEST_CASE("sculpt strokes: the benchmark driver runs on a small model", "[sculpt]") {
    const voxmesh::SculptBenchOptions o = small_benchmark(48, 20, 2, 1);
    const auto r = voxmesh::run_sculpt_benchmark(o);
    CHECK(r.update.count == 20);
    CHECK(r.triangles > 0);
    CHECK(r.full_extract_ms > 0);
    CHECK(r.threads == 2);
    CHECK(r.workers == std::min(2u, voxmesh::detail::resolve_threads(0)));
    const std::string text = voxmesh::format_sculpt_benchmark(r);
    CHECK_THAT(text, Catch::Contains("p95"));
    CHECK_THAT(text, Catch::Contains("48^3"));
}

TEST_CASE("sculpt strokes: the benchmark reports the threads asked for and the workers that ran", "[sculpt]") {
    const unsigned cores = voxmesh::detail::resolve_threads(0);
    voxmesh::SculptBenchOptions o = small_benchmark(24, 2, cores + 14, 0);  // the paper's 16-thread row on 2 cores
    const auto r = voxmesh::run_sculpt_benchmark(o);
    CHECK(r.threads == cores + 14);
    CHECK(r.workers == cores);
    CHECK_THAT(voxmesh::format_sculpt_benchmark(r),
               Catch::Contains(std::to_string(cores + 14) + " threads asked for, run on " + std::to_string(cores)));
    o.threads = 0;
    const auto all = voxmesh::run_sculpt_benchmark(o);
    CHECK(all.threads == cores);
    CHECK(all.workers == cores);
}
