#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "support/io_scratch.hpp"

using Catch::Matchers::Contains;
using namespace voxmesh;

namespace {

using iotest::Scratch;

std::string f32_samples(std::size_t count, bool big_endian) {
    std::string out;
    for (std::size_t i = 0; i < count; ++i) {
        const float f = static_cast<float>(i) * 1.5f - 7.0f;
        unsigned char b[4];
        std::memcpy(b, &f, 4);
        if (big_endian) std::reverse(b, b + 4);
        out.append(reinterpret_cast<const char*>(b), 4);
    }
    return out;
}

void check_f32(const Volume& v, std::size_t count) {
    REQUIRE(v.type == ScalarType::F32);
    REQUIRE(v.sample_count() == count);
    const auto* s = static_cast<const float*>(v.data);
    for (std::size_t i = 0; i < count; ++i) REQUIRE(s[i] == static_cast<float>(i) * 1.5f - 7.0f);
}

}  // namespace

TEST_CASE("raw: little and big endian, offsets, geometry", "[io][raw]") {
    Scratch s;
    RawLayout layout;
    layout.dims = {5, 4, 3};
    layout.type = ScalarType::F32;
    layout.spacing = {1, 2, 3};
    layout.origin = {-1, 0, 1};
    const std::size_t n = 60;
    check_f32(read_raw(s.file("a.raw", f32_samples(n, false)), layout), n);

    layout.offset = 6;  // misaligned: copied
    check_f32(read_raw(s.file("b.raw", "header" + f32_samples(n, false)), layout), n);

    layout.offset = 8;
    layout.big_endian = true;
    const std::string path = s.file("c.raw", "header!!" + f32_samples(n, true));
    const Volume v = read_raw(path, layout);
    check_f32(v, n);
    CHECK(v.spacing == layout.spacing);
    CHECK(v.origin == layout.origin);
    const VolumeInfo info = read_raw_info(path, layout);
    CHECK(info.format == "raw");
    CHECK(info.file_bytes == 8 + 4 * n);

    // Writing through a mapped volume never changes the file (private mapping).
    layout.big_endian = false;
    layout.offset = 0;
    const std::string mapped = s.file("d.raw", f32_samples(n, false));
    {
        Volume m = read_raw(mapped, layout);
        static_cast<float*>(m.data)[0] = 1234.f;
    }
    check_f32(read_raw(mapped, layout), n);
}

TEST_CASE("raw: sizes that do not match the file are errors naming it", "[io][raw][errors]") {
    Scratch s;
    RawLayout layout;
    layout.dims = {5, 4, 3};
    layout.type = ScalarType::F32;
    const std::string data = f32_samples(60, false);
    auto fails = [&](const std::string& path, const RawLayout& l, const std::string& what) {
        CHECK_THROWS_WITH(read_raw(path, l), Contains(path) && Contains(what));
        CHECK_THROWS_WITH(read_raw_info(path, l), Contains(path) && Contains(what));
    };
    fails(s.file("t.raw", data.substr(0, 100)), layout, "truncated");
    fails(s.file("l.raw", data + "x"), layout, "do not match");
    RawLayout big = layout;
    big.dims = {1u << 22, 1u << 22, 1u << 22};
    fails(s.file("o.raw", data), big, "overflow");
    big.dims = {100000, 100000, 1000};
    fails(s.file("m.raw", data), big, "need exactly");
    RawLayout zero = layout;
    zero.dims = {5, 0, 3};
    fails(s.file("z.raw", data), zero, "empty");
    RawLayout offset = layout;
    offset.offset = 1000;
    fails(s.file("f.raw", data), offset, "1000-byte header");
    fails(s.file("e.raw", ""), layout, "empty");
    std::filesystem::create_directory(s.dir + "/dir.raw");
    fails(s.dir + "/dir.raw", layout, "directory");
    fails(s.dir + "/missing.raw", layout, "does not exist");
    RawLayout spacing = layout;
    spacing.spacing = {1, 0, 1};
    fails(s.file("s.raw", data), spacing, "spacing");
    // Samples past FLT_MAX would mesh to inf coordinates.
    RawLayout far = layout;
    far.spacing = {1, 1e300, 1};
    fails(s.file("far.raw", data), far, "beyond the range of float");
    far.spacing = {1, 1, 1};
    far.origin = {0, 0, 3.4e38};
    far.spacing[2] = -1e38;  // z runs down: the last of 3 samples is at 3.4e38 - 2e38
    CHECK(read_raw(s.file("near.raw", data), far).origin[2] == 3.4e38 - 2e38);
    far.origin[2] = -3.4e38;
    fails(s.file("far.raw", data), far, "axis 2");
}

TEST_CASE("raw: a negative spacing runs its axis the other way, as in headers", "[io][raw]") {
    Scratch s;
    RawLayout layout;
    layout.dims = {5, 4, 3};
    layout.type = ScalarType::F32;
    layout.spacing = {-1, 2, -3};
    layout.origin = {10, 20, 30};
    const std::string path = s.file("n.raw", f32_samples(60, false));
    const std::array<double, 3> magnitude{1, 2, 3};
    const std::array<double, 3> corner{10 - 1 * 4, 20, 30 - 3 * 2};  // the file's last x and z samples
    const Volume v = read_raw(path, layout);
    CHECK(v.spacing == magnitude);
    CHECK(v.origin == corner);
    // Every sample keeps its position: (i, j, k) here is the file's (4 - i, j, 2 - k).
    const auto* got = static_cast<const float*>(v.data);
    const Volume file = read_raw(path, RawLayout{layout.dims, layout.type, false, 0, {1, 1, 1}, {0, 0, 0}});
    const auto* want = static_cast<const float*>(file.data);
    for (std::size_t k = 0; k < 3; ++k)
        for (std::size_t j = 0; j < 4; ++j)
            for (std::size_t i = 0; i < 5; ++i) REQUIRE(got[i + 5 * (j + 4 * k)] == want[(4 - i) + 5 * (j + 4 * (2 - k))]);
    const VolumeInfo info = read_raw_info(path, layout);
    CHECK(info.spacing == magnitude);
    CHECK(info.origin == corner);
    CHECK(info.flipped == std::array<bool, 3>{true, false, true});
}

namespace {

// a + b, built with append: gcc 12 gives a false -Wrestrict on operator+ of short strings.
std::string joined(std::string a, const std::string& b) {
    a.append(b);
    return a;
}

bool same_volume(const Volume& a, const Volume& b) {
    return a.type == b.type && a.dims == b.dims && a.spacing == b.spacing && a.origin == b.origin &&
           a.byte_size() == b.byte_size() && std::memcmp(a.data, b.data, a.byte_size()) == 0;
}

}  // namespace

TEST_CASE("raw from a stream: the same volume as from the file, whatever the layout", "[io][raw]") {
    Scratch s;
    const std::string little = f32_samples(60, false), big = f32_samples(60, true);
    struct Case {
        std::string bytes;
        RawLayout layout;
    };
    const std::vector<Case> cases{
        {little, {{5, 4, 3}, ScalarType::F32, false, 0, {1, 2, 3}, {-1, 0, 1}}},
        {joined("header", little), {{5, 4, 3}, ScalarType::F32, false, 6, {1, 1, 1}, {0, 0, 0}}},
        {joined("header!!", big), {{5, 4, 3}, ScalarType::F32, true, 8, {0.5, 1, 1}, {0, 0, 0}}},
        {big, {{4, 5, 6}, ScalarType::I16, true, 0, {1, 1, 1}, {0, 0, 0}}},  // the 240 bytes as i16
        {little, {{5, 4, 3}, ScalarType::F32, false, 0, {-1, 2, -3}, {10, 20, 30}}},  // x and z flipped
        {joined(std::string(70000, 'h'), little), {{5, 4, 3}, ScalarType::F32, false, 70000, {1, 1, 1}, {0, 0, 0}}},
    };
    for (std::size_t c = 0; c < cases.size(); ++c) {
        INFO("case " << c);
        const std::string path = s.file(joined("s", std::to_string(c)).append(".raw"), cases[c].bytes);
        std::istringstream in(cases[c].bytes);
        CHECK(same_volume(read_raw(in, "piped", cases[c].layout), read_raw(path, cases[c].layout)));
    }
}

TEST_CASE("raw from a stream: too short, too long and bad sizes are errors naming it", "[io][raw][errors]") {
    RawLayout layout{{5, 4, 3}, ScalarType::F32, false, 8, {1, 1, 1}, {0, 0, 0}};
    const std::string samples = f32_samples(60, false);
    const auto fails = [&](const std::string& bytes, const RawLayout& l, const std::string& what) {
        std::istringstream in(bytes);
        CHECK_THROWS_WITH(read_raw(in, "piped", l), Contains("piped") && Contains(what));
    };
    fails("head", layout, "inside the 8-byte offset");
    fails(joined("header!!", samples.substr(0, 100)), layout, "holds 100 bytes of samples but 5x4x3 f32 needs 240");
    fails(joined("header!!", samples).append("x"), layout, "goes on past the 240 bytes");
    fails("", layout, "inside the 8-byte offset");
    RawLayout empty = layout;
    empty.dims = {5, 0, 3};
    fails(joined("header!!", samples), empty, "empty");
    RawLayout huge = layout;
    huge.dims = {std::size_t{1} << 40, std::size_t{1} << 40, 4};
    fails(joined("header!!", samples), huge, "piped");  // overflow, refused before anything is read
    RawLayout flat = layout;
    flat.spacing = {1, 0, 1};
    fails(joined("header!!", samples), flat, "spacing");
}

TEST_CASE("raw from a stream that throws on failure: still our errors, and its mask kept", "[io][raw][errors]") {
    const RawLayout layout{{5, 4, 3}, ScalarType::F32, false, 0, {1, 1, 1}, {0, 0, 0}};
    const std::string samples = f32_samples(60, false);
    const auto mask = std::ios::failbit | std::ios::badbit;
    std::istringstream short_in(samples.substr(0, 100));
    short_in.exceptions(mask);
    CHECK_THROWS_WITH(read_raw(short_in, "piped", layout), Contains("holds 100 bytes of samples"));
    CHECK(short_in.exceptions() == mask);
    std::istringstream whole(samples);
    whole.exceptions(mask);
    CHECK(read_raw(whole, "piped", layout).dims == layout.dims);  // its end is peeked at, not an error
    CHECK(whole.exceptions() == mask);
}
