#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>

#include "support/io_scratch.hpp"

using Catch::Matchers::Contains;
using namespace voxmesh;

namespace {

using iotest::Scratch;

// u16 samples 0, 3, 6, ... in the given byte order.
std::string u16_samples(std::size_t count, bool big_endian) {
    std::string out;
    for (std::size_t i = 0; i < count; ++i) {
        const auto v = static_cast<std::uint16_t>(i * 3 + 1000);
        const char lo = static_cast<char>(v & 0xff), hi = static_cast<char>(v >> 8);
        out += big_endian ? hi : lo;
        out += big_endian ? lo : hi;
    }
    return out;
}

void check_u16(const Volume& v, std::size_t count) {
    REQUIRE(v.type == ScalarType::U16);
    REQUIRE(v.sample_count() == count);
    const auto* s = static_cast<const std::uint16_t*>(v.data);
    for (std::size_t i = 0; i < count; ++i) REQUIRE(s[i] == static_cast<std::uint16_t>(i * 3 + 1000));
}

const std::string kHead = "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nElementType = MET_USHORT\n";
constexpr std::size_t kCount = 24;

// u16_samples name their index: sample (i,j,k) must be the file's (n-1-i, j, k) on each
// flipped axis.
void check_flipped_u16(const Volume& v, std::array<bool, 3> flipped) {
    const std::array<std::size_t, 3> n{4, 3, 2};
    REQUIRE(v.dims == n);
    const auto* s = static_cast<const std::uint16_t*>(v.data);
    iotest::for_each_sample_of_file(n, flipped, [&](std::size_t at, std::array<std::size_t, 3> f) {
        INFO("sample " << at);
        REQUIRE(s[at] == static_cast<std::uint16_t>((f[0] + 4 * (f[1] + 3 * f[2])) * 3 + 1000));
    });
}

}  // namespace

TEST_CASE("metaimage: a TransformMatrix axis in the negative direction is reversed", "[io][metaimage]") {
    Scratch s;
    const std::string geometry =
        "ElementSpacing = 0.5 0.25 2\nOffset = -1 2 3.5\nTransformMatrix = -1 0 0 0 1 0 0 0 1\n";
    auto check_x_flip = [](const std::string& path) {
        const Volume v = read_volume(path);
        check_flipped_u16(v, {true, false, false});
        CHECK(v.spacing == std::array<double, 3>{0.5, 0.25, 2});
        CHECK(v.origin == std::array<double, 3>{-1 - 0.5 * 3, 2, 3.5});  // x sample 3 of the file
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.flipped == std::array<bool, 3>{true, false, false});
        CHECK_FALSE(info.rotation_dropped);
        CHECK(info.spacing == v.spacing);
        CHECK(info.origin == v.origin);
    };
    SECTION(".mha LOCAL, big endian") {
        check_x_flip(s.file("v.mha", kHead + geometry + "ElementByteOrderMSB = True\nElementDataFile = LOCAL\n" +
                                         u16_samples(kCount, true)));
    }
    SECTION(".mhd with a detached file (memory-mapped): the file is not changed") {
        const std::string samples = u16_samples(kCount, false);
        const std::string data = s.file("v.raw", samples);
        check_x_flip(s.file("v.mhd", kHead + geometry + "ElementDataFile = v.raw\n"));
        CHECK(iotest::read_file(data) == samples);
    }
    SECTION("compressed, with z flipped too (Rotation, MetaIO's other spelling)") {
        const std::string path =
            s.file("v.mha", kHead + "Offset = -1 2 3.5\nRotation = -1 0 0 0 1 0 0 0 -1\nCompressedData = True\n"
                                    "ElementDataFile = LOCAL\n" +
                                    iotest::deflate_bytes(u16_samples(kCount, false), false));
        const Volume v = read_volume(path);
        check_flipped_u16(v, {true, false, true});
        CHECK(v.origin == std::array<double, 3>{-1 - 3, 2, 3.5 - 1});
        CHECK(read_volume_info(path).flipped == std::array<bool, 3>{true, false, true});
    }
    SECTION("a negative ElementSpacing runs its axis the other way; with a flipping matrix it cancels") {
        const std::string path =
            s.file("v.mha", kHead + "ElementSpacing = -0.5 0.25 -2\nOffset = -1 2 3.5\n"
                                    "TransformMatrix = 1 0 0 0 1 0 0 0 -1\nElementDataFile = LOCAL\n" +
                                    u16_samples(kCount, false));
        const Volume v = read_volume(path);
        check_flipped_u16(v, {true, false, false});
        CHECK(v.spacing == std::array<double, 3>{0.5, 0.25, 2});
        CHECK(v.origin == std::array<double, 3>{-1 - 0.5 * 3, 2, 3.5});
        CHECK(read_volume_info(path).flipped == std::array<bool, 3>{true, false, false});
    }
    SECTION("a permutation is dropped, not flipped") {
        const std::string path = s.file("v.mha", kHead + "Offset = -1 2 3.5\nTransformMatrix = 0 -1 0 -1 0 0 0 0 1\n"
                                                         "ElementDataFile = LOCAL\n" + u16_samples(kCount, false));
        check_flipped_u16(read_volume(path), {false, false, false});
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.rotation_dropped);
        CHECK(info.flipped == std::array<bool, 3>{false, false, false});
        CHECK(info.origin == std::array<double, 3>{-1, 2, 3.5});
    }
}

TEST_CASE("metaimage: .mha LOCAL, .mhd detached, compressed, big endian", "[io][metaimage]") {
    Scratch s;
    SECTION(".mha with LOCAL data, spacing and offset") {
        const std::string path = s.file("v.mha", kHead + "ElementSpacing = 0.5 0.25 2\nOffset = -1 2 3.5\n"
                                                         "BinaryData = True\nBinaryDataByteOrderMSB = False\n"
                                                         "ElementDataFile = LOCAL\n" + u16_samples(kCount, false));
        const Volume v = read_volume(path);
        check_u16(v, kCount);
        CHECK(v.dims == std::array<std::size_t, 3>{4, 3, 2});
        CHECK(v.spacing == std::array<double, 3>{0.5, 0.25, 2});
        CHECK(v.origin == std::array<double, 3>{-1, 2, 3.5});
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.format == "metaimage");
        CHECK(info.encoding == "raw");
    }
    SECTION(".mhd with a detached big-endian data file and HeaderSize") {
        s.file("v.raw", "HDR!" + u16_samples(kCount, true));
        const std::string path =
            s.file("v.mhd", kHead + "ElementByteOrderMSB = True\nHeaderSize = 4\nElementDataFile = v.raw\n");
        check_u16(read_volume(path), kCount);
        CHECK(read_volume_info(path).big_endian);
    }
    SECTION("compressed (zlib) .mha with CompressedDataSize") {
        const std::string z = iotest::deflate_bytes(u16_samples(kCount, false), false);
        const std::string path =
            s.file("v.mha", kHead + "CompressedData = True\nCompressedDataSize = " + std::to_string(z.size()) +
                                "\nElementDataFile = LOCAL\r\n" + z);
        check_u16(read_volume(path), kCount);
        CHECK(read_volume_info(path).encoding == "gzip");
    }
    SECTION("a data file name with spaces (as SimpleITK writes for 'my scan.mhd')") {
        const std::string data = s.file("my scan.raw", u16_samples(kCount, false));
        const std::string path = s.file("my scan.mhd", kHead + "ElementDataFile = my scan.raw\n");
        check_u16(read_volume(path), kCount);
        CHECK(read_volume_info(path).data_file == data);
    }
    // Found by a review: 'Local' and 'local' were taken as a data file's name; MetaIO reads
    // them as LOCAL.
    SECTION("ElementDataFile = Local or local is LOCAL") {
        for (const std::string local : {"Local", "local"})
            check_u16(read_volume(s.file("v.mha", kHead + "ElementDataFile = " + local + "\n" +
                                                      u16_samples(kCount, false))),
                      kCount);
    }
    // Found by a review: HeaderSize in a LOCAL file was counted from the end of the header;
    // MetaIO seeks to it from the start of the file.
    SECTION("HeaderSize in a .mha counts from the start of the file, as in MetaIO") {
        const std::string head = kHead + "HeaderSize = 200\nElementDataFile = LOCAL\n";
        REQUIRE(head.size() < 200);
        check_u16(read_volume(s.file("v.mha", head + std::string(200 - head.size(), '#') +
                                                  u16_samples(kCount, false))),
                  kCount);
    }
    SECTION("4-D with a size-1 axis") {
        const std::string path = s.file("v.mha", "NDims = 4\nDimSize = 4 3 2 1\nElementType = MET_USHORT\n"
                                                 "ElementDataFile = LOCAL\n" + u16_samples(kCount, false));
        check_u16(read_volume(path), kCount);
    }
}

// Found by a review: MetaIO's MET_LONG and MET_ULONG (4 bytes, as MET_ValueTypeSize says) were
// refused; HeaderSize = -1 reads the samples from the file's end.
TEST_CASE("metaimage: MET_LONG and MET_ULONG are 32-bit, HeaderSize -1 reads the file's end", "[io][metaimage]") {
    Scratch s;
    std::string data;
    for (std::int32_t i = 0; i < std::int32_t(kCount); ++i) {
        const std::int32_t v = i * 1000 - 7;
        data.append(reinterpret_cast<const char*>(&v), 4);
    }
    const std::string head = "NDims = 3\nDimSize = 4 3 2\nBinaryDataByteOrderMSB = False\n";
    const Volume l = read_volume(s.file("l.mha", head + "ElementType = MET_LONG\nElementDataFile = LOCAL\n" + data));
    REQUIRE(l.type == ScalarType::I32);
    CHECK(static_cast<const std::int32_t*>(l.data)[5] == 4993);
    const Volume u = read_volume(
        s.file("u.mha", head + "ElementType = MET_ULONG\nHeaderSize = -1\nElementDataFile = LOCAL\n" + data));
    REQUIRE(u.type == ScalarType::U32);
    CHECK(static_cast<const std::uint32_t*>(u.data)[5] == 4993u);
}

TEST_CASE("metaimage: bad headers are errors naming the file", "[io][metaimage][errors]") {
    Scratch s;
    const std::string data = u16_samples(kCount, false);
    auto fails = [&](const std::string& name, const std::string& bytes, const std::string& what) {
        const std::string path = s.file(name, bytes);
        CHECK_THROWS_WITH(read_volume(path), Contains(path) && Contains(what));
    };
    fails("a.mha", "NDims = 3\nDimSize = 4 3\nElementType = MET_USHORT\nElementDataFile = LOCAL\n" + data,
          "NDims is 3 but DimSize lists 2");
    fails("a.mha", "NDims = 3\nElementType = MET_USHORT\nElementDataFile = LOCAL\n" + data, "DimSize");
    fails("a.mha", kHead, "ElementDataFile");
    fails("a.mha", "NDims = 3\nDimSize = 4 3 2\nElementType = MET_LONG_LONG\nElementDataFile = LOCAL\n" + data,
          "unsupported ElementType 'MET_LONG_LONG'");
    fails("a.mha", kHead + "ElementDataFile = LOCAL\n" + data.substr(1), "truncated");
    // Found by a review: samples at the end of the file (HeaderSize = -1) read the header's
    // own bytes as samples where the file was too short; "LIST 2D" was looked for as a file.
    fails("a.mha", kHead + "HeaderSize = -1\nElementDataFile = LOCAL\n" + data.substr(10), "may not overlap");
    fails("a.mhd", kHead + "ElementDataFile = LIST 2D\na.raw\n", "lists and file patterns are not supported");
    fails("a.mha", kHead + "ElementSpacing = 1 1\nElementDataFile = LOCAL\n" + data, "ElementSpacing");
    fails("a.mha", kHead + "BinaryDataByteOrderMSB = True\nElementByteOrderMSB = False\nElementDataFile = LOCAL\n" + data,
          "disagree");
    fails("a.mha", kHead + "ElementNumberOfChannels = 3\nElementDataFile = LOCAL\n" + data, "ElementNumberOfChannels");
    fails("a.mha", kHead + "BinaryData = False\nElementDataFile = LOCAL\n" + data, "ASCII");
    fails("a.mha", kHead + "CompressedData = True\nElementDataFile = LOCAL\nnot zlib at all, no", "corrupt");
    fails("a.mha", kHead + "CompressedData = True\nCompressedDataSize = 99999\nElementDataFile = LOCAL\nxx", "truncated");
    fails("a.mha", kHead + "HeaderSize = 10\nElementDataFile = LOCAL\n" + data,
          "HeaderSize 10 points inside the header");
    fails("a.mha", "this is not a header\n", "not 'Key = Value'");
    fails("a.mha", "", "empty");
    fails("a.mhd", kHead + "ElementDataFile = missing.raw\n", "missing.raw");
    fails("a.mhd", kHead + "ElementDataFile = img_%03d.raw 1 10 1\n", "not supported");
    fails("a.mha", "NDims = 3\nDimSize = 4294967296 4294967296 4294967296\nElementType = MET_DOUBLE\n"
                   "ElementDataFile = LOCAL\n" + data,
          "overflow");
}
