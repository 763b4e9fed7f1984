// The voxmesh tool at the edges a review of its command line found wanting: a file size limit,
// a standard output that cannot be written, TMPDIR, the default iso of samples near the
// largest double, and whole numbers written with leading zeros.
#include <catch2/catch.hpp>

#ifdef VOXMESH_CLI_PATH

#include <voxmesh/voxmesh.hpp>

#include "support/io_scratch.hpp"
#include "support/mesh_checks.hpp"
#include "support/run_program.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::string quote(const std::string& s) { return vmtest::shell_quote(s); }

std::string data_file(const std::string& name) { return (fs::path(VOXMESH_TEST_DATA) / name).string(); }

// `script` run by /bin/sh; its exit status, or -1 when it did not exit normally.
int shell(const std::string& script) {
    const int status = std::system(("sh -c " + quote(script)).c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<std::string> stdin_copies(const std::string& tmpdir) {
    std::vector<std::string> left;
    for (const std::string& name : vmtest::directory_entries(tmpdir))
        if (name.rfind("voxmesh-stdin-", 0) == 0) left.push_back(name);
    return left;
}

}  // namespace

// ulimit -f: SIGXFSZ killed the tool (exit 153, no message) with the temporary beside the
// output, or the copy of standard input in TMPDIR, left behind; with PoCL loaded its LLVM's
// one-shot handler let the write fail instead, so the outcome hung on the backend.
TEST_CASE("cli: a file size limit fails the write, names it and leaves no temporary", "[cli]") {
    iotest::Scratch s;
    const std::string out = s.dir + "/out.stl";
    iotest::write_file(out, "OLD");
    const std::string voxmesh = quote(VOXMESH_CLI_PATH);
    for (const char* backend : {"cpu", "auto"}) {
        INFO(backend);
        const int code = shell("ulimit -f 100; " + voxmesh + " mesh " + quote(data_file("headsq.nrrd")) +
                               " --iso 499.5 --backend " + backend + " -o " + quote(out) + " > /dev/null 2> " +
                               quote(s.dir + "/err.txt"));
        CHECK(code == 2);
        CHECK(iotest::read_file(s.dir + "/err.txt").find("File too large") != std::string::npos);
        CHECK(iotest::read_file(out) == "OLD");
        CHECK(vmtest::directory_entries(s.dir) == std::vector<std::string>{"err.txt", "out.stl"});
    }
    // The copy of standard input, over the limit.
    const std::string tmp = s.dir + "/tmp";
    fs::create_directories(tmp);
    const int code = shell("ulimit -f 100; TMPDIR=" + quote(tmp) + " " + voxmesh + " info - < " +
                           quote(data_file("mri_someones_anatomy.nii.gz")) + " > /dev/null 2> " + quote(s.dir + "/err.txt"));
    CHECK(code == 2);
    CHECK(iotest::read_file(s.dir + "/err.txt").find("File too large") != std::string::npos);
    CHECK(stdin_copies(tmp).empty());
}

// PoCL writes the kernels it compiles to files; under the limit its LLVM called exit(1) after
// "LLVM ERROR: IO failure on output stream" (or failed the build), and voxmesh said nothing.
// A cache directory of its own makes PoCL compile afresh.
TEST_CASE("cli: a file size limit that stops the OpenCL kernel compiler is named", "[cli]") {
#ifdef VOXMESH_HAS_OPENCL
    if (voxmesh::list_devices().empty()) {
        WARN("no OpenCL device: SKIPPED");
        return;
    }
    iotest::Scratch s;
    fs::create_directories(s.dir + "/pocl");
    const int code = shell("ulimit -f 100; POCL_CACHE_DIR=" + quote(s.dir + "/pocl") + " " + quote(VOXMESH_CLI_PATH) +
                           " mesh " + quote(data_file("headsq.nrrd")) + " --iso 499.5 --backend opencl -o " +
                           quote(s.dir + "/o.stl") + " > /dev/null 2> " + quote(s.dir + "/err.txt"));
    const std::string err = iotest::read_file(s.dir + "/err.txt");
    INFO(err);
    CHECK((code == 1 || code == 2));
    CHECK(err.find("voxmesh: error: ") != std::string::npos);
    CHECK(err.find("a file size limit (ulimit -f) is set") != std::string::npos);
    CHECK(!fs::exists(s.dir + "/o.stl"));
#endif
}

// Warnings are in the CLI's words, as errors are: Hybrid's advice with only CPU devices named
// Options::devices and device_type, which the command line does not have.
TEST_CASE("cli: a warning's advice names the CLI's options", "[cli]") {
#ifdef VOXMESH_HAS_OPENCL
    const auto devices = voxmesh::list_devices();
    if (devices.empty() || std::any_of(devices.begin(), devices.end(), [](const voxmesh::DeviceInfo& d) {
            return d.type != voxmesh::DeviceType::Cpu;
        })) {
        WARN("not only CPU OpenCL devices: SKIPPED");
        return;
    }
    iotest::Scratch s;
    const std::string args = "mesh " + quote(data_file("headsq.nrrd")) + " --iso 499.5 --backend hybrid -o " +
                             quote(s.dir + "/o.stl");
    for (const std::string json : {"", " --json"}) {
        const vmtest::ProgramResult r = vmtest::run_program(VOXMESH_CLI_PATH, args + json, s.dir);
        INFO(r.err << r.out);
        CHECK(r.code == 0);
        const std::string said = r.err + r.out;
        CHECK(said.find("name one with --device to use it anyway") != std::string::npos);
        CHECK(said.find("Options::") == std::string::npos);
        CHECK(said.find("device_type") == std::string::npos);
    }
#endif
}

// info's report and mesh --json are the output: lost to a full disk they exited 0.
TEST_CASE("cli: a report that cannot be written to standard output is an error", "[cli]") {
    iotest::Scratch s;
    const std::string voxmesh = quote(VOXMESH_CLI_PATH), head = quote(data_file("headsq.nrrd"));
    const std::string err = " 2> " + quote(s.dir + "/err.txt");
    CHECK(shell(voxmesh + " info " + head + " > /dev/full" + err) == 2);
    CHECK(iotest::read_file(s.dir + "/err.txt").find("cannot write standard output") != std::string::npos);
    CHECK(shell(voxmesh + " mesh " + head + " --iso 499.5 --json -o " + quote(s.dir + "/o.stl") + " > /dev/full" + err) == 2);
    CHECK(shell(voxmesh + " info " + head + " > /dev/null" + err) == 0);
}

// fs::temp_directory_path() threw for these: "internal error: filesystem error", exit 1.
TEST_CASE("cli: standard input with TMPDIR empty or missing", "[cli]") {
    iotest::Scratch s;
    const std::string args = "info - < " + quote(data_file("headsq.nrrd"));
    const vmtest::ProgramResult empty = vmtest::run_program(VOXMESH_CLI_PATH, args, s.dir, "TMPDIR=");
    CHECK(empty.code == 0);  // as unset: /tmp
    CHECK(empty.out.find("64x64x93") != std::string::npos);
    const vmtest::ProgramResult missing =
        vmtest::run_program(VOXMESH_CLI_PATH, args, s.dir, "TMPDIR=" + quote(s.dir + "/missing"));
    CHECK(missing.code == 2);
    CHECK(missing.err.find("internal error") == std::string::npos);
    CHECK(missing.err.find(s.dir + "/missing") != std::string::npos);
}

// 0.5 * (min + max) overflowed: iso inf, an empty mesh, exit 0, and "iso": inf in the JSON.
TEST_CASE("cli: the default iso of samples near the largest double is finite", "[cli]") {
    iotest::Scratch s;
    std::vector<double> samples(27, 1.0e308);
    samples[13] = 1.7e308;
    std::string bytes(samples.size() * sizeof(double), '\0');
    std::memcpy(bytes.data(), samples.data(), bytes.size());
    const std::string raw = s.file("big.raw", bytes);
    const vmtest::ProgramResult r = vmtest::run_program(
        VOXMESH_CLI_PATH, "mesh " + quote(raw) + " --dims 3 3 3 --type f64 --json -o " + quote(s.dir + "/o.stl"), s.dir);
    INFO(r.err);
    CHECK(r.code == 0);
    CHECK(r.out.find("\"iso\": 1.35e+308") != std::string::npos);
    CHECK(r.out.find("\"triangles\": 8,") != std::string::npos);  // the octahedron around the centre sample
    CHECK(r.err.find("no surface") == std::string::npos);
}

// CLI11 converts integers with base 0: --resolution 016 passed the check as 16 and ran as 14,
// --dims 010 read 8 samples, --threads 010 ran 8, and 0x10 was 16 where --resolution refused it.
TEST_CASE("cli: whole-number options are decimal", "[cli]") {
    iotest::Scratch s;
    const std::string model = quote(data_file("torus.stl")), out = quote(s.dir + "/o.nrrd");
    const vmtest::ProgramResult padded =
        vmtest::run_program(VOXMESH_CLI_PATH, "voxelize " + model + " -o " + out + " --resolution 016 --padding 02", s.dir);
    CHECK(padded.code == 0);
    CHECK(padded.out.find("20x20x10") != std::string::npos);  // as --resolution 16 --padding 2
    const std::string raw = s.file("k.raw", std::string(1000, '\x01'));
    const vmtest::ProgramResult dims =
        vmtest::run_program(VOXMESH_CLI_PATH, "info " + quote(raw) + " --dims 010 010 010 --type u8", s.dir);
    CHECK(dims.code == 0);
    CHECK(dims.out.find("10x10x10") != std::string::npos);
    const std::string head = quote(data_file("headsq.nrrd"));
    const vmtest::ProgramResult threads = vmtest::run_program(
        VOXMESH_CLI_PATH, "mesh " + head + " --backend cpu --threads 010 -o " + quote(s.dir + "/o.stl"), s.dir);
    CHECK(threads.code == 0);
    CHECK(threads.out.find("(10 threads") != std::string::npos);
    for (const char* bad : {"--threads 0x10", "--threads -1", "--device 0x1", "--offset 0x10 --dims 2 2 2 --type u8"}) {
        const vmtest::ProgramResult r =
            vmtest::run_program(VOXMESH_CLI_PATH, "mesh " + quote(raw) + " -o " + quote(s.dir + "/o.stl") + " " + bad, s.dir);
        INFO(bad << ": " << r.err);
        CHECK(r.code == 2);
        CHECK((r.err.find("is not a whole number") != std::string::npos || r.err.find("out of range") != std::string::npos));
    }
}

// Real numbers too: CLI11 converts them with strtold, which took hex (--iso 0x10 ran at 16),
// leading blanks, and an exponent past the range as inf.
TEST_CASE("cli: real-number options are decimal", "[cli]") {
    iotest::Scratch s;
    const std::string raw = s.file("k.raw", std::string(1000, '\x01'));
    const std::string out = quote(s.dir + "/o.stl");
    const std::string head = quote(data_file("headsq.nrrd"));
    for (const char* bad : {"--iso 0x10", "--iso ' 5'", "--iso 1e400", "--iso +-1"}) {
        const vmtest::ProgramResult r = vmtest::run_program(VOXMESH_CLI_PATH, "mesh " + head + " -o " + out + " " + bad, s.dir);
        INFO(bad << ": " << r.err);
        CHECK(r.code == 2);
        CHECK((r.err.find("is not a decimal number") != std::string::npos || r.err.find("out of range") != std::string::npos));
    }
    for (const char* bad : {"--spacing 0x1 1 1", "--origin 0 0 0x1p3"}) {
        const vmtest::ProgramResult r =
            vmtest::run_program(VOXMESH_CLI_PATH, "info " + quote(raw) + " --dims 10 10 10 --type u8 " + bad, s.dir);
        INFO(bad << ": " << r.err);
        CHECK(r.code == 2);
        CHECK(r.err.find("is not a decimal number") != std::string::npos);
    }
    const vmtest::ProgramResult plus =
        vmtest::run_program(VOXMESH_CLI_PATH, "mesh " + head + " --backend cpu --iso +499.5 -o " + out, s.dir);
    CHECK(plus.code == 0);
    CHECK(plus.out.find("iso 499.5") != std::string::npos);
    const vmtest::ProgramResult spaced = vmtest::run_program(
        VOXMESH_CLI_PATH, "info " + quote(raw) + " --dims 10 10 10 --type u8 --spacing 0.5 2e0 1 --origin -1 1e-400 3", s.dir);
    CHECK(spaced.code == 0);
    CHECK(spaced.out.find("0.5 2 1") != std::string::npos);
    CHECK(spaced.out.find("-1 0 3") != std::string::npos);  // an exponent below the range is 0, as strtod reads it
}

// Found by a review: the decimal check handed CLI11 the shortest form of the double it read,
// which CLI11's strtold-then-double reads as the next double for about 1 in 10^4 values:
// --iso 6.4496454125996075e-280 (or its shortest form) missed a sample of exactly that value.
TEST_CASE("cli: a decimal real number reaches the command as the double it names", "[cli]") {
    iotest::Scratch s;
    const double d = 6.4496454125996075e-280;  // shortest form 6.449645412599608e-280
    std::string samples(27 * sizeof(double), '\0');
    std::memcpy(&samples[13 * sizeof(double)], &d, sizeof d);  // the centre sample, inside at iso d
    const std::string raw = s.file("d.raw", samples);
    for (const char* iso : {"6.4496454125996075e-280", "6.449645412599608e-280"}) {
        const vmtest::ProgramResult r = vmtest::run_program(
            VOXMESH_CLI_PATH,
            "mesh " + quote(raw) + " --dims 3 3 3 --type f64 --backend cpu --json --iso " + iso + " -o " +
                quote(s.dir + "/o.stl"),
            s.dir);
        INFO(iso << ": " << r.err << r.out);
        CHECK(r.code == 0);
        CHECK(r.out.find("\"triangles\": 8") != std::string::npos);
    }
}

// Options that would have been ignored: --endian for a file with a header, --device where no
// OpenCL device is used.
TEST_CASE("cli: --endian without .raw input and --device with --backend cpu are refused", "[cli]") {
    iotest::Scratch s;
    const std::string head = quote(data_file("headsq.nrrd")), out = quote(s.dir + "/o.stl");
    const vmtest::ProgramResult endian =
        vmtest::run_program(VOXMESH_CLI_PATH, "mesh " + head + " --iso 499.5 --endian big -o " + out, s.dir);
    CHECK(endian.code == 2);
    CHECK(endian.err.find("--endian") != std::string::npos);
    CHECK(endian.err.find("apply only to .raw input") != std::string::npos);
    const vmtest::ProgramResult info = vmtest::run_program(VOXMESH_CLI_PATH, "info " + head + " --endian little", s.dir);
    CHECK(info.code == 2);
    for (const std::string& command :
         {"mesh " + head + " --iso 499.5 --backend cpu --device 0 -o " + out,
          "sculpt " + quote(data_file("torus.stl")) + " --resolution 16 --device 0 -o " + out}) {
        const vmtest::ProgramResult r = vmtest::run_program(VOXMESH_CLI_PATH, command, s.dir);
        INFO(command << ": " << r.err);
        CHECK(r.code == 2);
        CHECK(r.err.find("--device 0 picks an OpenCL device, which the cpu backend does not use; ") != std::string::npos);
        // sculpt's backend is cpu unless one is given: the message says so.
        CHECK((command.rfind("sculpt", 0) != 0 || r.err.find("it is sculpt's default") != std::string::npos));
    }
    CHECK(!fs::exists(s.dir + "/o.stl"));
    // Raw input still takes --endian.
    const std::string raw = s.file("k.raw", std::string(16, '\x01'));
    const vmtest::ProgramResult big =
        vmtest::run_program(VOXMESH_CLI_PATH, "info " + quote(raw) + " --dims 2 2 2 --type u16 --endian big", s.dir);
    CHECK(big.code == 0);
    CHECK(big.out.find("big endian") != std::string::npos);
}


// A directory the output cannot be made in was found only when the mesh was written, after
// all the work (minutes for a large volume); now before the input is read.
TEST_CASE("cli: an output in a directory it may not write is refused before the work", "[cli]") {
    iotest::Scratch s;
    fs::permissions(s.dir, fs::perms::all, fs::perm_options::add);  // nobody may reach the input
    const std::string input = s.dir + "/head.nrrd";
    fs::copy_file(data_file("headsq.nrrd"), input);
    fs::permissions(input, fs::perms::others_read, fs::perm_options::add);
    const std::string ro = s.dir + "/ro";
    fs::create_directory(ro);
    fs::permissions(ro, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                            fs::perms::others_read | fs::perms::others_exec);
    const std::string out = ro + "/o.stl", err = s.dir + "/err.txt";
    int code = -1;
    if (::geteuid() == 0) {
        // Root writes anything: the tool runs as nobody, for whom ro is read-only.
        const int err_fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        REQUIRE(err_fd >= 0);
        const pid_t child = ::fork();
        REQUIRE(child >= 0);
        if (child == 0) {
            if (::setgid(65534) != 0 || ::setuid(65534) != 0 || ::dup2(err_fd, STDERR_FILENO) < 0) ::_exit(99);
            ::execl(VOXMESH_CLI_PATH, "voxmesh", "mesh", input.c_str(), "--iso", "499.5", "-o", out.c_str(),
                    static_cast<char*>(nullptr));
            ::_exit(98);
        }
        ::close(err_fd);
        int status = 0;
        REQUIRE(::waitpid(child, &status, 0) == child);
        REQUIRE(WIFEXITED(status));
        code = WEXITSTATUS(status);
        if (code == 99 || code == 98) {
            WARN("cannot run the tool as nobody here");
            return;
        }
    } else {
        fs::permissions(ro, fs::perms::owner_write, fs::perm_options::remove);
        code = shell(quote(VOXMESH_CLI_PATH) + " mesh " + quote(input) + " --iso 499.5 -o " + quote(out) + " 2> " +
                     quote(err));
        fs::permissions(ro, fs::perms::owner_write, fs::perm_options::add);
    }
    CHECK(code == 2);
    const std::string message = iotest::read_file(err);
    INFO(message);
    // check_writable's words: the write itself says "cannot create a temporary file".
    CHECK(message.find("'" + out + "': cannot create a file in '" + ro + "' (Permission denied)") != std::string::npos);
    CHECK(vmtest::directory_entries(ro).empty());
}


// JSON text is UTF-8: a file name's bytes that are not (another encoding) made json.load fail.
TEST_CASE("cli: --json names a file whose name is not UTF-8 in valid UTF-8", "[cli]") {
    iotest::Scratch s;
    // 0xff and a lone continuation byte are no UTF-8; e-acute (C3 A9) and a 4-byte emoji are.
    const std::string name = "h\xff\x80\xc3\xa9\xf0\x9f\x99\x82.nrrd";
    fs::copy_file(data_file("headsq.nrrd"), s.dir + "/" + name);
    const vmtest::ProgramResult r = vmtest::run_program(
        VOXMESH_CLI_PATH, "mesh " + quote(s.dir + "/" + name) + " --iso 499.5 --json -o " + quote(s.dir + "/o.stl"), s.dir);
    INFO(r.err);
    CHECK(r.code == 0);
    CHECK(r.out.find("h\\ufffd\\ufffd\xc3\xa9\xf0\x9f\x99\x82.nrrd\"") != std::string::npos);
}


// A gzip-compressed file on standard input was taken for a .nii.gz, and a .stl.gz or .nrrd.gz
// refused as "sizeof_hdr is ..., not a NIfTI-1 file".
TEST_CASE("cli: a compressed file on standard input that is not a NIfTI says so", "[cli]") {
    iotest::Scratch s;
    for (const char* name : {"torus.stl", "headsq.nrrd"}) {
        const std::string gz = s.file(std::string(name) + ".gz", iotest::deflate_bytes(iotest::read_file(data_file(name)), true));
        const vmtest::ProgramResult r = vmtest::run_program(VOXMESH_CLI_PATH, "info - < " + quote(gz), s.dir);
        INFO(name << ": " << r.err);
        CHECK(r.code == 2);
        CHECK(r.err.find("gzip-compressed, and not a NIfTI-1 header inside") != std::string::npos);
        CHECK(r.err.find("sizeof_hdr") == std::string::npos);
    }
    const vmtest::ProgramResult nifti =
        vmtest::run_program(VOXMESH_CLI_PATH, "info - < " + quote(data_file("mri_someones_anatomy.nii.gz")), s.dir);
    CHECK(nifti.code == 0);
    CHECK(nifti.out.find("nifti (gzip") != std::string::npos);
}


// The library's advice named its API ("use Backend::Cpu, Backend::Auto"), not the options.
TEST_CASE("cli: advice about backends names the options", "[cli]") {
    iotest::Scratch s;
    const vmtest::ProgramResult r =
        vmtest::run_program(VOXMESH_CLI_PATH,
                            "mesh " + quote(data_file("headsq.nrrd")) + " --iso 499.5 --backend opencl -o " +
                                quote(s.dir + "/o.stl"),
                            s.dir, "OCL_ICD_VENDORS=" + quote(s.dir + "/no-vendors"));
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("Backend::") == std::string::npos);
    CHECK((r.err.find("--backend cpu") != std::string::npos || r.err.find("the cpu backend") != std::string::npos));
}


// A VOXMESH_ISA other than portable (a typo such as "portble") ran the AVX2 code without a word.
TEST_CASE("cli: an unknown VOXMESH_ISA is named, portable in any case is not", "[cli]") {
    iotest::Scratch s;
    const std::string args = "mesh " + quote(data_file("headsq.nrrd")) + " --iso 499.5 --backend cpu -o " + quote(s.dir + "/o.stl");
    const vmtest::ProgramResult typo = vmtest::run_program(VOXMESH_CLI_PATH, args, s.dir, "VOXMESH_ISA=portble");
    CHECK(typo.code == 0);
    CHECK(typo.err.find("VOXMESH_ISA='portble' is not 'portable', 'popcnt' or 'native'; ignored") != std::string::npos);
    for (const char* fine : {"PORTABLE", "portable", "Popcnt", "native", ""}) {
        const vmtest::ProgramResult r =
            vmtest::run_program(VOXMESH_CLI_PATH, args, s.dir, "VOXMESH_ISA=" + quote(fine));
        INFO(fine);
        CHECK(r.code == 0);
        CHECK(r.err.find("VOXMESH_ISA") == std::string::npos);
    }
}

// An iso outside the data (the MRI's stored values are 0..255; 499.5 is a CT's skin) gave
// "no surface at iso 499.5" with nothing to say why: the warning names the range and the side.
TEST_CASE("cli: no surface names the samples' range", "[cli]") {
    iotest::Scratch s;
    const std::string mri = quote(data_file("mri_someones_anatomy.nii.gz")), out = " -o " + quote(s.dir + "/o.stl");
    const vmtest::ProgramResult above = vmtest::run_program(VOXMESH_CLI_PATH, "mesh " + mri + " --iso 499.5" + out, s.dir);
    INFO(above.err);
    CHECK(above.code == 0);
    CHECK(above.err.find("no surface at iso 499.5") != std::string::npos);
    CHECK(above.err.find("range 0 .. 255, all below the iso") != std::string::npos);
    const vmtest::ProgramResult below = vmtest::run_program(VOXMESH_CLI_PATH, "mesh " + mri + " --iso 0" + out, s.dir);
    INFO(below.err);
    CHECK(below.err.find("range 0 .. 255, all at or above the iso") != std::string::npos);
}

#endif
