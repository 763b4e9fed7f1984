// Runs the built voxmesh-bench on tiny volumes: every row it reports is a real extract of the
// volume named (same triangles whatever the engine), its outputs parse, a written volume
// reads back to the same mesh, and bad arguments fail. Timings are not checked.
#include <catch2/catch.hpp>

#ifdef VOXMESH_BENCH_PATH

#include "support/io_scratch.hpp"
#include "support/mesh_checks.hpp"
#include "support/run_program.hpp"

#include <voxmesh/io.hpp>
#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <cstddef>
#include <map>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <vector>

namespace {

using iotest::Scratch;
using vmtest::shell_quote;

vmtest::ProgramResult bench(const Scratch& s, const std::string& args) {
    return vmtest::run_program(VOXMESH_BENCH_PATH, args + " -q", s.dir);
}

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
        if (!line.empty()) lines.push_back(line);
    return lines;
}

// The value of "key": in a one-line JSON object, as text (strings without their quotes).
std::string json_value(const std::string& line, const std::string& key) {
    const std::string tag = "\"" + key + "\":";
    const std::size_t at = line.find(tag);
    if (at == std::string::npos) return "<missing " + key + ">";
    std::size_t begin = at + tag.size();
    if (line[begin] == '"') return line.substr(begin + 1, line.find('"', begin + 1) - begin - 1);
    const std::size_t end = line.find_first_of(",}", begin);
    return line.substr(begin, end - begin);
}

}  // namespace

TEST_CASE("bench: every backend and thread count reports the same mesh of a volume", "[bench]") {
    Scratch s;
    const bool opencl = !voxmesh::list_devices().empty();
    const std::string backends = opencl ? "cpu,opencl,hybrid,auto" : "cpu,auto";
    const auto r = bench(s, "--field sphere,gyroid --type f32,u8 --sizes 12,21 --threads 1,2 --backends " + backends +
                                " --repeat 2 --warmup 0 --json --no-floor");
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto rows = lines_of(r.out);
    // 2 fields x 2 types x 2 sizes, each backend at each thread count (OpenCL's devices take
    // the place of threads: one row).
    const std::size_t per_volume = opencl ? 2 + 1 + 2 + 2 : 2 + 2;
    CHECK(rows.size() == 8 * per_volume);
    std::map<std::string, std::string> triangles;  // per volume
    for (const std::string& row : rows) {
        INFO(row);
        REQUIRE(row.front() == '{');
        REQUIRE(row.back() == '}');
        CHECK(json_value(row, "status") == "ok");
        CHECK(json_value(row, "repeat") == "2");
        const std::string volume =
            json_value(row, "field") + " " + json_value(row, "type") + " " + json_value(row, "size");
        const std::string count = json_value(row, "triangles");
        CHECK(std::stoul(count) > 0);
        const auto [it, first] = triangles.emplace(volume, count);
        CHECK(it->second == count);
    }
    CHECK(triangles.size() == 8);
}

TEST_CASE("bench: each Hybrid call's mode is recorded, the warm-up's in lower case", "[bench]") {
    if (voxmesh::list_devices().empty()) return;
    Scratch s;
    // Device 0 named: Hybrid leaves a CPU device out otherwise, and runs the CPU engine alone.
    const auto r = bench(s, "--field gyroid --type u8 --sizes 24 --threads 2 --backends cpu,hybrid --devices 0 "
                            "--repeat 6 --warmup 1 --json --no-floor");
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto rows = lines_of(r.out);
    REQUIRE(rows.size() == 2);
    CHECK(json_value(rows[0], "hybrid_modes").empty());  // the CPU engine: no modes
    const std::string modes = json_value(rows[1], "hybrid_modes");
    INFO(rows[1]);
    // A new shape: the untimed split (the warm-up), the split timed, then the CPU engine alone
    // and the device alone once each, then the quickest (hybrid_schedule.hpp).
    REQUIRE(modes.size() == 7);
    CHECK(modes.substr(0, 4) == "sSCD");
    CHECK(modes.find_first_not_of("SCD", 1) == std::string::npos);
}

TEST_CASE("bench: CSV has one header and rows of its width; the table names its columns", "[bench]") {
    Scratch s;
    auto fields = [](const std::string& line) {  // commas outside quotes, plus one
        std::size_t n = 1;
        bool quoted = false;
        for (char c : line) {
            if (c == '"') quoted = !quoted;
            n += !quoted && c == ',';
        }
        return n;
    };
    const auto csv = bench(s, "--field blobs --type i16 --sizes 10 --threads 1,2 --backends cpu,hybrid --repeat 1 "
                              "--warmup 0 --csv --no-floor");
    INFO(csv.err);
    REQUIRE(csv.code == 0);
    const auto lines = lines_of(csv.out);
    REQUIRE(lines.size() == 1 + 4);
    CHECK(lines[0].rfind("field,type,size,", 0) == 0);
    for (const std::string& line : lines) CHECK(fields(line) == fields(lines[0]));

    const auto table = bench(s, "--field ct --type u8 --sizes 16 --threads 1 --repeat 1 --warmup 0");
    REQUIRE(table.code == 0);
    CHECK(table.out.find("median_s") != std::string::npos);
    CHECK(table.out.find("ct       u8   16") != std::string::npos);
}

// Two ceilings beside each speed-up: a dependent chain, which hyperthreads of one core hide, and
// a loop that fills a core's issue width, which they share (the forty-third session could not
// tell why 2 threads gained 1.5x on a 16-core machine whose chain ceiling read 1.96).
TEST_CASE("bench: each speed-up has a chain ceiling and a full-width ceiling beside it", "[bench]") {
    Scratch s;
    const auto json = bench(s, "--sizes 12 --threads 1,2 --repeat 1 --warmup 0 --no-floor --json");
    INFO(json.err);
    REQUIRE(json.code == 0);
    const auto rows = lines_of(json.out);
    REQUIRE(rows.size() == 2);
    for (const std::string& row : rows) {
        INFO(row);
        // Against the series' own base, 1 thread: 1 exactly there; a rate ratio above 0 at 2.
        const double chain = std::stod(json_value(row, "compute_ceiling"));
        const double wide = std::stod(json_value(row, "compute_ceiling_wide"));
        if (json_value(row, "threads") == "1") {
            CHECK(chain == 1.0);
            CHECK(wide == 1.0);
        } else {
            CHECK(chain > 0);
            CHECK(wide > 0);
        }
    }
    const auto one = bench(s, "--sizes 12 --threads 2 --repeat 1 --warmup 0 --no-floor --json");
    REQUIRE(one.code == 0);  // one thread count: nothing to compare, so neither is measured
    CHECK(json_value(one.out, "compute_ceiling_wide") == "null");
    const auto table = bench(s, "--sizes 12 --threads 1,2 --repeat 1 --warmup 0 --no-floor");
    REQUIRE(table.code == 0);
    CHECK(table.out.find("  ceil ceil_w  fl_sp ") != std::string::npos);
}

TEST_CASE("bench: the paper's grid runs 1, 2, 4, 6 and 16 threads", "[bench]") {
    Scratch s;
    const auto r = bench(s, "--paper --sizes 64 --repeat 1 --warmup 0 --no-floor");
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(r.out.find("Table 1, reproduced") != std::string::npos);
    for (const char* threads : {"\n1 ", "\n2 ", "\n4 ", "\n6 ", "\n16 "}) CHECK(r.out.find(threads) != std::string::npos);
    // 64^3 is the paper's first column: ours is filled in, not "-".
    const std::size_t row = r.out.find("\n16       |");
    REQUIRE(row != std::string::npos);
    CHECK(r.out.substr(row, 30).find(" - ") == std::string::npos);
}

TEST_CASE("bench: --mesh-ops times each operation on one mesh and leaves no file behind", "[bench]") {
    Scratch s;
    const std::string tmp = s.dir + "/tmp";
    std::filesystem::create_directory(tmp);
    const auto r = vmtest::run_program(VOXMESH_BENCH_PATH, "--mesh-ops --field sphere --type u8 --sizes 40 --repeat 2 --json -q",
                                       s.dir, "TMPDIR=" + shell_quote(tmp));
    INFO(r.err);
    REQUIRE(r.code == 0);
    const std::vector<std::string> lines = lines_of(r.out);
    std::vector<std::string> ops;
    for (const std::string& line : lines) {
        CHECK(json_value(line, "bench") == "mesh_ops");
        CHECK(json_value(line, "triangles") == json_value(lines[0], "triangles"));
        CHECK(std::stod(json_value(line, "median_s")) >= 0);
        ops.push_back(json_value(line, "op"));
    }
    CHECK(ops == std::vector<std::string>{"extract", "analyze_topology_1_worker", "analyze_topology",
                                          "keep_largest_components", "write_stl", "write_ply", "write_obj", "write_glb",
                                          "vertex_edges", "triangle_cells", "edge_cell_ranges"});
    CHECK(std::stoul(json_value(lines[0], "triangles")) > 1000);
    CHECK(json_value(lines[0], "vs_extract") == "1.000");
    CHECK(std::filesystem::is_empty(tmp));  // its directory and files removed
}

TEST_CASE("bench: a volume written for the peers reads back to the same mesh", "[bench]") {
    Scratch s;
    const std::string file = s.dir + "/gyroid.nrrd";
    const auto written = bench(s, "--field gyroid --type f32 --sizes 24 --write-volume " + shell_quote(file));
    INFO(written.err);
    REQUIRE(written.code == 0);
    const std::string common = " --threads 1 --backends cpu --repeat 1 --warmup 0 --json --no-floor";
    const auto built_in = bench(s, "--field gyroid --type f32 --sizes 24" + common);
    const auto from_file = bench(s, "--input " + shell_quote(file) + common);
    REQUIRE(built_in.code == 0);
    REQUIRE(from_file.code == 0);
    CHECK(json_value(from_file.out, "iso") == json_value(built_in.out, "iso"));  // voxmesh_iso in the file
    CHECK(json_value(from_file.out, "triangles") == json_value(built_in.out, "triangles"));
    CHECK(json_value(from_file.out, "vertices") == json_value(built_in.out, "vertices"));
    // A recorded iso that is not one finite number is refused before any run, as mesh does
    // (strtod took "1abc" as 1 and "inf" as an iso that meshes nothing); --iso goes on.
    const voxmesh::Volume volume = voxmesh::read_volume(file);
    for (const char* bad : {"1abc", "inf", "nan", ""}) {
        INFO("'" << bad << "'");
        voxmesh::write_nrrd(file, volume.view(), {{"voxmesh_iso", bad}});
        const auto refused = bench(s, "--input " + shell_quote(file) + common);
        CHECK(refused.code == 1);
        CHECK_THAT(refused.err, Catch::Contains("its voxmesh_iso ('" + std::string(bad) +
                                                "') is not a finite number: give --iso"));
        CHECK(refused.out.empty());
    }
    CHECK(bench(s, "--input " + shell_quote(file) + " --iso 0" + common).code == 0);
    // A name is taken whole: "--input" was a comma list, so a file named with a comma was
    // looked for as two files.
    const std::string comma = s.dir + "/gyroid,24.nrrd";
    voxmesh::write_nrrd(comma, volume.view(), {{"voxmesh_iso", "0"}});
    const auto named = bench(s, "--input " + shell_quote(comma) + common);
    INFO(named.err);
    CHECK(named.code == 0);
    CHECK(json_value(named.out, "triangles") == json_value(built_in.out, "triangles"));
}

TEST_CASE("bench: --save writes the JSON lines printed, and a bad path fails before any run", "[bench]") {
    Scratch s;
    const std::string saved = s.dir + "/runs.json";
    const auto r = bench(s, "--field sphere --type u8 --sizes 10,14 --threads 1 --repeat 1 --warmup 0 --json "
                            "--no-floor --save " + shell_quote(saved));
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(iotest::read_file(saved) == r.out);
    // A bad path is named at once: the runs (here 400^3, seconds) never start.
    const auto bad = bench(s, "--sizes 400 --threads 1 --save " + shell_quote(s.dir + "/no/such/dir/x.json"));
    CHECK(bad.code != 0);
    CHECK_THAT(bad.err, Catch::Contains("no/such/dir/x.json"));
    CHECK(bad.out.find("median_s") == std::string::npos);
}

TEST_CASE("bench: Ctrl-C stops the runs and prints and saves what finished, with no temporary left", "[bench]") {
    Scratch s;
    const std::string out_dir = s.dir + "/out";
    std::filesystem::create_directories(out_dir);
    const std::string saved = out_dir + "/runs.json";
    // The second volume's 1000 runs take seconds: the signal comes while they run.
    const vmtest::StartedProgram run = vmtest::start_program(
        VOXMESH_BENCH_PATH, {"--field", "sphere", "--type", "u8", "--sizes", "12,256", "--threads", "1", "--repeat", "1000",
                             "--warmup", "0", "--no-floor", "--json", "--save", saved},
        s.dir);
    const bool second_started = vmtest::wait_for_stderr(run, "[2/2]", 120);
    ::kill(run.pid, SIGINT);
    const int status = vmtest::wait_program(run);
    const std::string err = iotest::read_file(run.err_path);
    INFO(err);
    REQUIRE(second_started);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 130);
    // The first volume's row, and the second's from the runs it finished, if any.
    const std::string out = iotest::read_file(run.out_path);
    const auto rows = lines_of(out);
    REQUIRE(!rows.empty());
    REQUIRE(rows.size() <= 2);
    CHECK(json_value(rows[0], "size") == "12");
    if (rows.size() == 1) {
        CHECK_THAT(err, Catch::Contains("interrupted: printing the 1 finished result(s)"));
    } else {
        CHECK(json_value(rows[1], "size") == "256");
        CHECK_THAT(err, Catch::Contains("interrupted: printing 2 result(s), the last from"));
        CHECK_THAT(err, Catch::Contains("of 1000 runs"));
    }
    CHECK(iotest::read_file(saved) == out);
    CHECK(vmtest::directory_entries(out_dir) == std::vector<std::string>{"runs.json"});
}

TEST_CASE("bench: killed while writing a volume, leaves the whole file or none, never a temporary", "[bench]") {
    Scratch s;
    // 131 MB: generated in about 0.1 s and written in as long here.
    const std::vector<std::string> args{"--field", "gyroid", "--sizes", "320", "--write-volume"};
    auto write_into = [&](const std::string& dir) {
        std::filesystem::create_directories(dir);
        std::vector<std::string> a = args;
        a.push_back(dir + "/g.nrrd");
        return vmtest::start_program(VOXMESH_BENCH_PATH, a, s.dir);
    };
    const vmtest::StartedProgram whole = write_into(s.dir + "/whole");
    const int whole_status = vmtest::wait_program(whole);
    REQUIRE(WIFEXITED(whole_status));
    REQUIRE(WEXITSTATUS(whole_status) == 0);
    const auto whole_size = std::filesystem::file_size(s.dir + "/whole/g.nrrd");

    std::size_t killed = 0;
    for (const int delay_ms : {2, 10, 25, 50, 75, 100, 130, 170, 220}) {
        const std::string dir = s.dir + "/run-" + std::to_string(delay_ms);
        const vmtest::StartedProgram run = write_into(dir);
        std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
        ::kill(run.pid, SIGTERM);
        const int status = vmtest::wait_program(run);
        const bool finished = WIFEXITED(status) && WEXITSTATUS(status) == 0;
        INFO("killed after " << delay_ms << " ms: wait status " << status);
        CHECK((finished || (WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM)));
        killed += !finished;
        const std::vector<std::string> left = vmtest::directory_entries(dir);
        // Killed after the rename, the whole file is there too.
        INFO("left: " << (left.empty() ? std::string("nothing") : left[0]));
        if (finished || !left.empty()) {
            CHECK(left == std::vector<std::string>{"g.nrrd"});
            CHECK(std::filesystem::file_size(dir + "/g.nrrd") == whole_size);
        }
        std::filesystem::remove_all(dir);
    }
    CHECK(killed > 0);  // 2 ms is too early for any machine to have written 131 MB
}

// A size or thread count given twice made a second series under the same key, whose speed-ups
// were taken against the first copy; a floor not measured read 0.
TEST_CASE("bench: repeated list entries run once, and a floor not measured is shown as missing", "[bench]") {
    Scratch s;
    const auto r = bench(s, "--sizes 12,12 --threads 1,1,2 --type u8,u8 --repeat 1 --no-floor");
    INFO(r.err);
    REQUIRE(r.code == 0);
    std::vector<std::string> rows;
    for (const std::string& line : lines_of(r.out))
        if (line.rfind("sphere", 0) == 0) rows.push_back(line);
    REQUIRE(rows.size() == 2);  // threads 1 and 2, once each
    std::istringstream row(rows[1]);
    std::vector<std::string> cells;
    for (std::string cell; row >> cell;) cells.push_back(cell);
    REQUIRE(cells.size() > 13);
    CHECK(cells[5] == "2");
    CHECK(cells[11] == "-");  // floor_s
    CHECK(cells[12] == "-");  // x_floor
    const auto json = bench(s, "--sizes 12 --threads 1 --repeat 1 --no-floor --json");
    CHECK(json_value(json.out, "floor_s") == "null");
    CHECK(json_value(json.out, "floor_ratio") == "null");
    // A file name that is not UTF-8 made a JSON line no parser takes: such bytes are U+FFFD.
    const std::string odd = s.dir + "/odd\xff\xc3\xa9.nrrd";
    REQUIRE(bench(s, "--sizes 12 --write-volume " + shell_quote(odd)).code == 0);
    const auto named = bench(s, "--input " + shell_quote(odd) + " --threads 1 --repeat 1 --no-floor --json");
    INFO(named.err);
    CHECK(json_value(named.out, "field") == s.dir + "/odd\\ufffd\xc3\xa9.nrrd");
}

TEST_CASE("bench: bad arguments fail with a message", "[bench][errors]") {
    Scratch s;
    const std::vector<std::pair<std::string, std::string>> bad = {
        {"--sizes 1", "at least 8 samples"},
        {"--sizes 4", "at least 8 samples"},
        {"--field nope", "unknown field 'nope'"},
        {"--type f16", "unknown type 'f16'"},
        {"--backends gpu", "unknown backend 'gpu'"},
        {"--iso nan", "finite"},
        {"--csv --json", "one of --csv and --json"},
        {"--input " + shell_quote(s.dir + "/missing.nrrd"), "missing.nrrd"},
        {"--field sphere,gyroid --write-volume " + shell_quote(s.dir + "/x.nrrd"), "exactly one"},
        {"--repeat 0", "--repeat"},
        {"--threads ''", "--threads: empty value"},  // CLI11 alone read '' as 0 (every CPU)
        {"--iso ''", "--iso: empty value"},
        // Found by a review: each was accepted, then crashed, ran something else or was ignored.
        {"--threads 100000", "--threads: 100000 is out of range (0..65536)"},  // aborted (a thread each)
        {"--sizes -5", "--sizes: -5 is out of range (1..65536)"},                // wrapped to 2^64 - 5
        // CLI::Range said "Value 1.5 not in range 1 to 1000" of a number in the range.
        {"--repeat 1.5", "--repeat: '1.5' is not a whole number"},
        {"--threads 1,two", "--threads: 'two' is not a whole number"},
        {"--pause nan", "--pause must be a number"},
        // strtold took hex: --iso 0x10 ran at 16.
        {"--iso 0x10", "--iso: '0x10' is not a decimal number"},
        {"--pause 0x10", "--pause: '0x10' is not a decimal number"},
        {"--backends opencl --devices 0,,1", "an empty entry"},
        {"--backends opencl --devices 0+0", "each device once"},
        {"--backends opencl --devices 7", "no combination could run here"},  // exited 0
        {"--write-volume " + shell_quote(s.dir + "/v.nii"), "writes NRRD"},  // wrote NRRD named .nii
        {"--sculpt --save x.json", "--save does not apply to --sculpt"},
        {"--mesh-ops --csv", "--csv does not apply to --mesh-ops"},
        {"--paper --backends opencl", "--backends does not apply to --paper"},
    };
    for (const auto& [args, message] : bad) {
        INFO(args);
        const auto r = bench(s, args + " --sizes 8 --no-floor");
        CHECK(r.code != 0);
        CHECK_THAT(r.err, Catch::Contains(message));
    }
}

#endif
