// NumPy .npy volumes: files numpy itself wrote (tests/fuzz_corpus/npy, made by
// tools/gen_npy_corpus.py) read with every sample in place whatever their order, byte order and
// format version; from memory the same; a volume saved by numpy meshes as the array it came
// from; broken files are errors naming the file.
#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include "support/io_scratch.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

using Catch::Matchers::Contains;
using namespace voxmesh;

namespace {

using iotest::Scratch;

constexpr std::array<std::size_t, 3> kDims{5, 4, 3};

std::string corpus(const std::string& name) { return std::string(VOXMESH_TEST_DATA) + "/../fuzz_corpus/npy/" + name; }

// The corpus's samples: (x, y, z) holds (7 i) mod 251, i = x + nx (y + ny z), less 100 for
// signed and float types; bool files hold i odd.
template <class T>
void check_samples(const Volume& v, bool boolean = false) {
    REQUIRE(v.dims == kDims);
    REQUIRE(v.spacing == std::array<double, 3>{1, 1, 1});
    REQUIRE(v.origin == std::array<double, 3>{0, 0, 0});
    const auto* s = static_cast<const T*>(v.data);
    const long long shift = std::is_signed_v<T> ? 100 : 0;
    for (std::size_t i = 0; i < v.sample_count(); ++i) {
        INFO("sample " << i);
        const long long want = boolean ? static_cast<long long>(i % 2) : static_cast<long long>((i * 7) % 251) - shift;
        REQUIRE(s[i] == static_cast<T>(want));
    }
}

// An .npy file's bytes with the header text given (padded as numpy pads it) and `data` after it.
std::string npy(const std::string& dict, const std::string& data, int major = 1) {
    const std::size_t prefix = major == 1 ? 10 : 12;
    std::string header = dict;
    while ((prefix + header.size() + 1) % 64 != 0) header += ' ';
    header += '\n';
    std::string out = std::string("\x93NUMPY", 6) + static_cast<char>(major) + '\0';
    const std::size_t n = header.size();
    out += static_cast<char>(n & 0xff);
    out += static_cast<char>((n >> 8) & 0xff);
    if (major != 1) out += std::string(2, '\0');
    return out + header + data;
}

std::string error_of(const std::string& path) {
    try {
        read_volume(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace

TEST_CASE("npy: numpy's own files read with every sample in place", "[io][npy]") {
    check_samples<float>(read_volume(corpus("f4_c.npy")));
    check_samples<double>(read_volume(corpus("f8_c.npy")));
    check_samples<std::int16_t>(read_volume(corpus("i2_big_c.npy")));
    check_samples<std::uint16_t>(read_volume(corpus("u2_fortran.npy")));  // [x, y, z] in Fortran order
    check_samples<std::uint8_t>(read_volume(corpus("u1_c.npy")));
    check_samples<std::int8_t>(read_volume(corpus("i1_c.npy")));
    check_samples<std::uint32_t>(read_volume(corpus("u4_c.npy")));
    check_samples<std::int32_t>(read_volume(corpus("i4_big_c.npy")));
    check_samples<std::uint8_t>(read_volume(corpus("bool_c.npy")), true);
    check_samples<float>(read_volume(corpus("f4_c_v2.npy")));
    check_samples<float>(read_volume(corpus("f4_c_v3.npy")));
    check_samples<float>(read_volume(corpus("f4_4d_c.npy")));  // (1, z, y, x)

    VolumeInfo info;
    const Volume big = read_volume(corpus("i2_big_c.npy"), info);
    CHECK(big.type == ScalarType::I16);
    CHECK(info.format == "npy");
    CHECK(info.encoding == "raw");
    CHECK(info.big_endian);
    CHECK(info.dims == kDims);
    const VolumeInfo header_only = read_volume_info(corpus("u2_fortran.npy"));
    CHECK(header_only.type == ScalarType::U16);
    CHECK(header_only.dims == kDims);
    CHECK_FALSE(header_only.big_endian);
    CHECK(header_only.file_bytes == 248);

    // From memory: the same samples.
    const std::string bytes = iotest::read_file(corpus("u2_fortran.npy"));
    check_samples<std::uint16_t>(read_volume_from_memory(bytes.data(), bytes.size(), "sent.npy"));
}

// Found by a review: an array (z, y, x, 1), as image stacks with one channel are, was refused,
// though its samples lie as those of (z, y, x) do.
TEST_CASE("npy: axes of size 1 anywhere leave the 3-D volume", "[io][npy]") {
    const std::string f4 = iotest::read_file(corpus("f4_c.npy"));  // shape (3, 4, 5), version 1.0
    const std::size_t header_length = static_cast<unsigned char>(f4[8]) | static_cast<unsigned char>(f4[9]) << 8;
    const std::string data = f4.substr(10 + header_length);
    Scratch s;
    for (const std::string shape : {"(3, 4, 5, 1)", "(1, 3, 1, 4, 5, 1)"}) {
        INFO(shape);
        const std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': " + shape + ", }";
        check_samples<float>(read_volume(s.file("c.npy", npy(dict, data))));
    }
    const std::string fortran = "{'descr': '<f4', 'fortran_order': True, 'shape': (1, 5, 4, 3), }";
    check_samples<float>(read_volume(s.file("f.npy", npy(fortran, data))));
}

// Found by a review: numpy under Python 2 wrote sizes as longs, (3L, 4L, 5L); numpy reads them.
TEST_CASE("npy: Python 2's long sizes read as sizes", "[io][npy]") {
    const std::string f4 = iotest::read_file(corpus("f4_c.npy"));
    const std::size_t header_length = static_cast<unsigned char>(f4[8]) | static_cast<unsigned char>(f4[9]) << 8;
    Scratch s;
    const std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (3L, 4L, 5L), }";
    check_samples<float>(read_volume(s.file("py2.npy", npy(dict, f4.substr(10 + header_length)))));
}

TEST_CASE("npy: a volume numpy saved meshes as the samples it holds", "[io][npy]") {
    // A ball, 12³ floats, written here in numpy's layout.
    constexpr std::size_t n = 12;
    std::string data(n * n * n * 4, '\0');
    std::vector<float> samples(n * n * n);
    for (std::size_t z = 0; z < n; ++z)
        for (std::size_t y = 0; y < n; ++y)
            for (std::size_t x = 0; x < n; ++x) {
                const double c = (n - 1) / 2.0;
                samples[x + n * (y + n * z)] =
                    static_cast<float>(4.0 - std::sqrt((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c)));
            }
    std::memcpy(data.data(), samples.data(), data.size());
    Scratch s;
    const std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (12, 12, 12), }";
    const std::string path = s.file("ball.npy", npy(header, data));
    const Volume v = read_volume(path);
    VolumeView view;
    view.data = samples.data();
    view.dims = {n, n, n};
    Options o;
    o.backend = Backend::Cpu;
    const Mesh from_file = extract(v.view(), o), from_array = extract(view, o);
    REQUIRE(from_file.triangle_count() > 100);
    CHECK(from_file.indices == from_array.indices);
    CHECK(from_file.positions == from_array.positions);
    CHECK(analyze_topology(from_file).closed());
}

TEST_CASE("npy: broken files are errors naming the file and the problem", "[io][npy]") {
    Scratch s;
    const std::string samples(5 * 4 * 3 * 4, '\x01');
    const std::string good = "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 5), }";
    REQUIRE_NOTHROW(read_volume(s.file("good.npy", npy(good, samples))));
    REQUIRE_NOTHROW(read_volume(s.file("good2.npy", npy(good, samples, 2))));
    // Double quotes and no spaces: a hand-written header.
    const std::string tight = "{\"descr\":\"<f4\",\"fortran_order\":False,\"shape\":(3,4,5)}";
    REQUIRE_NOTHROW(read_volume(s.file("quoted.npy", npy(tight, samples))));

    const struct {
        const char* name;
        std::string bytes;
        const char* message;
    } cases[] = {
        {"magic.npy", "\x92NUMPY" + npy(good, samples).substr(6), "no \\x93NUMPY magic"},
        {"short.npy", std::string("\x93NUMPY\x01", 7), "no \\x93NUMPY magic"},
        {"version.npy", npy(good, samples, 4), "version 4.0"},
        {"cut_header.npy", npy(good, samples).substr(0, 40), "header is cut off"},
        {"cut_data.npy", npy(good, samples.substr(1)), "holds 367 bytes"},
        {"extra_data.npy", npy(good, samples + "x"), "holds 369 bytes"},
        {"fortran_4d.npy", npy("{'descr': '<f4', 'fortran_order': True, 'shape': (5, 4, 3, 2), }", samples + samples),
         "'shape' (5, 4, 3, 2) has 4 axes longer than 1"},
        {"int64.npy", npy("{'descr': '<i8', 'fortran_order': False, 'shape': (3, 4, 5), }", samples + samples),
         "unsupported .npy dtype '<i8'"},
        {"complex.npy", npy("{'descr': '<c8', 'fortran_order': False, 'shape': (3, 4, 5), }", samples + samples),
         "unsupported .npy dtype"},
        {"structured.npy", npy("{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (3, 4, 5), }", samples),
         "expected a quoted 'descr'"},
        {"two_d.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (12, 5), }", samples),
         "has 2 dimension(s)"},
        {"four_d.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 4, 5), }", samples + samples),
         "'shape' (2, 3, 4, 5) has 4 axes longer than 1"},
        {"no_shape.npy", npy("{'descr': '<f4', 'fortran_order': False, }", samples), "lacks 'shape'"},
        {"no_order.npy", npy("{'descr': '<f4', 'shape': (3, 4, 5), }", samples), "lacks 'fortran_order'"},
        {"key.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 5), 'x': 1}", samples),
         "unexpected key 'x'"},
        {"order.npy", npy("{'descr': '<f4', 'fortran_order': 0, 'shape': (3, 4, 5), }", samples),
         "'fortran_order' must be True or False"},
        {"negative.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (3, -4, 5), }", samples),
         "'shape' must be a tuple of sizes"},
        {"unclosed.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 5)", samples),
         "to close the header"},
        {"after.npy", npy(good + " junk", samples), "text after the closing"},
        {"zero.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (3, 0, 5), }", ""), "are empty"},
        {"huge.npy",
         npy("{'descr': '<f4', 'fortran_order': False, 'shape': (4294967296, 4294967296, 4294967296), }", samples),
         "overflow"},
        {"long_header.npy", std::string("\x93NUMPY\x02\x00\x00\x00\x10\x00", 12) + good, "at most 65536 are read"},
    };
    for (const auto& c : cases) {
        CAPTURE(c.name);
        const std::string path = s.file(c.name, c.bytes);
        const std::string message = error_of(path);
        CHECK_THAT(message, Contains(c.name) && Contains(c.message));
        // The same file from memory fails the same way.
        try {
            read_volume_from_memory(c.bytes.data(), c.bytes.size(), c.name);
            FAIL("no error from memory");
        } catch (const Error& e) {
            CHECK_THAT(std::string(e.what()), Contains(c.message));
        }
    }
}
