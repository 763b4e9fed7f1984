#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "support/io_scratch.hpp"

using Catch::Matchers::Contains;
using namespace voxmesh;

namespace {

using iotest::Scratch;

std::string i16_samples(std::size_t count, bool big_endian) {
    std::string out;
    for (std::size_t i = 0; i < count; ++i) {
        const auto v = static_cast<std::uint16_t>(static_cast<std::int16_t>(i * 7 - 100));
        const char lo = static_cast<char>(v & 0xff), hi = static_cast<char>(v >> 8);
        out += big_endian ? hi : lo;
        out += big_endian ? lo : hi;
    }
    return out;
}

void check_i16(const Volume& v, std::size_t count) {
    REQUIRE(v.type == ScalarType::I16);
    REQUIRE(v.sample_count() == count);
    const auto* s = static_cast<const std::int16_t*>(v.data);
    for (std::size_t i = 0; i < count; ++i) REQUIRE(s[i] == static_cast<std::int16_t>(i * 7 - 100));
}

const std::string kHeader343 = "NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 5\nendian: little\n";

// 4x3x2 samples of type T whose value names their index: x + 10*y + 100*z.
constexpr std::array<std::size_t, 3> kDims432{4, 3, 2};
template <class T>
std::string indexed_samples(bool big_endian) {
    std::string out;
    for (std::size_t z = 0; z < 2; ++z)
        for (std::size_t y = 0; y < 3; ++y)
            for (std::size_t x = 0; x < 4; ++x) {
                const auto value = static_cast<T>(x + 10 * y + 100 * z);
                char b[sizeof(T)];
                std::memcpy(b, &value, sizeof(T));
                if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
                out.append(b, sizeof(T));
            }
    return out;
}

// Sample (i,j,k) is the file's (n-1-i, j, k) on each flipped axis.
template <class T>
void check_indexed(const Volume& v, std::array<bool, 3> flipped) {
    REQUIRE(v.dims == kDims432);
    const auto* s = static_cast<const T*>(v.data);
    iotest::for_each_sample_of_file(kDims432, flipped, [&](std::size_t at, std::array<std::size_t, 3> f) {
        INFO("sample " << at);
        REQUIRE(s[at] == static_cast<T>(f[0] + 10 * f[1] + 100 * f[2]));
    });
}

}  // namespace

TEST_CASE("nrrd: an axis in the negative direction is reversed from the minimum corner", "[io][nrrd]") {
    Scratch s;
    const std::string space = "space: left-posterior-superior\nspace origin: (10,20,30)\n";
    const std::string short_432 = "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 2\n";
    const std::string x_down = "space directions: (-2,0,0) (0,1,0) (0,0,1)\n";
    auto check_x_flip = [](const std::string& path) {
        const Volume v = read_volume(path);
        check_indexed<std::int16_t>(v, {true, false, false});
        CHECK(v.spacing == std::array<double, 3>{2, 1, 1});
        CHECK(v.origin == std::array<double, 3>{10 - 2 * 3, 20, 30});  // sample 3 of the file's x
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.flipped == std::array<bool, 3>{true, false, false});
        CHECK_FALSE(info.rotation_dropped);
        CHECK(info.spacing == v.spacing);
        CHECK(info.origin == v.origin);
        // read_volume with an info: the same samples, and what read_volume_info says.
        VolumeInfo read_along;
        check_indexed<std::int16_t>(read_volume(path, read_along), {true, false, false});
        CHECK(read_along.flipped == info.flipped);
        CHECK(read_along.origin == info.origin);
        CHECK(read_along.spacing == info.spacing);
        CHECK(read_along.file_bytes == info.file_bytes);
        CHECK(read_along.data_file == info.data_file);
        CHECK(read_along.encoding == info.encoding);
    };
    SECTION("detached raw (memory-mapped): the file is not changed") {
        const std::string samples = indexed_samples<std::int16_t>(false);
        const std::string data = s.file("x.raw", samples);
        check_x_flip(
            s.file("x.nhdr", short_432 + "endian: little\nencoding: raw\ndata file: x.raw\n" + space + x_down));
        CHECK(iotest::read_file(data) == samples);
    }
    SECTION("attached gzip, big endian") {
        check_x_flip(s.file("x.nrrd", short_432 + "endian: big\nencoding: gzip\n" + space + x_down + "\n" +
                                          iotest::deflate_bytes(indexed_samples<std::int16_t>(true), true)));
    }
    SECTION("y and z down, 1- and 8-byte samples") {
        const std::string yz_down = "space directions: (0.5,0,0) (0,-1,0) (0,0,-3)\n";
        const std::string u8 = s.file("u8.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 3 2\nencoding: raw\n" +
                                                     space + yz_down + "\n" + indexed_samples<std::uint8_t>(false));
        check_indexed<std::uint8_t>(read_volume(u8), {false, true, true});
        const std::string f64 =
            s.file("f64.nrrd", "NRRD0004\ntype: double\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\n" +
                                   space + yz_down + "\n" + indexed_samples<double>(false));
        const Volume v = read_volume(f64);
        check_indexed<double>(v, {false, true, true});
        CHECK(v.origin == std::array<double, 3>{10, 20 - 1 * 2, 30 - 3 * 1});
        CHECK(read_volume_info(f64).flipped == std::array<bool, 3>{false, true, true});
    }
    SECTION("a negative 'spacings' value runs its axis down from 0") {
        const std::string path =
            s.file("n.nrrd", short_432 + "endian: little\nencoding: raw\nspacings: 2 -0.5 nan\n\n" +
                                 indexed_samples<std::int16_t>(false));
        const Volume v = read_volume(path);
        check_indexed<std::int16_t>(v, {false, true, false});
        CHECK(v.spacing == std::array<double, 3>{2, 0.5, 1});
        CHECK(v.origin == std::array<double, 3>{0, -0.5 * 2, 0});  // the file's y sample 2
        CHECK(read_volume_info(path).flipped == std::array<bool, 3>{false, true, false});
    }
    SECTION("positive directions and plain spacings are not flipped") {
        const std::string path = s.file("p.nrrd", short_432 + "endian: little\nencoding: raw\n" + space +
                                                      "space directions: (2,0,0) (0,1,0) (0,0,1)\n\n" +
                                                      indexed_samples<std::int16_t>(false));
        const Volume v = read_volume(path);
        check_indexed<std::int16_t>(v, {false, false, false});
        CHECK(v.origin == std::array<double, 3>{10, 20, 30});
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.flipped == std::array<bool, 3>{false, false, false});
        CHECK_FALSE(info.rotation_dropped);
    }
}

TEST_CASE("nrrd: real headsq CT reads as 64x64x93 i16", "[io][nrrd]") {
    const std::string path = std::string(VOXMESH_TEST_DATA) + "/headsq.nrrd";
    const VolumeInfo info = read_volume_info(path);
    CHECK(info.format == "nrrd");
    CHECK(info.encoding == "gzip");
    CHECK(info.type == ScalarType::I16);
    CHECK(info.dims == std::array<std::size_t, 3>{64, 64, 93});
    CHECK(info.file_bytes == 425434);

    const Volume v = read_volume(path);
    CHECK(v.type == ScalarType::I16);
    CHECK(v.dims == std::array<std::size_t, 3>{64, 64, 93});
    CHECK(v.spacing[0] == Approx(3.2));
    CHECK(v.spacing[1] == Approx(3.2));
    CHECK(v.spacing[2] == Approx(1.5));
    CHECK(v.origin == std::array<double, 3>{0, 0, 0});
    const auto* s = static_cast<const std::int16_t*>(v.data);
    std::int16_t lo = s[0], hi = s[0];
    double sum = 0;
    for (std::size_t i = 0; i < v.sample_count(); ++i) {
        lo = std::min(lo, s[i]);
        hi = std::max(hi, s[i]);
        sum += s[i];
    }
    CHECK(lo == 0);
    CHECK(hi == 3926);
    CHECK(sum / static_cast<double>(v.sample_count()) == Approx(507.7).margin(0.05));
}

TEST_CASE("nrrd: write_nrrd round trip is memory-mapped and exact", "[io][nrrd]") {
    Scratch s;
    std::vector<float> samples(6 * 5 * 4);
    for (std::size_t i = 0; i < samples.size(); ++i) samples[i] = static_cast<float>(i) * 0.25f - 3.0f;
    VolumeView view{samples.data(), ScalarType::F32, {6, 5, 4}, {0.5, 0.75, 1.25}, {-1.5, 2.0, 1e-3}};
    const std::string path = s.dir + "/out.nrrd";
    write_nrrd(path, view);
    CHECK_FALSE(std::filesystem::exists(s.dir + "/.out.nrrd.tmp"));

    const Volume v = read_volume(path);
    CHECK(v.type == ScalarType::F32);
    CHECK(v.dims == view.dims);
    CHECK(v.spacing == view.spacing);
    CHECK(v.origin == view.origin);
    CHECK(std::memcmp(v.data, samples.data(), samples.size() * 4) == 0);
    const VolumeInfo info = read_volume_info(path);
    CHECK(info.encoding == "raw");

    // Data at an aligned offset in host order is mapped: /proc/self/maps lists the file.
    std::ifstream maps("/proc/self/maps");
    bool mapped = false;
    for (std::string line; std::getline(maps, line);) {
        if (line.find(std::filesystem::canonical(path).string()) == std::string::npos) continue;
        unsigned long long lo = 0, hi = 0;
        std::sscanf(line.c_str(), "%llx-%llx", &lo, &hi);
        const auto p = reinterpret_cast<std::uintptr_t>(v.data);
        mapped = mapped || (p >= lo && p < hi);
    }
    CHECK(mapped);
}

TEST_CASE("nrrd: write_nrrd refuses bad views and missing directories", "[io][nrrd]") {
    Scratch s;
    float one = 1;
    CHECK_THROWS_WITH(write_nrrd(s.dir + "/no/such/dir/x.nrrd", VolumeView{&one, ScalarType::F32, {1, 1, 1}}),
                      Contains("x.nrrd") && Contains("does not exist"));
    CHECK_THROWS_WITH(write_nrrd(s.dir + "/x.nrrd", VolumeView{nullptr, ScalarType::F32, {1, 1, 1}}),
                      Contains("no data"));
    CHECK_THROWS_WITH(write_nrrd(s.dir + "/x.nrrd", VolumeView{&one, ScalarType::F32, {0, 1, 1}}), Contains("empty"));
    // Samples past the float range: read_volume would refuse the file (found by
    // fuzz_nrrd_roundtrip: the writer wrote what the reader then refused).
    CHECK_THROWS_WITH(write_nrrd(s.dir + "/x.nrrd", VolumeView{&one, ScalarType::F32, {1, 1, 1}, {1, 1, 1}, {-1e308, 0, 0}}),
                      Contains("along x") && Contains("float"));
    std::vector<float> two(2, 1.0f);
    CHECK_THROWS_WITH(write_nrrd(s.dir + "/x.nrrd", VolumeView{two.data(), ScalarType::F32, {1, 1, 2}, {1, 1, -3e38}, {0, 0, -1e38}}),
                      Contains("along z"));
    CHECK_FALSE(std::filesystem::exists(s.dir + "/x.nrrd"));
}

TEST_CASE("nrrd: key/values read back exactly, or write_nrrd refuses them", "[io][nrrd]") {
    Scratch s;
    std::vector<std::uint8_t> samples(8, 1);
    const VolumeView view{samples.data(), ScalarType::U8, {2, 2, 2}};
    const std::string path = s.dir + "/kv.nrrd";
    const std::map<std::string, std::string> fine{{"a:", " spaced value "}, {"voxmesh_iso", "127.5"}, {"k", ""},
                                                  {"odd=key", "x:=y: z"}};
    write_nrrd(path, view, fine);
    CHECK(read_volume_info(path).key_values == fine);
    // Each would read back as something else (found by fuzz_nrrd_roundtrip: a '#' key came
    // back as a comment, that is, not at all).
    for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
             {"#comment", "v"}, {"a: b", "v"}, {"a:=b", "v"}, {"", "v"}, {"k", "line\r"}, {"k", "two\nlines"},
             {"k\r", "v"}, {"k", std::string(std::size_t{1} << 20, 'x')}}) {
        INFO("key '" << key << "'");
        CHECK_THROWS_AS(write_nrrd(s.dir + "/bad.nrrd", view, {{key, value}}), Error);
    }
    CHECK_FALSE(std::filesystem::exists(s.dir + "/bad.nrrd"));
}

// Found by a review: NRRD key/values are escaped ("\\n" a line break, "\\\\" a backslash, as
// teem's airUnescape reads them); backslashes were written and read as they were, so teem read
// "C:\\new" as "C:", a line break and "ew", and a teem-written backslash came back doubled.
TEST_CASE("nrrd: key/values are escaped as teem writes and reads them", "[io][nrrd]") {
    Scratch s;
    std::vector<std::uint8_t> samples(8, 1);
    const VolumeView view{samples.data(), ScalarType::U8, {2, 2, 2}};
    const std::string path = s.dir + "/kv.nrrd";
    const std::map<std::string, std::string> kv{{"source", "C:\\new\\n"}, {"back\\slash", "\\"}};
    write_nrrd(path, view, kv);
    const std::string text = iotest::read_file(path);
    CHECK_THAT(text, Contains("\nsource:=C:\\\\new\\\\n\n") && Contains("\nback\\\\slash:=\\\\\n"));
    CHECK(read_volume_info(path).key_values == kv);
    const std::string teem = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
                             "note:=line 1\\nline 2 in C:\\\\dir, \\t kept\n\n" + std::string(8, '\1');
    CHECK(read_volume_info(s.file("teem.nrrd", teem)).key_values.at("note") == "line 1\nline 2 in C:\\dir, \\t kept");
}

TEST_CASE("nrrd: recorded_iso reads voxmesh_iso as one finite number, or refuses it naming the file", "[io][nrrd]") {
    VolumeInfo info;
    CHECK_FALSE(recorded_iso(info, "a.nrrd").has_value());  // no key: none recorded
    for (const auto& [text, value] : std::vector<std::pair<std::string, double>>{
             {"0", 0.0}, {"127.5", 127.5}, {"-2.5e-3", -2.5e-3}, {"1e300", 1e300}}) {
        info.key_values[kRecordedIsoKey] = text;
        CHECK(recorded_iso(info, "a.nrrd") == value);
    }
    for (const char* bad : {"", " 1", "1 ", "1abc", "nan", "inf", "-inf", "1e400", "0x10", "zero"}) {
        INFO("'" << bad << "'");
        info.key_values[kRecordedIsoKey] = bad;
        CHECK_THROWS_WITH(recorded_iso(info, "a.nrrd"), "'a.nrrd': its voxmesh_iso ('" + std::string(bad) +
                                                            "') is not a finite number");
    }
}

TEST_CASE("nrrd: spacings far from 1 read back exactly, tiny and huge", "[io][nrrd]") {
    // Their squares underflow to 0: the length of a direction vector
    // (1e-300, 0, 0) was read as 0 and refused (found by fuzz_nrrd_roundtrip).
    Scratch s;
    std::vector<std::uint8_t> samples(2 * 2 * 2, 7);
    for (const std::array<double, 3>& spacing : {std::array<double, 3>{1e-300, 1, 7}, std::array<double, 3>{1e-160, 2e-170, 3},
                                                 std::array<double, 3>{3e38, 1e-3, 1e30}}) {
        INFO(spacing[0] << " " << spacing[1] << " " << spacing[2]);
        const VolumeView view{samples.data(), ScalarType::U8, {2, 2, 2}, spacing, {0, 0, 0}};
        const std::string path = s.dir + "/far.nrrd";
        write_nrrd(path, view);
        const Volume v = read_volume(path);
        CHECK(v.spacing == spacing);
    }
}

TEST_CASE("nrrd: encodings, byte orders, detached headers", "[io][nrrd]") {
    Scratch s;
    const std::size_t n = 3 * 4 * 5;
    SECTION("attached raw, header length odd: copied, not misaligned") {
        const std::string header = kHeader343 + "encoding: raw\n# pad\n\n";
        REQUIRE(header.size() % 2 == 1);
        check_i16(read_volume(s.file("a.nrrd", header + i16_samples(n, false))), n);
    }
    SECTION("attached raw, big endian") {
        const std::string header = "NRRD0005\ntype: int16\ndimension: 3\nsizes: 3 4 5\nendian: big\nencoding: raw\n\n";
        check_i16(read_volume(s.file("a.nrrd", header + i16_samples(n, true))), n);
    }
    SECTION("attached gzip with space directions and origin") {
        const std::string header = kHeader343 +
                                   "encoding: gzip\nspace: left-posterior-superior\n"
                                   "space directions: (0,2,0) (3,0,0) (0,0,-4)\nspace origin: (1.5,-2,3)\n\n";
        const std::string path = s.file("a.nrrd", header + iotest::deflate_bytes(i16_samples(n, false), true));
        const Volume v = read_volume(path);
        // x and y are swapped (dropped); z points down, so it is reversed from the minimum corner.
        REQUIRE(v.sample_count() == n);
        const auto* samples = static_cast<const std::int16_t*>(v.data);
        for (std::size_t i = 0; i < n; ++i) {
            const std::size_t file_i = i % 12 + 12 * (4 - i / 12);
            REQUIRE(samples[i] == static_cast<std::int16_t>(file_i * 7 - 100));
        }
        CHECK(v.spacing == std::array<double, 3>{2, 3, 4});
        CHECK(v.origin == std::array<double, 3>{1.5, -2, 3 - 4 * 4});
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.encoding == "gzip");
        CHECK(info.flipped == std::array<bool, 3>{false, false, true});
        CHECK(info.rotation_dropped);
        CHECK(info.origin == v.origin);
    }
    SECTION("detached raw with byte skip -1 (data at the end)") {
        s.file("d.raw", "JUNKJUNK!" + i16_samples(n, false));
        const std::string path =
            s.file("d.nhdr", kHeader343 + "encoding: raw\nbyte skip: -1\ndata file: d.raw\nspacings: 1 2 3\n");
        const Volume v = read_volume(path);
        check_i16(v, n);
        CHECK(v.spacing == std::array<double, 3>{1, 2, 3});
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.data_file == s.dir + "/d.raw");
    }
    SECTION("detached gzip with line skip") {
        s.file("d.gz", "line one\nline two\n" + iotest::deflate_bytes(i16_samples(n, false), true));
        check_i16(read_volume(s.file("d.nhdr", kHeader343 + "encoding: gz\nline skip: 2\ndatafile: d.gz\n")), n);
    }
    // Attached data with 'line skip' was refused; teem skips the lines after the blank line.
    SECTION("attached raw and gzip with line skip") {
        check_i16(read_volume(s.file("a.nrrd", kHeader343 + "encoding: raw\nline skip: 2\n\none\n\n" +
                                                   i16_samples(n, false))),
                  n);
        check_i16(read_volume(s.file("a.nrrd", kHeader343 + "encoding: gzip\nline skip: 1\n\n# a\n" +
                                                   iotest::deflate_bytes(i16_samples(n, false), true))),
                  n);
        CHECK_THROWS_WITH(read_volume(s.file("a.nrrd", kHeader343 + "encoding: raw\nline skip: 2\n\none line\n")),
                          Contains("a.nrrd") && Contains("before the 2 lines"));
        // Found by a review: lines end at "\r\n" and a lone "\r" too, as teem reads them; also
        // where the "\r" is the last byte of a 64 KiB chunk read.
        check_i16(read_volume(s.file("a.nrrd", kHeader343 + "encoding: raw\nline skip: 3\n\nmac\rdos\r\nunix\n" +
                                                   i16_samples(n, false))),
                  n);
        const std::string long_line(65535, 'x');
        for (const std::string end : {"\r", "\r\n", "\n"}) {
            s.file("d.raw", long_line + end + i16_samples(n, false));
            check_i16(read_volume(s.file("d.nhdr", kHeader343 + "encoding: raw\nline skip: 1\ndata file: d.raw\n")), n);
        }
    }
    SECTION("4-D with a trailing size-1 axis is 3-D") {
        const std::string header =
            "NRRD0004\ntype: short\ndimension: 4\nsizes: 3 4 5 1\nendian: little\nencoding: raw\n\n";
        check_i16(read_volume(s.file("a.nrrd", header + i16_samples(n, false))), n);
    }
    // Found by a review: a size-1 axis before x was refused, the error blaming axis 3.
    SECTION("4-D with a leading size-1 axis is 3-D, that axis's fields skipped") {
        const std::string header = "NRRD0004\ntype: short\ndimension: 4\nsizes: 1 3 4 5\nendian: little\n"
                                   "encoding: raw\nspace dimension: 3\n";
        check_i16(read_volume(s.file("a.nrrd", header + "\n" + i16_samples(n, false))), n);
        const Volume v = read_volume(s.file("a.nrrd", header + "space directions: none (2,0,0) (0,3,0) (0,0,4)\n\n" +
                                                          i16_samples(n, false)));
        check_i16(v, n);
        CHECK(v.dims == std::array<std::size_t, 3>{3, 4, 5});
        CHECK(v.spacing == std::array<double, 3>{2, 3, 4});
    }
}

// Found by a review: 'kinds' was not read, so an RGB image or a vector field would be meshed as
// if its components were a spatial axis.
// Found by a review: without a space, teem places samples by 'axis mins' (cell-centred unless
// 'centers' says node; the step from 'spacings', or from 'axis maxs'), which was ignored; and
// teem reads 'type' and 'endian' in any case.
TEST_CASE("nrrd: axis mins and maxs place the samples, type and endian in any case", "[io][nrrd]") {
    Scratch s;
    const std::size_t n = 3 * 4 * 5;
    const std::string head = "NRRD0004\ntype: Short\ndimension: 3\nsizes: 3 4 5\nendian: LITTLE\nencoding: raw\n";
    SECTION("mins with spacings, cell-centred: the first sample half a step in") {
        const Volume v = read_volume(s.file("a.nrrd", head + "spacings: 2 3 4\naxis mins: 10 20 30\n\n" +
                                                           i16_samples(n, false)));
        check_i16(v, n);
        CHECK(v.spacing == std::array<double, 3>{2, 3, 4});
        CHECK(v.origin == std::array<double, 3>{11, 21.5, 32});
    }
    SECTION("mins and maxs, one axis node-centred, one unknown") {
        const Volume v = read_volume(s.file("a.nrrd", head + "axis mins: 10 20 nan\naxis maxs: 16 32 50\n"
                                                           "centers: cell node ???\n\n" + i16_samples(n, false)));
        CHECK(v.spacing == std::array<double, 3>{2, 4, 1});
        CHECK(v.origin == std::array<double, 3>{11, 20, 0});
    }
    SECTION("a max below the min runs the axis the other way") {
        VolumeInfo info;
        const Volume v = read_volume(
            s.file("a.nrrd", head + "axis mins: 0 0 10\naxis maxs: 3 4 0\n\n" + i16_samples(n, false)), info);
        CHECK(v.spacing == std::array<double, 3>{1, 1, 2});
        CHECK(info.flipped == std::array<bool, 3>{false, false, true});
        CHECK(v.origin[2] == 1);  // samples at 9, 7, ..., 1: the minimum corner
    }
}

// Found by a review: teem reads "spacedirections", "spaceorigin", "axismins", "centerings" and
// its other joined spellings as the fields they name; they were ignored, so the volume came out
// at spacing 1 and origin 0 with no error.
TEST_CASE("nrrd: teem's joined field spellings are the fields they name", "[io][nrrd]") {
    Scratch s;
    const std::size_t n = 3 * 4 * 5;
    const std::string head = "NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 5\nendian: little\nencoding: raw\n";
    SECTION("spacedimension, spacedirections, spaceorigin") {
        const Volume v = read_volume(s.file("a.nrrd", head + "spacedimension: 3\n"
                                                           "spacedirections: (2,0,0) (0,3,0) (0,0,4)\n"
                                                           "SpaceOrigin: (5,6,7)\n\n" + i16_samples(n, false)));
        check_i16(v, n);
        CHECK(v.spacing == std::array<double, 3>{2, 3, 4});
        CHECK(v.origin == std::array<double, 3>{5, 6, 7});
    }
    SECTION("axismins, axismaxs, centerings") {
        const Volume v = read_volume(s.file("a.nrrd", head + "axismins: 10 20 30\naxismaxs: 12 26 38\n"
                                                           "centerings: node node node\n\n" + i16_samples(n, false)));
        CHECK(v.spacing == std::array<double, 3>{1, 2, 2});
        CHECK(v.origin == std::array<double, 3>{10, 20, 30});
    }
    SECTION("a field given in both spellings appears twice") {
        CHECK_THROWS_WITH(read_volume(s.file("a.nrrd", head + "space dimension: 3\nspaceorigin: (0,0,0)\n"
                                                              "space origin: (0,0,0)\n\n" + i16_samples(n, false))),
                          Contains("a.nrrd") && Contains("'space origin' appears twice"));
    }
}

// Found by a review: teem refuses a spacing only on an axis that has a direction vector, and
// "nan" is no spacing; such headers were refused whole as contradictory.
TEST_CASE("nrrd: spacings of nan beside space directions are no spacings, as in teem", "[io][nrrd]") {
    Scratch s;
    const std::size_t n = 3 * 4 * 5;
    const std::string head = "NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 5\nendian: little\nencoding: raw\n";
    const std::string directed = "space dimension: 3\nspace directions: (2,0,0) (0,3,0) (0,0,4)\n";
    const std::string samples = i16_samples(n, false);
    const Volume v = read_volume(s.file("a.nrrd", head + directed + "spacings: nan nan NaN\n\n" + samples));
    check_i16(v, n);
    CHECK(v.spacing == std::array<double, 3>{2, 3, 4});
    const std::string four = "NRRD0004\ntype: short\ndimension: 4\nsizes: 1 3 4 5\nendian: little\nencoding: raw\n"
                             "space dimension: 3\nspace directions: none (2,0,0) (0,3,0) (0,0,4)\n";
    const Volume w = read_volume(s.file("a.nrrd", four + "spacings: 1 nan nan nan\n\n" + samples));
    check_i16(w, n);
    CHECK(w.spacing == std::array<double, 3>{2, 3, 4});
    CHECK_THROWS_WITH(read_volume(s.file("a.nrrd", head + directed + "spacings: nan 3 nan\n\n" + samples)),
                      Contains("a.nrrd") && Contains("axis 1 has both") && Contains("contradictory"));
}

TEST_CASE("nrrd: axes of a kind that is not spatial are refused, or dropped where of size 1", "[io][nrrd]") {
    Scratch s;
    const std::size_t n = 3 * 4 * 5;
    const std::string data = i16_samples(n, false);
    auto header = [](const std::string& sizes, const std::string& kinds) {
        return "NRRD0004\ntype: short\ndimension: " + std::to_string(std::count(sizes.begin(), sizes.end(), ' ') + 1) +
               "\nsizes: " + sizes + "\nendian: little\nencoding: raw\nkinds: " + kinds + "\n\n";
    };
    const std::pair<std::string, std::string> accepted[] = {{"3 4 5", "domain SPACE Domain"},
                                                            {"3 4 5", "??? none space"},
                                                            {"3 4 5 1", "domain domain domain RGB-color"},
                                                            {"1 3 4 5", "stub space space space"},
                                                            {"3 4 1 5", "domain domain list domain"}};
    for (const auto& [sizes, kinds] : accepted) {
        INFO(sizes << " / " << kinds);
        const Volume v = read_volume(s.file("a.nrrd", header(sizes, kinds) + data));
        check_i16(v, n);
        CHECK(v.dims == std::array<std::size_t, 3>{3, 4, 5});
    }
    auto fails = [&](const std::string& text, const std::string& what) {
        const std::string path = s.file("bad.nrrd", text + data);
        CHECK_THROWS_WITH(read_volume(path), Contains(path) && Contains(what));
    };
    fails(header("3 4 5", "RGB-color domain domain"), "axis 0 (size 3) has kind 'RGB-color'");
    fails(header("3 4 5", "domain domain time"), "axis 2 (size 5) has kind 'time'");
    fails(header("3 4 5 2", "domain domain domain 2-vector"), "axis 3 (size 2) has kind '2-vector'");
    fails(header("3 3 4 5", "3-color domain domain domain"), "axis 0 (size 3) has kind '3-color'");
    fails(header("1 4 15", "stub domain domain"), "axis 0 (size 1) has kind 'stub'");
    fails(header("3 4 5", "domain domain"), "'kinds' lists 2 values");
}

TEST_CASE("nrrd: bad headers and data are errors naming the file", "[io][nrrd][errors]") {
    Scratch s;
    const std::size_t n = 3 * 4 * 5;
    const std::string data = i16_samples(n, false);
    auto attached = [&](const std::string& header, const std::string& body) { return s.file("bad.nrrd", header + body); };
    auto fails = [&](const std::string& path, const std::string& what) {
        CHECK_THROWS_WITH(read_volume(path), Contains(path) && Contains(what));
    };

    fails(attached("NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4\nendian: little\nencoding: raw\n\n", data),
          "'dimension' is 3 but 'sizes' lists 2");
    fails(attached("NRRD0004\ndimension: 3\nsizes: 3 4 5\nencoding: raw\n\n", data), "'type'");
    fails(attached("NRRD0004\ntype: complex\ndimension: 3\nsizes: 3 4 5\nencoding: raw\n\n", data),
          "unsupported NRRD type 'complex'");
    fails(attached("NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 5\nencoding: raw\n\n", data), "endian");
    fails(attached(kHeader343 + "encoding: bzip2\n\n", data), "encoding 'bzip2'");
    fails(attached(kHeader343 + "encoding: raw\nspacings: 1 1 1\nspace dimension: 3\n"
                                "space directions: (1,0,0) (0,1,0) (0,0,1)\n\n", data),
          "contradictory");
    fails(attached(kHeader343 + "encoding: raw\nspacings: 1 0 1\n\n", data), "spacing");
    // Finite doubles, but samples past FLT_MAX would mesh to inf coordinates.
    fails(attached(kHeader343 + "encoding: raw\nspacings: 1e300 1 1\n\n", data), "beyond the range of float");
    fails(attached(kHeader343 + "encoding: raw\nspace dimension: 3\nspace origin: (0,0,1e39)\n\n", data), "axis 2");
    CHECK_THROWS_WITH(read_volume_info(attached(kHeader343 + "encoding: raw\nspacings: 1 2e38 1\n\n", data)),
                      Contains("bad.nrrd") && Contains("axis 1"));
    fails(attached(kHeader343 + "encoding: raw\n\n", data.substr(0, data.size() - 3)), "truncated");
    fails(attached(kHeader343 + "encoding: raw\n\n", data + "xx"), "do not match");
    fails(attached(kHeader343 + "encoding: raw\nencoding: raw\n\n", data), "twice");
    fails(attached("NRRD0004\ntype: short\ndimension: 4\nsizes: 3 4 5 2\nendian: little\nencoding: raw\n\n", data),
          "sizes 3 4 5 2 have 4 axes longer than 1; only 3-D");
    fails(attached("NRRD0004\ntype: short\ndimension: 3\nsizes: 3 0 5\nendian: little\nencoding: raw\n\n", data),
          "empty");
    fails(attached("NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 5x\nendian: little\nencoding: raw\n\n", data),
          "'5x' is not");
    fails(s.file("bad.nrrd", "P5\n3 4\n255\n"), "not a NRRD file");
    fails(s.file("bad.nrrd", ""), "empty");
    fails(s.file("bad.nrrd", kHeader343 + "encoding: raw\n"), "no blank line");
    // Data file that is missing, or a directory.
    fails(s.file("bad.nhdr", kHeader343 + "encoding: raw\ndata file: nowhere.raw\n"), "nowhere.raw");
    CHECK_THROWS_WITH(read_volume(s.file("bad.nhdr", kHeader343 + "encoding: raw\ndata file: nowhere.raw\n")),
                      Contains("does not exist") && Contains("bad.nhdr"));
    std::filesystem::create_directory(s.dir + "/sub");
    fails(s.file("bad.nhdr", kHeader343 + "encoding: raw\ndata file: sub\n"), "directory");
    fails(s.file("bad.nhdr", kHeader343 + "encoding: raw\ndata file: LIST\nx.raw\n"), "LIST");
    // Found by a review: "LIST 3" (a list with a sub-dimension) said a line was not a field;
    // samples at the end of the file (byte skip -1) read the header as samples when too short.
    fails(s.file("bad.nhdr", kHeader343 + "encoding: raw\ndata file: LIST 3\nx.raw\n"), "a list of data files");
    fails(attached(kHeader343 + "encoding: raw\nbyte skip: -1\n\n", data.substr(0, data.size() - 20)),
          "may not overlap");
    // Found by a review: 'line skip' past the end of the data file, or with none, was an error that
    // did not name the header, and counted the lines left instead of those asked for.
    s.file("short.raw", "one line\n");
    const std::string of_header = "(data file of '" + s.dir + "/bad.nhdr')";
    const std::string skip3 = kHeader343 + "encoding: raw\nline skip: 3\n";
    CHECK_THROWS_WITH(read_volume(s.file("bad.nhdr", skip3 + "data file: short.raw\n")),
                      Contains("short.raw") && Contains(of_header) && Contains("before the 3 lines"));
    CHECK_THROWS_WITH(read_volume(s.file("bad.nhdr", skip3 + "data file: none.raw\n")),
                      Contains("none.raw") && Contains("does not exist") && Contains(of_header));

    // gzip: corrupt, truncated, longer or shorter than the sizes say.
    const std::string gz = iotest::deflate_bytes(data, true);
    std::string corrupt = gz;
    for (std::size_t i = 12; i < corrupt.size() - 8; ++i) corrupt[i] = static_cast<char>(corrupt[i] ^ 0x5a);
    fails(attached(kHeader343 + "encoding: gzip\n\n", corrupt), "corrupt compressed data");
    fails(attached(kHeader343 + "encoding: gzip\n\n", gz.substr(0, gz.size() / 2)), "ends early");
    fails(attached(kHeader343 + "encoding: gzip\n\n", iotest::deflate_bytes(data + "more", true)), "longer");
    fails(attached(kHeader343 + "encoding: gzip\n\n", iotest::deflate_bytes(data.substr(4), true)), "truncated data");
    fails(attached(kHeader343 + "encoding: gzip\n\n", gz + "trailing"), "unexpected data");
    fails(attached(kHeader343 + "encoding: gzip\n\n", gz + std::string(8, '\0') + "x"), "9 bytes of unexpected data");
    // Found by a review: zero bytes after the stream (padding, which gzip -d and nibabel skip)
    // were refused as unexpected data.
    CHECK(read_volume(attached(kHeader343 + "encoding: gzip\n\n", gz + std::string(8, '\0'))).sample_count() == 60);
    fails(attached(kHeader343 + "encoding: gzip\n\n", ""), "no compressed data");

    // Sizes that overflow, or that no memory or compressed stream could hold: refused up front.
    fails(attached("NRRD0004\ntype: double\ndimension: 3\nsizes: 4294967296 4294967296 4294967296\n"
                   "endian: little\nencoding: gzip\n\n", gz),
          "overflow");
    fails(attached("NRRD0004\ntype: double\ndimension: 3\nsizes: 100000 100000 100000\n"
                   "endian: little\nencoding: gzip\n\n", gz),
          "memory");
    fails(attached("NRRD0004\ntype: double\ndimension: 3\nsizes: 1000 1000 100\n"
                   "endian: little\nencoding: gzip\n\n", gz),
          "cannot hold");
    fails(attached("NRRD0004\ntype: double\ndimension: 3\nsizes: 100000 100000 100000\n"
                   "endian: little\nencoding: raw\n\n", data),
          "need exactly");
    // read_volume_info runs the same checks without loading.
    CHECK_THROWS_WITH(read_volume_info(attached(kHeader343 + "encoding: raw\n\n", data + "xx")), Contains("bad.nrrd"));
}

TEST_CASE("read_volume: unknown extensions, directories and missing files", "[io][errors]") {
    Scratch s;
    CHECK_THROWS_WITH(read_volume(s.file("x.vti", "abc")), Contains("x.vti") && Contains("unknown volume format") && Contains(".vtk or .npy)"));
    CHECK_THROWS_WITH(read_volume(s.file("x.raw", "abc")), Contains("x.raw") && Contains("--dims"));
    std::filesystem::create_directory(s.dir + "/d.nrrd");
    CHECK_THROWS_WITH(read_volume(s.dir + "/d.nrrd"), Contains("d.nrrd") && Contains("directory"));
    CHECK_THROWS_WITH(read_volume(s.dir + "/none.nii"), Contains("none.nii") && Contains("does not exist"));
    CHECK_THROWS_WITH(read_volume_info(s.dir + "/none.mha"), Contains("none.mha") && Contains("does not exist"));
}
