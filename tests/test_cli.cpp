// Runs the built `voxmesh` binary on real files and on bad input.
#include <algorithm>
#include <catch2/catch.hpp>

#ifdef VOXMESH_CLI_PATH

#include "support/io_scratch.hpp"
#include "support/mesh_checks.hpp"
#include "support/run_program.hpp"
#include "support/sanitizers.hpp"

#include <voxmesh/io.hpp>
#include <voxmesh/voxmesh.hpp>

#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <string>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::string quote(const std::string& s) { return vmtest::shell_quote(s); }

// A scratch directory per test case, removed afterwards.
struct Scratch {
    fs::path dir;
    Scratch() {
        static int counter = 0;
        dir = fs::temp_directory_path() /
              ("voxmesh-cli-test-" + std::to_string(::getpid()) + "-" + std::to_string(++counter));
        fs::create_directories(dir);
    }
    ~Scratch() {
        std::error_code ec;
        fs::remove_all(dir, ec);
    }
    std::string path(const std::string& name) const { return (dir / name).string(); }
    std::string write(const std::string& name, const std::string& bytes) const {
        std::ofstream(dir / name, std::ios::binary) << bytes;
        return path(name);
    }
};

using Result = vmtest::ProgramResult;

// `env`: NAME=value assignments for the command's environment (the shell's prefix form).
Result run(const Scratch& s, const std::string& args, const std::string& env = "") {
    return vmtest::run_program(VOXMESH_CLI_PATH, args, s.dir.string(), env);
}

std::string data_file(const std::string& name) {
    const fs::path local = fs::path(VOXMESH_TEST_DATA) / name;
    if (fs::exists(local)) return local.string();
    return (fs::path("/work/shared/data") / name).string();
}

// Bad input: exit code 2, a message naming `names`, and no output file left behind.
void expect_rejected(const Scratch& s, const std::string& args, const std::string& names, const std::string& output,
                     const std::string& problem = "") {
    INFO("voxmesh " << args);
    const Result r = run(s, args);
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(names) != std::string::npos);
    if (!problem.empty()) CHECK(r.err.find(problem) != std::string::npos);
    if (!output.empty()) CHECK_FALSE(fs::exists(output));
    // Nor a temporary next to it.
    if (!output.empty() && fs::exists(fs::path(output).parent_path()))
        for (const std::string& name : vmtest::directory_entries(fs::path(output).parent_path().string()))
            CHECK(name.find(fs::path(output).filename().string()) == std::string::npos);
}

std::string f32_bytes(const std::vector<float>& v) {
    std::string s(v.size() * 4, '\0');
    std::memcpy(s.data(), v.data(), s.size());
    return s;
}

std::uint32_t stl_triangles(const std::string& path) {
    const std::string b = iotest::read_file(path);
    std::uint32_t n = 0;
    if (b.size() >= 84) std::memcpy(&n, b.data() + 80, 4);
    return n;
}

}  // namespace

TEST_CASE("cli: help and usage", "[cli]") {
    Scratch s;
    for (const char* sub : {"", "mesh ", "voxelize ", "info ", "devices ", "demo "}) {
        const Result r = run(s, std::string(sub) + "--help");
        INFO(sub);
        CHECK(r.code == 0);
        CHECK(r.out.find("Usage") != std::string::npos);
    }
    CHECK(run(s, "").code == 2);                       // no subcommand
    CHECK(run(s, "frobnicate").code == 2);             // unknown subcommand
    CHECK(run(s, "mesh").code == 2);                   // missing INPUT and -o
    CHECK(run(s, "mesh x.nrrd -o y.stl --backend warp").code == 2);
    CHECK(run(s, "voxelize m.stl -o v.nrrd").code == 2);  // --resolution is required
    // Whole-number options say what is wrong (CLI::Range said "not in range 2 to 4096" of both).
    for (const auto& [value, message] : std::vector<std::pair<std::string, std::string>>{
             {"100.5", "--resolution: '100.5' is not a whole number"},
             {"abc", "--resolution: 'abc' is not a whole number"},
             {"5000", "--resolution: 5000 is out of range (2..4096)"},
             {"-3", "--resolution: -3 is out of range (2..4096)"}}) {
        const Result r = run(s, "voxelize m.stl -o v.nrrd --resolution " + value);
        CHECK(r.code == 2);
        CHECK(r.err.find(message) != std::string::npos);
    }
}

TEST_CASE("cli: mesh a real CT volume", "[cli]") {
    Scratch s;
    const std::string in = data_file("headsq.nrrd"), out = s.path("head.stl");
    const Result r = run(s, "mesh " + quote(in) + " -o " + quote(out) + " --iso 499.5 --backend cpu");
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(r.out.find("57698 triangles") != std::string::npos);
    CHECK(r.out.find("29057 vertices") != std::string::npos);
    // The head touches the volume's border: the surface is cut open there.
    CHECK(r.out.find("open") != std::string::npos);
    CHECK(stl_triangles(out) == 57698);

    // --largest keeps the pieces with the most triangles: what keep_largest_components keeps.
    const voxmesh::Volume head = voxmesh::read_volume(in);
    voxmesh::Options o;
    o.iso = 499.5;
    const voxmesh::Mesh full = voxmesh::extract(head.view(), o);
    for (int count : {1, 3}) {
        const std::string kept = s.path("kept.stl");
        const Result k = run(s, "mesh " + quote(in) + " -o " + quote(kept) + " --iso 499.5 --json --largest " +
                                    std::to_string(count));
        INFO(k.err);
        REQUIRE(k.code == 0);
        CHECK(k.out.find("\"components\": " + std::to_string(count) + ",") != std::string::npos);
        CHECK(k.out.find("\"extracted_triangles\": 57698") != std::string::npos);
        const std::size_t expected = voxmesh::keep_largest_components(full, static_cast<std::size_t>(count)).triangle_count();
        CHECK(expected < 57698);
        CHECK(stl_triangles(kept) == expected);
    }
    CHECK(run(s, "mesh " + quote(in) + " -o " + quote(out) + " --largest 0").code == 2);

    const std::string ply = s.path("head.ply");
    const Result j = run(s, "mesh " + quote(in) + " -o " + quote(ply) + " --json --threads 2 --no-normals");
    REQUIRE(j.code == 0);
    CHECK(j.out.front() == '{');
    CHECK(j.out.find("\"iso_source\": \"default: midpoint of value range 0..3926\"") != std::string::npos);
    CHECK(j.out.find("\"iso\": 1963") != std::string::npos);
    CHECK(j.out.find("\"closed\": false") != std::string::npos);
    CHECK(fs::file_size(ply) > 0);

    const Result info = run(s, "info " + quote(in));
    REQUIRE(info.code == 0);
    CHECK(info.out.find("64x64x93") != std::string::npos);
    CHECK(info.out.find("i16") != std::string::npos);
    CHECK(info.out.find("3.2 3.2 1.5") != std::string::npos);
    CHECK(info.out.find("0 .. 3926") != std::string::npos);
}

TEST_CASE("cli: voxelize then mesh round trip on a real STL", "[cli]") {
    Scratch s;
    const std::string vol = s.path("torus.nrrd"), mesh = s.path("torus.obj");
    const Result v = run(s, "voxelize " + quote(data_file("torus.stl")) + " -o " + quote(vol) + " --resolution 48");
    INFO(v.err);
    REQUIRE(v.code == 0);
    const Result m = run(s, "mesh " + quote(vol) + " -o " + quote(mesh) + " --iso 0");
    INFO(m.err);
    REQUIRE(m.code == 0);
    CHECK(m.out.find("closed (euler 0)") != std::string::npos);  // a torus: genus 1

    const std::string occ = s.path("cube.nrrd"), cube = s.path("cube.stl");
    REQUIRE(run(s, "voxelize " + quote(data_file("20mm-xyz-cube.stl")) + " -o " + quote(occ) +
                       " --resolution 24 --padding 1 --field occupancy")
                .code == 0);
    const Result c = run(s, "mesh " + quote(occ) + " -o " + quote(cube));  // default iso: 127.5
    REQUIRE(c.code == 0);
    CHECK(c.out.find("iso 127.5 (default") != std::string::npos);
    CHECK(c.out.find("closed (euler 2)") != std::string::npos);

    // Raw input with the layout on the command line.
    std::vector<float> ball(16 * 16 * 16);
    for (int z = 0; z < 16; ++z)
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x)
                ball[x + 16 * (y + 16 * z)] = 5.f - std::sqrt(float((x - 7.5) * (x - 7.5) + (y - 7.5) * (y - 7.5) + (z - 7.5) * (z - 7.5)));
    const std::string raw = s.write("ball.raw", f32_bytes(ball));
    const Result b = run(s, "mesh " + quote(raw) + " -o " + quote(s.path("ball.stl")) +
                                " --dims 16 16 16 --type f32 --iso 0 --spacing 0.5 0.5 0.5");
    INFO(b.err);
    REQUIRE(b.code == 0);
    CHECK(b.out.find("closed (euler 2)") != std::string::npos);
    CHECK(run(s, "info " + quote(raw) + " --dims 16 16 16 --type f32").code == 0);

    // The same samples piped in ("-"): the same mesh, byte for byte.
    const std::string piped = s.path("piped.stl");
    const std::string cat = "cat " + quote(raw) + " | " + quote(VOXMESH_CLI_PATH) + " mesh - -o " + quote(piped) +
                            " --dims 16 16 16 --type f32 --iso 0 --spacing 0.5 0.5 0.5 > /dev/null 2>&1";
    const int status = std::system(cat.c_str());
    REQUIRE(WIFEXITED(status));
    REQUIRE(WEXITSTATUS(status) == 0);
    CHECK(iotest::read_file(piped) == iotest::read_file(s.path("ball.stl")));
    // A pipe that ends early, or goes on too long, is refused; nothing is written.
    for (const std::string& cut : {std::string("head -c 16000 "), std::string("cat ") + quote(raw) + " "}) {
        const std::string bad = cut + quote(raw) + " | " + quote(VOXMESH_CLI_PATH) + " mesh - -o " +
                                quote(s.path("cut.stl")) + " --dims 16 16 16 --type f32 > /dev/null 2> " +
                                quote(s.path("cut.err"));
        const int code = std::system(bad.c_str());
        INFO(bad << ": " << iotest::read_file(s.path("cut.err")));
        CHECK((WIFEXITED(code) && WEXITSTATUS(code) == 2));
        CHECK_THAT(iotest::read_file(s.path("cut.err")), Catch::Contains("standard input"));
        CHECK_FALSE(fs::exists(s.path("cut.stl")));
    }
}

// A thin model's distance field is not symmetric about 0 (the inside never reaches the band's
// depth), so the value range's midpoint moved the surface: a plate 0.05 thick came back 0.081
// in volume. voxelize records the iso its field is meshed at, and mesh takes it.
TEST_CASE("cli: mesh takes the iso voxelize recorded in the file", "[cli]") {
    Scratch s;
    const std::string plate = s.write("plate.obj",
                                      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 0.05\nv 1 0 0.05\nv 1 1 0.05\nv 0 1 0.05\n"
                                      "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                                      "f 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n");
    const auto volume_of = [&](const std::string& mesh) {
        const Result info = run(s, "info " + quote(mesh));
        const std::size_t at = info.out.find("volume:");
        REQUIRE(at != std::string::npos);
        return std::stod(info.out.substr(at + 7));
    };
    for (const char* field : {"distance", "occupancy"}) {
        INFO(field);
        const std::string vol = s.path(std::string(field) + ".nrrd"), out = s.path(std::string(field) + ".stl");
        REQUIRE(run(s, "voxelize " + quote(plate) + " -o " + quote(vol) + " --resolution 64 --field " + field).code == 0);
        CHECK_THAT(iotest::read_file(vol), Catch::Contains(std::string("\nvoxmesh_iso:=") +
                                                            (field == std::string("distance") ? "0" : "127.5") + "\n"));
        const Result m = run(s, "mesh " + quote(vol) + " -o " + quote(out));
        INFO(m.err);
        REQUIRE(m.code == 0);
        CHECK(m.out.find("(default: the file's voxmesh_iso)") != std::string::npos);
        CHECK_THAT(run(s, "info " + quote(vol)).out,
                   Catch::Contains(std::string("iso:       ") + (field == std::string("distance") ? "0" : "127.5") +
                                   " (voxmesh_iso"));
        // Occupancy has no sub-voxel position: its surface is the staircase's (about 0.062).
        if (field == std::string("distance")) CHECK(volume_of(out) == Approx(0.05).epsilon(0.03));
    }
    // --iso wins over the file's; a recorded iso that is not a number is refused, naming it.
    const std::string vol = s.path("distance.nrrd");
    const Result given = run(s, "mesh " + quote(vol) + " -o " + quote(s.path("given.stl")) + " --iso -0.01");
    CHECK(given.out.find("; iso -0.01;") != std::string::npos);
    const voxmesh::Volume field = voxmesh::read_volume(vol);
    for (const char* bad : {"zero", "", "nan", "1e999"}) {
        const std::string path = s.path("bad.nrrd");
        voxmesh::write_nrrd(path, field.view(), {{"voxmesh_iso", bad}});
        expect_rejected(s, "mesh " + quote(path) + " -o " + quote(s.path("bad.stl")), "voxmesh_iso", s.path("bad.stl"),
                        "is not a finite number");
    }
}

// "-" reads standard input in any format the tool reads, told from its first bytes: it is
// copied to a temporary file (TMPDIR) that is gone when the command ends, however it ends.
TEST_CASE("cli: every input format from standard input", "[cli]") {
    Scratch s;
    const std::string tmp = s.path("tmp");
    fs::create_directories(tmp);
    // `producer | voxmesh args`, the tool's temporaries in `tmp`.
    const auto piped = [&](const std::string& producer, const std::string& args) {
        const std::string line = producer + " | TMPDIR=" + quote(tmp) + " " + quote(VOXMESH_CLI_PATH) + " " + args;
        return vmtest::run_program("sh", "-c " + quote(line), s.dir.string());
    };
    const auto cat = [&](const std::string& file) { return "cat " + quote(file); };

    // Volumes: the same mesh as from the file, byte for byte.
    const std::string head = data_file("headsq.nrrd");
    REQUIRE(run(s, "mesh " + quote(head) + " -o " + quote(s.path("a.stl")) + " --iso 499.5").code == 0);
    const Result m = piped(cat(head), "mesh - -o " + quote(s.path("b.stl")) + " --iso 499.5");
    INFO(m.out << m.err);
    REQUIRE(m.code == 0);
    CHECK(m.out.rfind("standard input -> ", 0) == 0);
    CHECK(iotest::read_file(s.path("a.stl")) == iotest::read_file(s.path("b.stl")));
    const Result nii = piped(cat(data_file("mri_someones_anatomy.nii.gz")), "info -");
    CHECK(nii.code == 0);
    CHECK(nii.out.find("file:      standard input") != std::string::npos);
    CHECK(nii.out.find("57x67x56") != std::string::npos);
    const std::string mha = s.write("v.mha", "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nElementType = MET_UCHAR\n"
                                             "ElementDataFile = LOCAL\n" + std::string(24, '\x07'));
    const Result meta = piped(cat(mha), "info -");
    CHECK(meta.code == 0);
    CHECK(meta.out.find("4x3x2") != std::string::npos);
    CHECK(meta.out.find("range:     7 .. 7") != std::string::npos);
    const std::string vtk = std::string(VOXMESH_TEST_DATA) + "/../fuzz_corpus/vtk/i16_binary.vtk";  // VTK's own
    const Result legacy_vtk = piped(cat(vtk), "info -");
    CHECK(legacy_vtk.code == 0);
    CHECK(legacy_vtk.out.find("format:    vtk (raw, big endian)") != std::string::npos);
    CHECK(legacy_vtk.out.find("range:     -100 .. 61") != std::string::npos);
    // Text samples have no byte order: none is shown (it said "little endian").
    const Result ascii_vtk = piped(cat(std::string(VOXMESH_TEST_DATA) + "/../fuzz_corpus/vtk/i16_ascii.vtk"), "info -");
    CHECK(ascii_vtk.code == 0);
    CHECK(ascii_vtk.out.find("format:    vtk (ascii)\n") != std::string::npos);
    const std::string npy = std::string(VOXMESH_TEST_DATA) + "/../fuzz_corpus/npy/i2_big_c.npy";  // numpy's own
    const Result numpy_file = piped(cat(npy), "info -");
    CHECK(numpy_file.code == 0);
    CHECK(numpy_file.out.find("format:    npy (raw, big endian)") != std::string::npos);
    CHECK(numpy_file.out.find("5x4x3") != std::string::npos);
    CHECK(numpy_file.out.find("range:     -100 .. 145") != std::string::npos);
    const Result nii_plain = piped("gunzip -c " + quote(data_file("mri_someones_anatomy.nii.gz")), "info -");
    CHECK(nii_plain.code == 0);
    CHECK(nii_plain.out.find("57x67x56") != std::string::npos);
    const std::string ascii_stl = s.write("t.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                                   "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n");
    const Result ascii = piped(cat(ascii_stl), "info -");
    CHECK(ascii.code == 0);
    CHECK(ascii.out.find("triangles: 1\n") != std::string::npos);
    // Found by a review: the VTK reader takes its version line in any case, standard input did not.
    const Result lower_vtk = piped("printf '# vtk datafile version 3.0\\nx\\nASCII\\nDATASET STRUCTURED_POINTS\\n"
                                   "DIMENSIONS 2 2 2\\nPOINT_DATA 8\\nSCALARS s float\\nLOOKUP_TABLE default\\n"
                                   "0 1 2 3 4 5 6 7\\n'",
                                   "info -");
    CHECK(lower_vtk.code == 0);
    CHECK(lower_vtk.out.find("2x2x2") != std::string::npos);
    const Result raw = piped("head -c 24 /dev/zero", "info - --dims 2 3 4 --type u8");
    CHECK(raw.code == 0);
    CHECK(raw.out.find("2x3x4") != std::string::npos);

    // Models: STL (binary), PLY and OBJ as the tool writes them.
    for (const char* ext : {".ply", ".obj"})
        REQUIRE(run(s, "mesh " + quote(head) + " -o " + quote(s.path(std::string("a") + ext)) + " --iso 499.5").code == 0);
    for (const char* name : {"a.stl", "a.ply", "a.obj"}) {
        INFO(name);
        const Result info = piped(cat(s.path(name)), "info -");
        CHECK(info.code == 0);
        CHECK(info.out.find("triangles: 57698") != std::string::npos);
    }
    const std::string torus = data_file("torus.stl");
    REQUIRE(run(s, "voxelize " + quote(torus) + " -o " + quote(s.path("t1.nrrd")) + " --resolution 24").code == 0);
    CHECK(piped(cat(torus), "voxelize - -o " + quote(s.path("t2.nrrd")) + " --resolution 24").code == 0);
    CHECK(iotest::read_file(s.path("t1.nrrd")) == iotest::read_file(s.path("t2.nrrd")));
    const Result sculpt = piped("printf 'add 10 10 5 3 1\\n'", "sculpt " + quote(torus) + " --resolution 24 --strokes - -o " +
                                                                  quote(s.path("s.ply")));
    CHECK(sculpt.code == 0);
    CHECK(sculpt.out.find("1 dabs re-meshed") != std::string::npos);

    // Refused, naming standard input, never the temporary copy.
    const struct {
        std::string producer, args, names;
    } refused[] = {
        {"echo hello", "info -", "not a volume (NRRD, NIfTI-1, MetaImage .mha, legacy VTK, NumPy .npy) or a model"},
        {"echo hello", "mesh - -o " + quote(s.path("x.stl")), "not a volume"},
        {"printf ''", "voxelize - -o " + quote(s.path("x.nrrd")) + " --resolution 8", "is empty"},
        {"head -c 2000 " + quote(head), "mesh - -o " + quote(s.path("x.stl")), "ends early"},
        {"printf 'NRRD0004\\ntype: uint8\\ndimension: 3\\nsizes: 4 4 4\\nencoding: raw\\ndata file: v.raw\\n\\n'",
         "info -", "separate data file ('v.raw')"},
        {cat(torus), "sculpt - --resolution 16 --strokes - -o " + quote(s.path("x.ply")), "cannot both be standard input"},
        {"printf 'bogus 1 2\\n'", "sculpt " + quote(torus) + " --resolution 16 --strokes - -o " + quote(s.path("x.ply")),
         "standard input:1: unknown op 'bogus'"},
    };
    for (const auto& r : refused) {
        const Result bad = piped(r.producer, r.args);
        INFO(r.producer << " | voxmesh " << r.args << ": " << bad.err);
        CHECK(bad.code == 2);
        CHECK(bad.err.find(r.names) != std::string::npos);
        CHECK(bad.err.find("standard input") != std::string::npos);
        CHECK(bad.err.find("voxmesh-stdin") == std::string::npos);
    }
    // A directory as standard input: the reading fails, not the copy (which was named).
    const Result directory = vmtest::run_program(
        "sh", "-c " + quote("TMPDIR=" + quote(tmp) + " " + quote(VOXMESH_CLI_PATH) + " mesh - -o " +
                            quote(s.path("x.stl")) + " < " + quote(s.dir.string())),
        s.dir.string());
    CHECK(directory.code == 2);
    CHECK_THAT(directory.err, Catch::Contains("cannot read standard input: Is a directory"));
    CHECK(directory.err.find("voxmesh-stdin") == std::string::npos);
    CHECK_FALSE(fs::exists(s.path("x.stl")));
    CHECK(fs::is_empty(tmp));  // no copy of standard input left behind
}

// Killed while it copies standard input (a pipe still open, more to come), the tool removes
// the copy: a signal handler, not a destructor, is what runs then.
TEST_CASE("cli: killed while reading standard input, no copy of it is left", "[cli]") {
    Scratch s;
    const std::string tmp = s.path("tmp");
    fs::create_directories(tmp);
    int pipe_fds[2];
    REQUIRE(::pipe2(pipe_fds, O_CLOEXEC) == 0);
    const vmtest::StartedProgram run =
        vmtest::start_program(VOXMESH_CLI_PATH, {"info", "-"}, s.dir.string(), pipe_fds[0], {"TMPDIR=" + tmp});
    ::close(pipe_fds[0]);
    REQUIRE(::write(pipe_fds[1], "NRRD0004\n", 9) == 9);
    bool copying = false;  // the copy appears once the tool has started reading
    for (int i = 0; i < 2000 && !copying; ++i) {
        copying = !fs::is_empty(tmp);
        if (!copying) ::usleep(5000);
    }
    CHECK(copying);
    ::kill(run.pid, SIGTERM);
    const int status = vmtest::wait_program(run);
    ::close(pipe_fds[1]);
    CHECK(WIFSIGNALED(status));
    CHECK(WTERMSIG(status) == SIGTERM);
    CHECK(fs::is_empty(tmp));
}

// "-o -" writes the output to standard output (the report goes to standard error): the same
// bytes as the file, so commands chain.
TEST_CASE("cli: outputs to standard output", "[cli]") {
    Scratch s;
    const std::string head = quote(data_file("headsq.nrrd")), torus = quote(data_file("torus.stl"));
    for (const char* format : {"stl", "ply", "obj", "glb"}) {
        INFO(format);
        const std::string file = s.path(std::string("f.") + format);
        REQUIRE(run(s, "mesh " + head + " -o " + quote(file) + " --iso 499.5").code == 0);
        const Result piped = run(s, "mesh " + head + " -o - --format " + format + " --iso 499.5");
        INFO(piped.err);
        REQUIRE(piped.code == 0);
        CHECK(piped.err.find(" -> standard output: 29057 vertices") != std::string::npos);
        CHECK(piped.out == iotest::read_file(file));
    }
    REQUIRE(run(s, "voxelize " + torus + " -o " + quote(s.path("t.nrrd")) + " --resolution 24").code == 0);
    const Result volume = run(s, "voxelize " + torus + " -o - --resolution 24");
    CHECK(volume.code == 0);
    CHECK(volume.out == iotest::read_file(s.path("t.nrrd")));
    REQUIRE(run(s, "sculpt " + torus + " --resolution 24 -o " + quote(s.path("sc.ply"))).code == 0);
    const Result sculpted = run(s, "sculpt " + torus + " --resolution 24 -o - --format ply");
    CHECK(sculpted.code == 0);
    CHECK(sculpted.out == iotest::read_file(s.path("sc.ply")));

    // Chained: voxelize | mesh | info.
    const std::string cli = quote(VOXMESH_CLI_PATH);
    const Result chain = vmtest::run_program(
        "sh", "-c " + quote(cli + " voxelize " + torus + " -o - --resolution 24 | " + cli + " mesh - -o - --format stl | " +
                            cli + " info -"),
        s.dir.string());
    INFO(chain.err);
    CHECK(chain.code == 0);
    CHECK(chain.out.find("closed (every edge in two triangles), euler 0") != std::string::npos);

    // --format only with -o -, and -o - only with it.
    const Result no_format = run(s, "mesh " + head + " -o -");
    CHECK(no_format.code == 2);
    CHECK(no_format.err.find("needs --format") != std::string::npos);
    const Result stray = run(s, "mesh " + head + " -o " + quote(s.path("x.stl")) + " --format ply");
    CHECK(stray.code == 2);
    CHECK(stray.err.find("--format applies only to -o -") != std::string::npos);
    CHECK_FALSE(fs::exists(s.path("x.stl")));
}

TEST_CASE("cli: info reports an axis stored in the negative direction", "[cli]") {
    Scratch s;
    const std::vector<float> samples(4 * 3 * 2, 1.f);
    const std::string flipped = s.write("flip.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 3 2\n"
                                                     "endian: little\nencoding: raw\nspace: left-posterior-superior\n"
                                                     "space directions: (-2,0,0) (0,1,0) (0,0,1)\n"
                                                     "space origin: (10,20,30)\n\n" + f32_bytes(samples));
    const Result info = run(s, "info " + quote(flipped));
    INFO(info.out << info.err);
    REQUIRE(info.code == 0);
    CHECK(info.out.find("flipped:   x (stored in the negative direction") != std::string::npos);
    CHECK(info.out.find("origin:    4 20 30") != std::string::npos);  // the minimum corner: 10 - 2 * 3
    CHECK(info.out.find("rotation:") == std::string::npos);

    const std::string rotated = s.write("rot.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 3 2\n"
                                                    "endian: little\nencoding: raw\nspace: left-posterior-superior\n"
                                                    "space directions: (0,1,0) (1,0,0) (0,0,1)\n\n" +
                                                    f32_bytes(samples));
    const Result rot = run(s, "info " + quote(rotated));
    REQUIRE(rot.code == 0);
    CHECK(rot.out.find("rotation:  dropped") != std::string::npos);
    CHECK(rot.out.find("flipped:") == std::string::npos);

    // mesh warns about the dropped rotation (the mesh would otherwise look misplaced silently),
    // and only then.
    const Result mesh_rot = run(s, "mesh " + quote(rotated) + " -o " + quote(s.path("rot.stl")) + " --iso 0.5");
    INFO(mesh_rot.err);
    REQUIRE(mesh_rot.code == 0);
    CHECK(mesh_rot.err.find("rotation is dropped") != std::string::npos);
    const Result mesh_flip = run(s, "mesh " + quote(flipped) + " -o " + quote(s.path("flip.stl")) + " --iso 0.5");
    REQUIRE(mesh_flip.code == 0);
    CHECK(mesh_flip.err.find("rotation") == std::string::npos);
}

namespace {
// A box of 1s (index 1..4 of 6^3) in 0s: at iso 0.5 its faces lie at index 0.5 and 4.5.
std::vector<float> box_of_six() {
    std::vector<float> samples(6 * 6 * 6, 0.f);
    for (std::size_t k = 1; k < 5; ++k)
        for (std::size_t j = 1; j < 5; ++j)
            for (std::size_t i = 1; i < 5; ++i) samples[i + 6 * (j + 6 * k)] = 1.f;
    return samples;
}
}  // namespace

TEST_CASE("cli: mesh --world places the mesh by the file's direction matrix", "[cli]") {
    Scratch s;
    const std::vector<float> samples = box_of_six();
    const std::string head = "NRRD0004\ntype: float\ndimension: 3\nsizes: 6 6 6\nendian: little\nencoding: raw\n"
                             "space: left-posterior-superior\nspace origin: (5,-3,7)\n";
    const std::string rotated =
        s.write("perm.nrrd", head + "space directions: (0,0,2) (1.5,0,0) (0,-1,0)\n\n" + f32_bytes(samples));
    const Result world = run(s, "mesh " + quote(rotated) + " -o " + quote(s.path("w.stl")) + " --iso 0.5 --world --backend cpu");
    INFO(world.err);
    REQUIRE(world.code == 0);
    CHECK(world.err.find("warning") == std::string::npos);  // nothing dropped (--backend cpu: auto warns without OpenCL)
    // Index axis 0 runs along z from 7 in steps of 2, axis 1 along x from 5 by 1.5, axis 2 down y from -3.
    const Result bounds = run(s, "info " + quote(s.path("w.stl")));
    CHECK(bounds.out.find("bounds:    5.75 -7.5 8 .. 11.75 -3.5 16") != std::string::npos);
    CHECK(bounds.out.find("topology:  closed") != std::string::npos);
    CHECK(bounds.out.find("volume:") != std::string::npos);
    CHECK(bounds.out.find("negative: the triangles face inward") == std::string::npos);  // determinant -1, still outward
    const Result plain = run(s, "mesh " + quote(rotated) + " -o " + quote(s.path("p.stl")) + " --iso 0.5");
    REQUIRE(plain.code == 0);
    CHECK(plain.err.find("--world") != std::string::npos);  // the warning says the way on
    const Result info = run(s, "info " + quote(rotated));
    CHECK(info.out.find("world:     sample 0 at 5 -3 7; axes x: 0 0 1, y: 1 0 0, z: 0 -1 0") != std::string::npos);

    // Flips only: --world changes nothing.
    const std::string flipped =
        s.write("flip.nrrd", head + "space directions: (-2,0,0) (0,1.5,0) (0,0,-1)\n\n" + f32_bytes(samples));
    REQUIRE(run(s, "mesh " + quote(flipped) + " -o " + quote(s.path("f1.stl")) + " --iso 0.5 --world").code == 0);
    REQUIRE(run(s, "mesh " + quote(flipped) + " -o " + quote(s.path("f2.stl")) + " --iso 0.5").code == 0);
    CHECK(stl_triangles(s.path("f1.stl")) > 0);
    CHECK(iotest::read_file(s.path("f1.stl")) == iotest::read_file(s.path("f2.stl")));
}

// --world's edge cases: a file whose affine puts the mesh beyond the float range is an error
// naming the file (no inf in the output, none written); directions that do not span 3-D cannot
// be applied, so info and mesh --world say the rotation stays dropped instead of promising it.
TEST_CASE("cli: mesh --world refuses a world beyond floats; unusable directions are said so", "[cli]") {
    Scratch s;
    const std::vector<float> samples = box_of_six();
    const std::string head = "NRRD0004\ntype: float\ndimension: 3\nsizes: 6 6 6\nendian: little\nencoding: raw\n"
                             "space: right-anterior-superior\n";
    // World x of sample (i, j, k): 2.9e38 + 8e36 * i + 6e36 * j, past FLT_MAX at the box's far
    // corner (i = j = 4.5); loaded x stays within 2.9e38 + 8e36 * 5.
    const std::string far = s.write("far.nrrd", head + "space directions: (8e36,0,0) (6e36,8e36,0) (0,0,1)\n"
                                                       "space origin: (2.9e38,0,0)\n\n" + f32_bytes(samples));
    const Result plain = run(s, "mesh " + quote(far) + " -o " + quote(s.path("far.stl")) + " --iso 0.5 --backend cpu");
    INFO(plain.err);
    REQUIRE(plain.code == 0);  // in index axes the grid fits floats
    const Result world = run(s, "mesh " + quote(far) + " -o " + quote(s.path("w.stl")) + " --iso 0.5 --world --backend cpu");
    INFO(world.err);
    CHECK(world.code != 0);
    CHECK(world.err.find("far.nrrd") != std::string::npos);
    CHECK(world.err.find("beyond the range of float") != std::string::npos);
    CHECK_FALSE(fs::exists(s.path("w.stl")));

    // Coplanar directions: axis z along x + y.
    const std::string flat =
        s.write("flat.nrrd", head + "space directions: (1,0,0) (0,1,0) (1,1,0)\n\n" + f32_bytes(samples));
    const Result info = run(s, "info " + quote(flat));
    INFO(info.out);
    REQUIRE(info.code == 0);
    CHECK(info.out.find("rotation:  dropped") != std::string::npos);
    CHECK(info.out.find("do not span 3-D") != std::string::npos);
    CHECK(info.out.find("world:") == std::string::npos);
    const Result flat_world =
        run(s, "mesh " + quote(flat) + " -o " + quote(s.path("f.stl")) + " --iso 0.5 --world --backend cpu");
    INFO(flat_world.err);
    REQUIRE(flat_world.code == 0);
    CHECK(flat_world.err.find("rotation is dropped") != std::string::npos);
}

// The AVX2 row packers, the AVX2/BMI copy of the generator and the batched normals must give
// the portable code's bits (no fused multiply-adds; IEEE divide and square root), for every
// sample type's packer: the [core] tests under VOXMESH_ISA=portable only compare with the
// oracle within a tolerance. On a processor without AVX2 both runs are portable.
TEST_CASE("cli: the AVX2 and portable code paths write identical files", "[cli]") {
    Scratch s;
    std::vector<float> wave(37 * 41 * 43);
    for (int z = 0; z < 43; ++z)
        for (int y = 0; y < 41; ++y)
            for (int x = 0; x < 37; ++x)
                wave[x + 37 * (y + 41 * z)] = std::sin(0.31f * x) * std::cos(0.23f * y) + std::sin(0.17f * z + 0.4f * x) +
                                              0.013f * float((x * 7 + y * 13 + z * 29) % 11);
    const std::string raw = s.write("wave.raw", f32_bytes(wave));
    const std::vector<std::string> inputs = {
        quote(data_file("headsq.nrrd")) + " --iso 499.5",                    // i16, a real CT
        quote(data_file("mri_someones_anatomy.nii.gz")) + " --iso 19.5",     // u8, a real MRI
        quote(raw) + " --dims 37 41 43 --type f32 --iso 0.1 --spacing 0.5 0.75 1.25",
    };
    for (const std::string& input : inputs)
        for (const char* threads : {"1", "2"}) {
            INFO(input << " --threads " << threads);
            const std::string native = s.path("native.ply"), portable = s.path("portable.ply");
            const std::string args = " --backend cpu --threads " + std::string(threads);
            const Result a = run(s, "mesh " + input + " -o " + quote(native) + args);
            INFO(a.err);
            REQUIRE(a.code == 0);
            const Result b = run(s, "mesh " + input + " -o " + quote(portable) + args, "VOXMESH_ISA=portable");
            INFO(b.err);
            REQUIRE(b.code == 0);
            CHECK(a.out.find("triangles") != std::string::npos);
            // Positions and normals bit for bit, and the indices.
            const std::string x = iotest::read_file(native), y = iotest::read_file(portable);
            CHECK(x.size() > 1000);
            CHECK(x.size() == y.size());
            const auto diff = std::mismatch(x.begin(), x.end(), y.begin(), y.end());
            INFO("first differing byte: " << (diff.first - x.begin()) << " of " << x.size());
            CHECK((diff.first == x.end() && diff.second == y.end()));
        }
}

TEST_CASE("cli: bad input exits 2 with a message and leaves no output", "[cli]") {
    Scratch s;
    const std::string out = s.path("out.stl");
    const std::string head = quote(data_file("headsq.nrrd"));

    const std::string truncated = s.write("truncated.raw", std::string(100, '\x01'));
    expect_rejected(s, "mesh " + quote(truncated) + " -o " + quote(out) + " --dims 10 10 10 --type u8", "truncated.raw",
                    out);
    const std::string longer = s.write("longer.raw", std::string(1500, '\x01'));
    expect_rejected(s, "mesh " + quote(longer) + " -o " + quote(out) + " --dims 10 10 10 --type u8", "longer.raw", out);
    expect_rejected(s, "mesh " + quote(longer) + " -o " + quote(out) + " --dims 4294967296 4294967296 4294967296 --type f64",
                    "longer.raw", out);
    expect_rejected(s, "mesh " + quote(longer) + " -o " + quote(out) + " --dims 10 10 15 --type f16", "f16", out);
    expect_rejected(s, "mesh " + quote(longer) + " -o " + quote(out), "longer.raw", out, "--dims");  // raw without layout
    const std::string f16 = s.write("f16.nrrd", "NRRD0004\ntype: float16\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n" +
                                                    std::string(16, '\0'));
    expect_rejected(s, "mesh " + quote(f16) + " -o " + quote(out), "f16.nrrd", out);

    expect_rejected(s, "mesh " + head + " -o " + quote(s.path("missing/dir/out.stl")), "missing/dir", "");
    CHECK_FALSE(fs::exists(s.path("missing")));
    expect_rejected(s, "mesh " + quote(s.dir.string()) + " -o " + quote(out), s.dir.string(), out, "directory");
    const std::string empty = s.write("empty.nrrd", "");
    expect_rejected(s, "mesh " + quote(empty) + " -o " + quote(out), "empty.nrrd", out, "empty");
    expect_rejected(s, "mesh " + quote(s.path("nonexistent.nrrd")) + " -o " + quote(out), "nonexistent.nrrd", out);
    expect_rejected(s, "mesh " + quote(data_file("torus.stl")) + " -o " + quote(out), "torus.stl", out,
                    "voxelize it first");  // a model: the message names the two ways

    std::vector<float> samples(27, 1.0f);
    samples[13] = std::nanf("");
    const std::string nan = s.write("nan.raw", f32_bytes(samples));
    expect_rejected(s, "mesh " + quote(nan) + " -o " + quote(out) + " --dims 3 3 3 --type f32 --iso 0.5", "nan.raw", out,
                    "NaN");

    // Spacing or origin that would put vertices past FLT_MAX (inf in the mesh file).
    const std::string far = s.write("far.nrrd", "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
                                                "spacings: 1e300 1 1\n\n" + std::string(4, '\0') + std::string(4, '\xff'));
    expect_rejected(s, "mesh " + quote(far) + " -o " + quote(out), "far.nrrd", out, "float");
    std::vector<float> ramp(27);
    for (std::size_t i = 0; i < ramp.size(); ++i) ramp[i] = static_cast<float>(i);
    const std::string ramp_raw = s.write("ramp.raw", f32_bytes(ramp));
    expect_rejected(s,
                    "mesh " + quote(ramp_raw) + " -o " + quote(out) +
                        " --dims 3 3 3 --type f32 --origin 0 0 3e38 --spacing 1 1 1e38",
                    "ramp.raw", out, "float");
    // Negative raw spacing is its magnitude, as in headers; it used to fail without naming the file.
    const Result neg = run(s, "mesh " + quote(ramp_raw) + " -o " + quote(out) + " --dims 3 3 3 --type f32 --spacing -1 1 1");
    INFO(neg.err);
    CHECK(neg.code == 0);
    CHECK(stl_triangles(out) > 0);
    fs::remove(out);

    expect_rejected(s, "mesh " + head + " -o " + quote(s.path("out.xyz")), "out.xyz", s.path("out.xyz"), "format");

    // A volume one sample thick: the message names the file, as the readers' do.
    const std::string thin = s.write("thin.nrrd", "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 1 4 4\nencoding: raw\n\n" +
                                                     std::string(16, '\x01'));
    expect_rejected(s, "mesh " + quote(thin) + " -o " + quote(out), "thin.nrrd", out, "dimension x is 1");
    // Values CLI11 would read as 0 or print as a 300-digit range, and an iso no volume reaches.
    expect_rejected(s, "mesh " + head + " -o " + quote(out) + " --iso ''", "--iso", out, "empty value");
    expect_rejected(s, "mesh " + head + " -o " + quote(out) + " --threads ''", "--threads", out, "empty value");
    expect_rejected(s, "mesh " + head + " -o " + quote(out) + " --device -1", "--device", out, "-1 is out of range");
    for (const char* iso : {"inf", "-inf"}) expect_rejected(s, "mesh " + head + " -o " + quote(out) + " --iso " + iso, "--iso", out, "finite");
    expect_rejected(s, "mesh " + head + " -o " + quote(out) + " --iso 1e400", "--iso", out, "out of range of a double");
    {
        const Result r = run(s, "mesh " + head + " -o " + quote(out) + " --device -1");
        CHECK(r.err.size() < 200);
    }
    const std::string odd = s.write("volume.foo", "abc");
    expect_rejected(s, "mesh " + quote(odd) + " -o " + quote(out), "volume.foo", out);
    expect_rejected(s, "info " + quote(empty), "empty.nrrd", "");

    // Voxelize: an open STL (one triangle), garbage, and a wrong output extension.
    std::string tri(84, '\0');
    const std::uint32_t one = 1;
    std::memcpy(tri.data() + 80, &one, 4);
    const float rec[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
    tri.append(reinterpret_cast<const char*>(rec), sizeof rec);
    tri.append(2, '\0');
    const std::string open = s.write("open.stl", tri);
    const std::string vol = s.path("v.nrrd");
    expect_rejected(s, "voxelize " + quote(open) + " -o " + quote(vol) + " --resolution 16", "open.stl", vol, "closed");
    const std::string junk = s.write("junk.stl", "solid junk\nthis is not an stl\n");
    expect_rejected(s, "voxelize " + quote(junk) + " -o " + quote(vol) + " --resolution 16", "junk.stl", vol);
    expect_rejected(s, "voxelize " + quote(data_file("torus.stl")) + " -o " + quote(s.path("v.raw")) + " --resolution 16",
                    "v.raw", s.path("v.raw"));
}

TEST_CASE("cli: killed at any moment, mesh leaves the whole output or none, never a temporary", "[cli]") {
    Scratch s;
    // A dense gyroid: a 70 MB OBJ, so that a good part of the run is spent writing it.
    const std::size_t n = 160;
    std::vector<float> samples;
    samples.reserve(n * n * n);
    for (std::size_t z = 0; z < n; ++z)
        for (std::size_t y = 0; y < n; ++y)
            for (std::size_t x = 0; x < n; ++x)
                samples.push_back(static_cast<float>(std::sin(0.3 * x) * std::cos(0.3 * y) +
                                                     std::sin(0.3 * y) * std::cos(0.3 * z) +
                                                     std::sin(0.3 * z) * std::cos(0.3 * x)));
    const std::string volume = s.write("g.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 160 160 160\n"
                                                 "endian: little\nencoding: raw\n\n" + f32_bytes(samples));
    const std::string args = "mesh " + quote(volume) + " --iso 0 -o ";
    const Result whole = run(s, args + quote(s.path("whole.obj")));
    REQUIRE(whole.code == 0);
    const auto whole_size = fs::file_size(s.path("whole.obj"));

    std::size_t killed = 0;
    for (const char* delay : {"0.02", "0.08", "0.15", "0.2", "0.25", "0.3", "0.4", "0.6"}) {
        const fs::path dir = s.dir / (std::string("run-") + delay);
        fs::create_directories(dir);
        const std::string out = (dir / "out.obj").string();
        // SIGTERM: a background job of a non-interactive shell ignores SIGINT.
        const std::string cmd = quote(VOXMESH_CLI_PATH) + " " + args + quote(out) + " > /dev/null 2>&1 & pid=$!; sleep " +
                                delay + "; kill -TERM $pid 2> /dev/null; wait $pid";
        const int status = std::system(("sh -c " + quote(cmd)).c_str());
        const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        INFO("killed after " << delay << " s: exit " << code);
        CHECK((code == 0 || code == 128 + SIGTERM));
        killed += code != 0;
        const std::vector<std::string> left = vmtest::directory_entries(dir.string());
        // Killed after the rename, the whole file is there too.
        INFO("left: " << (left.empty() ? std::string("nothing") : left[0]));
        if (code == 0 || !left.empty()) {
            CHECK(left == std::vector<std::string>{"out.obj"});
            CHECK(fs::file_size(out) == whole_size);
        }
    }
    CHECK(killed > 0);  // 20 ms is too early for any machine to have finished
}

// Memory running out during the work (here a cap on the process's data, `ulimit -d`) is not
// bad input: exit code 1, with a message saying what ran out, and nothing written.
TEST_CASE("cli: running out of memory exits 1, not as bad input", "[cli][memory]") {
    if (vmtest::kAddressSanitizer || vmtest::kThreadSanitizer) {
        WARN("skipped under a sanitizer: its allocator reports running out and dies, it throws nothing");
        return;
    }
    Scratch s;
    const std::string vol = s.path("big.nrrd");
    // A 700-sample grid of the torus: about 470 MB of f32 samples, over a 150 MB cap.
    const std::string line = "ulimit -d 150000 && " + quote(VOXMESH_CLI_PATH) + " voxelize " +
                             quote(data_file("torus.stl")) + " -o " + quote(vol) + " --resolution 700";
    const Result r = vmtest::run_program("sh", "-c " + quote(line), s.dir.string());
    INFO(r.out << r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find("voxmesh: error: ") != std::string::npos);
    CHECK(r.err.find("cannot allocate") != std::string::npos);
    CHECK_FALSE(fs::exists(vol));
    // Under the same cap a grid that fits is voxelized: the size, not the cap alone, failed.
    const std::string fits = "ulimit -d 150000 && " + quote(VOXMESH_CLI_PATH) + " voxelize " +
                             quote(data_file("torus.stl")) + " -o " + quote(vol) + " --resolution 64";
    CHECK(vmtest::run_program("sh", "-c " + quote(fits), s.dir.string()).code == 0);
}

TEST_CASE("cli: voxelize refuses a grid larger than the memory available", "[cli]") {
    // At most 4608^3 f32 samples (resolution 4096, padding 256): about 391 GB.
    const double physical = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGESIZE));
    if (physical >= 4.0 * 4608 * 4608 * 4608) {
        WARN("this machine has " << physical << " bytes of memory; the grid might fit");
        return;
    }
    Scratch s;
    const std::string vol = s.path("huge.nrrd");
    expect_rejected(s, "voxelize " + quote(data_file("20mm-xyz-cube.stl")) + " -o " + quote(vol) +
                           " --resolution 4096 --padding 256",
                    "resolution 4096", vol, "memory available");
}

TEST_CASE("cli: devices and demo", "[cli]") {
    Scratch s;
    const Result d = run(s, "devices");
    CHECK(d.code == 0);
    CHECK(d.out.find("hardware threads") != std::string::npos);
    // Pinned to one CPU (taskset, util-linux), the tool says it has one to use.
    cpu_set_t allowed;
    REQUIRE(sched_getaffinity(0, sizeof allowed, &allowed) == 0);
    int first = 0;
    while (!CPU_ISSET(first, &allowed)) ++first;
    const Result pinned = vmtest::run_program(
        "taskset", "-c " + std::to_string(first) + " " + vmtest::shell_quote(VOXMESH_CLI_PATH) + " devices",
        s.dir.string());
    INFO(pinned.out << pinned.err);
    CHECK(pinned.code == 0);
    CHECK(pinned.out.find(" 1 of them usable by this process") != std::string::npos);
    // Pinned, four threads asked for run on that one CPU, and the summary says so.
    const std::string head = vmtest::shell_quote(data_file("headsq.nrrd"));
    const Result mesh = vmtest::run_program(
        "taskset", "-c " + std::to_string(first) + " " + vmtest::shell_quote(VOXMESH_CLI_PATH) + " mesh " + head +
                       " -o " + vmtest::shell_quote(s.path("pinned.stl")) + " --backend cpu --threads 4",
        s.dir.string());
    INFO(mesh.out << mesh.err);
    CHECK(mesh.code == 0);
    CHECK(mesh.out.find("(4 threads asked for, run on 1 CPU)") != std::string::npos);
    const Result json = vmtest::run_program(
        "taskset", "-c " + std::to_string(first) + " " + vmtest::shell_quote(VOXMESH_CLI_PATH) + " mesh " + head +
                       " -o " + vmtest::shell_quote(s.path("pinned.stl")) + " --backend cpu --threads 4 --json",
        s.dir.string());
    CHECK(json.out.find("\"threads\": 4, \"workers\": 1") != std::string::npos);
    const Result demo = run(s, "demo");
    INFO(demo.out << demo.err);
    CHECK(demo.code == 0);
    CHECK(demo.out.find("index buffer identical") != std::string::npos);
    CHECK(demo.out.find("opencl") != std::string::npos);
}

TEST_CASE("cli: info on a model gives its size, topology, area and volume", "[cli]") {
    Scratch s;
    const Result t = run(s, "info " + quote(data_file("torus.stl")));
    INFO(t.err);
    REQUIRE(t.code == 0);
    CHECK(t.out.find("triangles: 8700") != std::string::npos);
    CHECK(t.out.find("closed (every edge in two triangles), euler 0, 1 piece") != std::string::npos);  // genus 1
    // A torus of radii 1 and 0.5: area 4 pi^2 R r = 19.74, volume 2 pi^2 R r^2 = 4.93, less
    // for the inscribed polygons.
    const auto value_after = [](const std::string& out, const std::string& label) {
        const std::size_t at = out.find(label);
        return at == std::string::npos ? 0.0 : std::stod(out.substr(at + label.size()));
    };
    CHECK(value_after(t.out, "area:") == Approx(19.74).epsilon(0.01));
    CHECK(value_after(t.out, "volume:") == Approx(4.93).epsilon(0.01));

    // The same sphere wound inward, as OBJ: the volume says so; one face less: open.
    voxmesh::Mesh sphere = voxmesh::read_stl(data_file("unit_sphere.stl"));
    for (std::size_t i = 0; i < sphere.indices.size(); i += 3) std::swap(sphere.indices[i + 1], sphere.indices[i + 2]);
    const std::string inward = s.path("inward.obj");
    voxmesh::write_mesh(inward, sphere);
    const Result in = run(s, "info " + quote(inward));
    REQUIRE(in.code == 0);
    CHECK(in.out.find("closed (every edge in two triangles), euler 2") != std::string::npos);
    CHECK(value_after(in.out, "volume:") == Approx(-4.15).epsilon(0.01));
    CHECK(in.out.find("face inward") != std::string::npos);
    sphere.indices.resize(sphere.indices.size() - 3);
    const std::string open = s.path("open.ply");
    voxmesh::write_mesh(open, sphere);
    const Result o = run(s, "info " + quote(open));
    REQUIRE(o.code == 0);
    CHECK(o.out.find("open: 3 boundary edges") != std::string::npos);
    CHECK(o.out.find("volume:") == std::string::npos);

    const std::string cloud = s.write("cloud.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                                   "property float y\nproperty float z\nend_header\n0 0 0\n1 2 3\n");
    const Result c = run(s, "info " + quote(cloud));
    REQUIRE(c.code == 0);
    CHECK(c.out.find("vertices:  2") != std::string::npos);
    CHECK(c.out.find("no triangles") != std::string::npos);
    CHECK(c.out.find("closed (every edge in two triangles)") == std::string::npos);
    CHECK(c.out.find("bounds:    0 0 0 .. 1 2 3") != std::string::npos);  // a cloud's bounds: every point

    // A vertex no face uses, far off: counted, and left out of the bounds, as voxelize leaves
    // it out of its grid.
    const std::string stray = s.write("stray.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 100 100 100\n"
                                                   "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    const Result st = run(s, "info " + quote(stray));
    REQUIRE(st.code == 0);
    CHECK(st.out.find("vertices:  5, 1 not used by any triangle") != std::string::npos);
    CHECK(st.out.find("bounds:    0 0 0 .. 1 1 1") != std::string::npos);
    CHECK(st.out.find("closed (every edge in two triangles), euler 2") != std::string::npos);
    CHECK(value_after(st.out, "volume:") == Approx(1.0 / 6));

    expect_rejected(s, "info " + quote(open) + " --dims 2 2 2", "open.ply", "", "apply only to .raw");
    const std::string junk = s.write("junk.ply", "ply\nformat ascii 1.0\n");
    expect_rejected(s, "info " + quote(junk), "junk.ply", "");
}

// Two overlapping spheres in one STL (CAD bodies): --fill nonzero voxelizes their union, the
// default (evenodd) leaves the overlap out; a flipped triangle is refused for nonzero only.
TEST_CASE("cli: voxelize and sculpt --fill", "[cli]") {
    Scratch s;
    voxmesh::Mesh pair = voxmesh::read_stl(data_file("unit_sphere.stl"));
    const std::size_t n = pair.positions.size();
    pair.positions.resize(2 * n);
    for (std::size_t i = 0; i < n; ++i) pair.positions[n + i] = pair.positions[i] + (i % 3 == 0 ? 1.0f : 0.0f);
    const std::size_t t = pair.indices.size();
    for (std::size_t i = 0; i < t; ++i) pair.indices.push_back(pair.indices[i] + static_cast<std::uint32_t>(n / 3));
    const std::string model = s.path("pair.stl");
    voxmesh::write_mesh(model, pair);

    const Result u = run(s, "sculpt " + quote(model) + " --resolution 48 --fill nonzero -o " + quote(s.path("u.stl")));
    INFO(u.err);
    REQUIRE(u.code == 0);
    CHECK(u.out.find("in 1 piece, closed (euler 2)") != std::string::npos);
    const Result x = run(s, "sculpt " + quote(model) + " --resolution 48 -o " + quote(s.path("x.stl")));
    REQUIRE(x.code == 0);
    CHECK(x.out.find("closed (euler 2)") == std::string::npos);

    const std::string vol = s.path("u.nrrd");
    REQUIRE(run(s, "voxelize " + quote(model) + " -o " + quote(vol) + " --resolution 48 --fill nonzero").code == 0);
    const Result m = run(s, "mesh " + quote(vol) + " -o " + quote(s.path("m.stl")));
    REQUIRE(m.code == 0);
    const voxmesh::MeshTopology topo = voxmesh::analyze_topology(voxmesh::read_stl(s.path("m.stl")));
    CHECK(topo.closed());
    CHECK(topo.euler == 2);

    std::swap(pair.indices[1], pair.indices[2]);
    const std::string flipped = s.path("flipped.stl");
    voxmesh::write_mesh(flipped, pair);
    const std::string out = s.path("f.nrrd");
    expect_rejected(s, "voxelize " + quote(flipped) + " -o " + quote(out) + " --resolution 16 --fill nonzero",
                    "flipped.stl", out, "not consistently wound: 3 edges");
    expect_rejected(s, "voxelize " + quote(flipped) + " -o " + quote(out) + " --resolution 16 --fill nonzero",
                    "--fill evenodd", out);
    CHECK(run(s, "voxelize " + quote(flipped) + " -o " + quote(out) + " --resolution 16 --fill evenodd").code == 0);
    expect_rejected(s, "sculpt " + quote(flipped) + " --resolution 16 --fill nonzero -o " + quote(s.path("f.stl")),
                    "--fill evenodd", s.path("f.stl"));
    expect_rejected(s, "voxelize " + quote(model) + " -o " + quote(s.path("b.nrrd")) + " --resolution 16 --fill odd",
                    "--fill", s.path("b.nrrd"));

    // Two unit cubes stacked, sharing the face z = 1 (four triangles at its edges): both rules
    // voxelize their union.
    voxmesh::Mesh stack;
    for (float z0 : {0.0f, 1.0f}) {
        const auto base = static_cast<std::uint32_t>(stack.vertex_count());
        for (int v = 0; v < 8; ++v)
            stack.positions.insert(stack.positions.end(), {float(v & 1), float(v >> 1 & 1), z0 + float(v >> 2)});
        for (std::uint32_t i : {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5})
            stack.indices.push_back(base + i);
    }
    const std::string stacked = s.path("stack.stl");
    voxmesh::write_mesh(stacked, stack);
    const Result info = run(s, "info " + quote(stacked));
    REQUIRE(info.code == 0);
    CHECK(info.out.find("not manifold: 5 edges in three or more triangles, euler 5, 1 piece (voxelize takes bodies "
                        "sharing edges or faces") != std::string::npos);
    for (const char* fill : {"evenodd", "nonzero"}) {
        const Result st = run(s, "sculpt " + quote(stacked) + " --resolution 16 --fill " + fill + " -o " + quote(s.path("st.stl")));
        INFO(st.err);
        REQUIRE(st.code == 0);
        CHECK(st.out.find("in 1 piece, closed (euler 2)") != std::string::npos);
    }
}

// The same model as STL, PLY and OBJ (the PLY and OBJ written by the library from what
// read_stl read) voxelizes to the same volume, and sculpts to the same mesh.
TEST_CASE("cli: voxelize and sculpt read PLY and OBJ models as they read STL", "[cli]") {
    Scratch s;
    const voxmesh::Mesh torus = voxmesh::read_stl(data_file("torus.stl"));
    const std::string ply = s.path("torus.ply"), obj = s.path("torus.obj");
    voxmesh::write_mesh(ply, torus);
    voxmesh::write_mesh(obj, torus);
    const std::string strokes = s.write("strokes.txt", "units world\nsubtract 0 0 0.2 0.3 2\n");
    std::vector<std::vector<float>> volumes;
    std::vector<std::string> sculpted;
    for (const std::string& model : {data_file("torus.stl"), ply, obj}) {
        INFO(model);
        const std::string vol = s.path("v.nrrd"), out = s.path("sculpted.ply");
        const Result v = run(s, "voxelize " + quote(model) + " -o " + quote(vol) + " --resolution 32");
        INFO(v.err);
        REQUIRE(v.code == 0);
        CHECK(v.out.find(std::to_string(torus.triangle_count()) + " triangles") != std::string::npos);
        const voxmesh::Volume volume = voxmesh::read_volume(vol);
        REQUIRE(volume.type == voxmesh::ScalarType::F32);
        const auto* f = static_cast<const float*>(volume.data);
        volumes.emplace_back(f, f + volume.dims[0] * volume.dims[1] * volume.dims[2]);
        const Result r = run(s, "sculpt " + quote(model) + " --resolution 32 --strokes " + quote(strokes) + " -o " + quote(out));
        INFO(r.err);
        REQUIRE(r.code == 0);
        sculpted.push_back(iotest::read_file(out));
    }
    CHECK(volumes[1] == volumes[0]);
    CHECK(volumes[2] == volumes[0]);
    CHECK(sculpted[1] == sculpted[0]);
    CHECK(sculpted[2] == sculpted[0]);

    const std::string other = s.write("model.off", "OFF\n");
    expect_rejected(s, "voxelize " + quote(other) + " -o " + quote(s.path("n.nrrd")) + " --resolution 16", "model.off",
                    s.path("n.nrrd"), "not a mesh file");
    const std::string broken = s.write("broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
    expect_rejected(s, "voxelize " + quote(broken) + " -o " + quote(s.path("n.nrrd")) + " --resolution 16",
                    "broken.obj", s.path("n.nrrd"), "line 3");
}

TEST_CASE("cli: sculpt a real STL model with a stroke script", "[cli]") {
    Scratch s;
    const std::string strokes = s.write("strokes.txt",
                                        "# a groove over the top of the unit sphere, then smoothed\n"
                                        "units world\n"
                                        "subtract 0 0 1 0.3 2\n"
                                        "subtract 0.3 0 0.95 0.3 2\n"
                                        "add -0.5 0 0.8 0.25 1\n"
                                        "smooth 0.15 0 0.97 0.3 0.5\n");
    const std::string out = s.path("sculpted.stl");
    const Result r = run(s, "sculpt " + quote(data_file("unit_sphere.stl")) + " --resolution 48 --strokes " +
                                quote(strokes) + " -o " + quote(out) + " --frames");
    INFO(r.out << r.err);
    REQUIRE(r.code == 0);
    CHECK(r.out.find("4 dabs") != std::string::npos);
    CHECK(r.out.find("frame 3:") != std::string::npos);
    CHECK(r.out.find("closed") != std::string::npos);
    CHECK(stl_triangles(out) > 1000);

    const std::string bad = s.write("bad.txt", "add 1 2\n");
    expect_rejected(s, "sculpt " + quote(data_file("unit_sphere.stl")) + " --resolution 48 --strokes " + quote(bad) +
                           " -o " + quote(s.path("never.stl")),
                    "bad.txt:1", s.path("never.stl"));

    // The same strokes re-meshed on an OpenCL device (or on the CPU with a warning where
    // there is none) write the same file, byte for byte.
    const std::string cpu_out = s.path("cpu.ply"), cl_out = s.path("opencl.ply");
    const std::string common = "sculpt " + quote(data_file("unit_sphere.stl")) + " --resolution 40 --strokes " +
                               quote(strokes) + " -o ";
    const Result cpu = run(s, common + quote(cpu_out) + " --backend cpu");
    const Result cl = run(s, common + quote(cl_out) + " --backend opencl");
    INFO(cpu.out << cpu.err << cl.out << cl.err);
    REQUIRE(cpu.code == 0);
    REQUIRE(cl.code == 0);
    CHECK(iotest::read_file(cpu_out) == iotest::read_file(cl_out));
}

// A bump built up 3 voxels on the top of the sphere: with the default 2 samples of padding the
// surface meets the volume's border and is cut open there; --padding 6 gives it room.
TEST_CASE("cli: sculpt --padding leaves a surface room to be built up", "[cli]") {
    Scratch s;
    const std::string strokes = s.write("bump.txt", "units world\nadd 0 0 1 0.4 3\n");
    const std::string common =
        "sculpt " + quote(data_file("unit_sphere.stl")) + " --resolution 32 --strokes " + quote(strokes) + " -o ";
    const Result tight = run(s, common + quote(s.path("tight.ply")));
    const Result roomy = run(s, common + quote(s.path("roomy.ply")) + " --padding 6");
    INFO(tight.out << tight.err << roomy.out << roomy.err);
    REQUIRE(tight.code == 0);
    REQUIRE(roomy.code == 0);
    CHECK(tight.out.find("36x36x36 volume") != std::string::npos);
    CHECK(tight.out.find(", open") != std::string::npos);
    CHECK(roomy.out.find("44x44x44 volume") != std::string::npos);
    CHECK(roomy.out.find("closed (euler 2)") != std::string::npos);
    expect_rejected(s, common + quote(s.path("never.ply")) + " --padding 300", "padding", s.path("never.ply"));
}

// Found by a review: a device that does not exist was found after the model was voxelized,
// and named as the model file's fault.
TEST_CASE("cli: sculpt names a device that does not exist before reading the model", "[cli]") {
    Scratch s;
    const std::string model = data_file("unit_sphere.stl"), out = s.path("o.ply");
    const Result r = run(s, "sculpt " + quote(model) + " --resolution 16 --backend opencl --device 99 -o " + quote(out));
    INFO(r.out << r.err);
    const std::size_t count = voxmesh::list_devices().size();
    if (count == 0) {  // no OpenCL here: the CPU re-meshes, with the library's warning
        CHECK(r.code == 0);
        CHECK(r.err.find("sculpt re-meshes on the CPU") != std::string::npos);
        return;
    }
    CHECK(r.code == 2);
    CHECK(r.err == "voxmesh: error: OpenCL device index 99 does not exist (voxmesh devices lists " + std::to_string(count) +
                       (count == 1 ? " device)\n" : " devices)\n"));
    CHECK_FALSE(std::filesystem::exists(out));
}

// Without strokes, sculpt is the paper's pipeline in one step: the file it writes is the one
// voxelize and mesh write in two (the same distance field near the surface, meshed at iso 0).
TEST_CASE("cli: sculpt without strokes voxelizes and meshes the model again", "[cli]") {
    Scratch s;
    const std::string model = data_file("torus.stl"), one = s.path("one.ply"), vol = s.path("torus.nrrd"),
                      two = s.path("two.ply");
    const Result r = run(s, "sculpt " + quote(model) + " --resolution 40 -o " + quote(one));
    INFO(r.out << r.err);
    REQUIRE(r.code == 0);
    CHECK(r.out.find("no strokes") != std::string::npos);
    CHECK(r.out.find("closed (euler 0)") != std::string::npos);  // the torus's genus survives
    REQUIRE(run(s, "voxelize " + quote(model) + " --resolution 40 -o " + quote(vol)).code == 0);
    REQUIRE(run(s, "mesh " + quote(vol) + " -o " + quote(two)).code == 0);
    const std::string a = iotest::read_file(one);
    CHECK(a.size() > 10000);
    CHECK(a == iotest::read_file(two));
}

// A dab in a far corner raises a second, floating piece; --largest 1 writes the model alone,
// the file sculpt writes without that dab (the model's samples are untouched by it).
TEST_CASE("cli: sculpt --largest drops a piece a brush left floating", "[cli]") {
    Scratch s;
    const std::string model = quote(data_file("unit_sphere.stl"));
    const std::string blob = s.write("blob.txt", "add 4 4 4 3 8\n");
    const std::string both = s.path("both.ply"), kept = s.path("kept.ply"), plain = s.path("plain.ply");
    const Result r = run(s, "sculpt " + model + " --resolution 40 --strokes " + quote(blob) + " -o " + quote(both));
    INFO(r.out << r.err);
    REQUIRE(r.code == 0);
    CHECK(r.out.find("in 2 pieces, closed (euler 4)") != std::string::npos);
    const Result k = run(s, "sculpt " + model + " --resolution 40 --strokes " + quote(blob) + " -o " + quote(kept) +
                                " --largest 1");
    INFO(k.out << k.err);
    REQUIRE(k.code == 0);
    CHECK(k.out.find("in 1 piece, closed (euler 2)") != std::string::npos);
    REQUIRE(run(s, "sculpt " + model + " --resolution 40 -o " + quote(plain)).code == 0);
    CHECK(iotest::read_file(kept) == iotest::read_file(plain));
    expect_rejected(s, "sculpt " + model + " --resolution 40 -o " + quote(s.path("never.ply")) + " --largest 0",
                    "--largest", s.path("never.ply"));
}

#else
TEST_CASE("cli: not built", "[cli]") { WARN("voxmesh_cli is not built (VOXMESH_BUILD_CLI=OFF): CLI tests skipped"); }
#endif
