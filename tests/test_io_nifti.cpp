#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include "support/io_scratch.hpp"

using Catch::Matchers::Contains;
using namespace voxmesh;

namespace {

using iotest::Scratch;

// A minimal NIfTI-1 single file, built field by field (offsets from nifti1.h).
struct Nifti {
    std::string header = std::string(352, '\0');
    bool big = false;
    template <class T>
    void put(std::size_t offset, T value) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &value, sizeof(T));
        if (big) std::reverse(b, b + sizeof(T));
        std::memcpy(header.data() + offset, b, sizeof(T));
    }
    explicit Nifti(bool big_endian, std::int16_t datatype = 4, std::int16_t bitpix = 16) : big(big_endian) {
        put<std::int32_t>(0, 348);
        const std::int16_t dim[8] = {3, 4, 3, 2, 1, 1, 1, 1};
        for (int i = 0; i < 8; ++i) put<std::int16_t>(40 + 2 * static_cast<std::size_t>(i), dim[i]);
        put<std::int16_t>(70, datatype);
        put<std::int16_t>(72, bitpix);
        const float pixdim[4] = {1, 1.5f, 2, 2.5f};
        for (int i = 0; i < 4; ++i) put<float>(76 + 4 * static_cast<std::size_t>(i), pixdim[i]);
        put<float>(108, 352);
        put<float>(112, 2);  // scl_slope
        put<float>(116, -5); // scl_inter
        put<std::int16_t>(252, 1);  // qform_code
        put<float>(268, 10);
        put<float>(272, 20);
        put<float>(276, 30);
        std::memcpy(header.data() + 344, "n+1\0", 4);
    }
    std::string samples() const {  // i16 0, -3, -6, ...
        std::string out;
        for (int i = 0; i < 24; ++i) {
            const auto v = static_cast<std::uint16_t>(static_cast<std::int16_t>(-3 * i));
            const char lo = static_cast<char>(v & 0xff), hi = static_cast<char>(v >> 8);
            out += big ? hi : lo;
            out += big ? lo : hi;
        }
        return out;
    }
    std::string file() const { return header + samples(); }
};

void check_samples(const Volume& v) {
    REQUIRE(v.type == ScalarType::I16);
    REQUIRE(v.dims == std::array<std::size_t, 3>{4, 3, 2});
    const auto* s = static_cast<const std::int16_t*>(v.data);
    for (int i = 0; i < 24; ++i) REQUIRE(s[i] == -3 * i);
    CHECK(v.spacing == std::array<double, 3>{1.5, 2, 2.5});
    CHECK(v.origin == std::array<double, 3>{10, 20, 30});
}

// Nifti's samples name their index (-3 * linear index): sample (i,j,k) must be the file's
// (n-1-i, j, k) on each flipped axis.
void check_flipped_samples(const Volume& v, std::array<bool, 3> flipped) {
    const std::array<std::size_t, 3> n{4, 3, 2};
    REQUIRE(v.dims == n);
    const auto* s = static_cast<const std::int16_t*>(v.data);
    iotest::for_each_sample_of_file(n, flipped, [&](std::size_t at, std::array<std::size_t, 3> f) {
        INFO("sample " << at);
        REQUIRE(s[at] == -3 * static_cast<int>(f[0] + 4 * (f[1] + 3 * f[2])));
    });
}

// read_volume and read_volume_info agree, and report the flips expected.
void check_geometry(const std::string& path, std::array<bool, 3> flipped, std::array<double, 3> spacing,
                    std::array<double, 3> origin) {
    const Volume v = read_volume(path);
    check_flipped_samples(v, flipped);
    CHECK(v.spacing == spacing);
    CHECK(v.origin == origin);
    const VolumeInfo info = read_volume_info(path);
    CHECK(info.flipped == flipped);
    CHECK_FALSE(info.rotation_dropped);
    CHECK(info.spacing == spacing);
    CHECK(info.origin == origin);
}

// srow_x, srow_y, srow_z (4 values each) and sform_code 4 (MNI).
void put_sform(Nifti& n, const std::array<float, 12>& rows) {
    n.put<std::int16_t>(254, 4);
    for (std::size_t i = 0; i < 12; ++i) n.put<float>(280 + 4 * i, rows[i]);
}

}  // namespace

TEST_CASE("nifti: axes in the negative direction are reversed from the minimum corner", "[io][nifti]") {
    Scratch s;
    SECTION("sform diag(-2, 2, 2) with the MNI offset, little and big endian, gzip") {
        for (const bool big : {false, true}) {
            Nifti n(big);
            for (std::size_t a = 1; a <= 3; ++a) n.put<float>(76 + 4 * a, 2);
            put_sform(n, {-2, 0, 0, 90, 0, 2, 0, -126, 0, 0, 2, -72});
            const std::array<double, 3> corner{90 - 2 * 3, -126, -72};  // x sample 3 of the file
            check_geometry(s.file("mni.nii", n.file()), {true, false, false}, {2, 2, 2}, corner);
            check_geometry(s.file("mni.nii.gz", iotest::deflate_bytes(n.file(), true)), {true, false, false},
                           {2, 2, 2}, corner);
        }
    }
    SECTION("qform with qfac = pixdim[0] = -1 flips z") {
        Nifti n(false);
        n.put<float>(76, -1);
        check_geometry(s.file("q.nii", n.file()), {false, false, true}, {1.5, 2, 2.5}, {10, 20, 30 - 2.5 * 1});
    }
    SECTION("qform rotated 180 degrees about y, qfac -1: x flipped (LAS, as dcm2niix writes)") {
        Nifti n(false);
        n.put<float>(76, -1);
        n.put<float>(260, 1);  // quatern_c
        check_geometry(s.file("las.nii", n.file()), {true, false, false}, {1.5, 2, 2.5}, {10 - 1.5 * 3, 20, 30});
    }
    SECTION("sform wins over a flipping qform") {
        Nifti n(false);
        n.put<float>(76, -1);
        put_sform(n, {1.5, 0, 0, 1, 0, -2, 0, 2, 0, 0, 2.5, 3});
        check_geometry(s.file("s.nii", n.file()), {false, true, false}, {1.5, 2, 2.5}, {1, 2 - 2 * 2, 3});
    }
    SECTION("the sform's column lengths are the spacing where pixdim disagrees") {
        Nifti n(false);  // pixdim 1.5, 2, 2.5
        put_sform(n, {3, 0, 0, 1, 0, -0.5, 0, 2, 0, 0, 4, 3});
        check_geometry(s.file("s.nii", n.file()), {false, true, false}, {3, 0.5, 4}, {1, 2 - 0.5 * 2, 3});
    }
    // Found by a review: pixdim[1..3] of 0 or NaN was refused even where the sform gives the spacing.
    SECTION("pixdim 0 or NaN is ignored where the sform gives the spacing") {
        for (const float bad : {0.0f, std::numeric_limits<float>::quiet_NaN()}) {
            Nifti n(false);
            for (std::size_t a = 1; a <= 3; ++a) n.put<float>(76 + 4 * a, bad);
            put_sform(n, {3, 0, 0, 1, 0, 0.5, 0, 2, 0, 0, 4, 3});
            check_geometry(s.file("s.nii", n.file()), {false, false, false}, {3, 0.5, 4}, {1, 2, 3});
        }
    }
    // Found by a review: a slightly oblique axis (as most scans converted from DICOM) kept its
    // negative direction unflipped, so the mesh came out mirrored and 8 mm off here.
    SECTION("a slightly oblique sform still flips its negative axis; only the tilt is dropped") {
        Nifti n(false);
        put_sform(n, {-2, 0, 0, 10, 0.002f, 2, 0, 0, 0, 0, 2, 0});  // column 0 tilted by 0.06 degrees
        const std::string path = s.file("o.nii", n.file());
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.rotation_dropped);
        CHECK(info.flipped == std::array<bool, 3>{true, false, false});
        CHECK(info.origin[0] == Approx(10 - 2 * 3).epsilon(1e-6));  // x sample 3 of the file
        check_flipped_samples(read_volume(path), {true, false, false});
    }
    SECTION("a permuting sform is dropped, not flipped") {
        Nifti n(false);
        put_sform(n, {0, -2, 0, 1, -1.5, 0, 0, 2, 0, 0, 2.5, 3});
        const std::string path = s.file("p.nii", n.file());
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.rotation_dropped);
        CHECK(info.flipped == std::array<bool, 3>{false, false, false});
        CHECK(info.origin == std::array<double, 3>{1, 2, 3});
        check_flipped_samples(read_volume(path), {false, false, false});
    }
}

TEST_CASE("nifti: real MRI reads with pixdim spacing and sform origin", "[io][nifti]") {
    const std::string path = std::string(VOXMESH_TEST_DATA) + "/mri_someones_anatomy.nii.gz";
    const VolumeInfo info = read_volume_info(path);
    CHECK(info.format == "nifti");
    CHECK(info.encoding == "gzip");
    CHECK(info.type == ScalarType::U8);
    CHECK(info.dims == std::array<std::size_t, 3>{57, 67, 56});
    CHECK(info.spacing == std::array<double, 3>{2.75, 2.75, 2.75});
    CHECK(info.origin == std::array<double, 3>{-78, -91, -91});
    CHECK(info.flipped == std::array<bool, 3>{false, false, false});  // sform diag(2.75, 2.75, 2.75)
    CHECK_FALSE(info.rotation_dropped);
    // scl_slope / scl_inter are reported, not applied.
    CHECK(info.value_scale == Approx(0.35246).epsilon(1e-4));
    CHECK(info.value_offset == Approx(6.6784).epsilon(1e-4));

    const Volume v = read_volume(path);
    CHECK(v.type == ScalarType::U8);
    CHECK(v.dims == info.dims);
    CHECK(v.origin == info.origin);
    const auto* s = static_cast<const std::uint8_t*>(v.data);
    unsigned hi = 0;
    double sum = 0;
    for (std::size_t i = 0; i < v.sample_count(); ++i) {
        hi = std::max<unsigned>(hi, s[i]);
        sum += s[i];
    }
    CHECK(hi == 255);
    CHECK(sum / static_cast<double>(v.sample_count()) == Approx(111.5).margin(0.05));
}

TEST_CASE("nifti: byte orders, gzip, 4-D with dim4 = 1", "[io][nifti]") {
    Scratch s;
    SECTION("little endian .nii") {
        const std::string path = s.file("a.nii", Nifti(false).file());
        check_samples(read_volume(path));
        const VolumeInfo info = read_volume_info(path);
        CHECK(info.value_scale == 2);
        CHECK(info.value_offset == -5);
    }
    SECTION("big endian .nii") { check_samples(read_volume(s.file("a.nii", Nifti(true).file()))); }
    SECTION(".nii.gz, and a .nii that is really gzip") {
        check_samples(read_volume(s.file("a.nii.gz", iotest::deflate_bytes(Nifti(false).file(), true))));
        check_samples(read_volume(s.file("b.NII", iotest::deflate_bytes(Nifti(true).file(), true))));
    }
    SECTION("dim[0] = 4 with dim[4] = 1") {
        Nifti n(false);
        n.put<std::int16_t>(40, 4);
        check_samples(read_volume(s.file("a.nii", n.file())));
    }
    SECTION("sform origin wins over qform") {
        Nifti n(false);
        n.put<std::int16_t>(254, 2);
        n.put<float>(280 + 12, -1);
        n.put<float>(296 + 12, -2);
        n.put<float>(312 + 12, -3);
        CHECK(read_volume(s.file("a.nii", n.file())).origin == std::array<double, 3>{-1, -2, -3});
    }
}

TEST_CASE("nifti: bad headers are errors naming the file", "[io][nifti][errors]") {
    Scratch s;
    auto fails = [&](const std::string& name, const std::string& bytes, const std::string& what) {
        const std::string path = s.file(name, bytes);
        CHECK_THROWS_WITH(read_volume(path), Contains(path) && Contains(what));
    };
    {
        Nifti n(false);
        n.put<std::int32_t>(0, 349);
        fails("a.nii", n.file(), "sizeof_hdr is 349");
    }
    {
        Nifti n(false);
        n.put<std::int16_t>(40, 2);
        fails("a.nii", n.file(), "dim[0] is 2");
    }
    {
        Nifti n(false);
        n.put<std::int16_t>(40, 4);
        n.put<std::int16_t>(48, 2);
        fails("a.nii", n.file(), "only 3-D");
    }
    {
        Nifti n(false);
        n.put<std::int16_t>(44, -3);
        fails("a.nii", n.file(), "dim[2] is -3");
    }
    {  // nifti1_io reads a 0 as 1, nibabel as an empty axis: no one meaning, so refused.
        Nifti n(false);
        n.put<std::int16_t>(46, 0);
        fails("a.nii", n.file(), "dim[3] is 0");
    }
    {
        Nifti n(false);
        n.put<std::int16_t>(72, 8);
        fails("a.nii", n.file(), "bitpix 8 contradicts datatype 4");
    }
    fails("a.nii", Nifti(false, 32, 64).file(), "unsupported NIfTI datatype 32");
    {
        Nifti n(false);
        n.put<float>(108, 351.5f);
        fails("a.nii", n.file(), "vox_offset");
    }
    {
        Nifti n(false);
        std::memcpy(n.header.data() + 344, "ni1\0", 4);
        fails("a.nii", n.file(), ".hdr/.img");
    }
    {
        Nifti n(false);
        n.put<std::int16_t>(42, 2000);
        n.put<std::int16_t>(44, 2000);
        n.put<std::int16_t>(46, 100);
        fails("a.nii", n.file(), "truncated file, or dims");
        fails("a.nii.gz", iotest::deflate_bytes(n.file(), true), "cannot hold");
    }
    const std::string good = Nifti(false).file();
    fails("a.nii", good.substr(0, good.size() - 1), "truncated");
    fails("a.nii", good.substr(0, 200), "too short");
    fails("a.nii", "", "empty");
    const std::string gz = iotest::deflate_bytes(good, true);
    fails("a.nii.gz", gz.substr(0, gz.size() - 20), "ends early");
    std::string corrupt = gz;
    for (std::size_t i = 30; i < corrupt.size() - 8; ++i) corrupt[i] = static_cast<char>(corrupt[i] ^ 0x33);
    fails("a.nii.gz", corrupt, "corrupt");
    fails("a.nii.gz", iotest::deflate_bytes(good.substr(0, 100), true), "too short");
}

// Found by a differential review against nibabel: each of these read there (and in
// nifti1_io), where the meaning is clear, and was refused here.
TEST_CASE("nifti: bytes after the samples are ignored, as nibabel and nifti1_io do", "[io][nifti]") {
    Scratch s;
    const std::string good = Nifti(false).file();
    SECTION(".nii") {
        const std::string path = s.file("a.nii", good + "extra");
        check_samples(read_volume(path));
        CHECK(read_volume_info(path).dims == std::array<std::size_t, 3>{4, 3, 2});
    }
    SECTION(".nii.gz, the gzip CRC still checked past the samples") {
        const std::string gz = iotest::deflate_bytes(good + "extra", true);
        check_samples(read_volume(s.file("a.nii.gz", gz)));
        std::string bad_crc = gz;
        bad_crc[bad_crc.size() - 8] = static_cast<char>(bad_crc[bad_crc.size() - 8] ^ 1);
        const std::string path = s.file("b.nii.gz", bad_crc);
        CHECK_THROWS_WITH(read_volume(path), Contains(path) && Contains("corrupt"));
    }
    SECTION("too few bytes are still an error") {
        const std::string path = s.file("a.nii", good.substr(0, good.size() - 1));
        CHECK_THROWS_WITH(read_volume_info(path), Contains(path) && Contains("truncated"));
    }
}

TEST_CASE("nifti: a pixdim of 0 or not finite, where used, is 1 (as nifti1_io)", "[io][nifti]") {
    Scratch s;
    const std::array<float, 3> bad_values{0.0f, std::numeric_limits<float>::quiet_NaN(),
                                          std::numeric_limits<float>::infinity()};
    SECTION("qform") {
        for (const float bad : bad_values) {
            Nifti n(false);  // pixdim 1.5, 2, 2.5
            n.put<float>(84, bad);
            check_geometry(s.file("q.nii", n.file()), {false, false, false}, {1.5, 1, 2.5}, {10, 20, 30});
        }
    }
    SECTION("no transform") {
        for (const float bad : bad_values) {
            Nifti n(false);
            n.put<std::int16_t>(252, 0);
            n.put<float>(80, bad);
            check_geometry(s.file("n.nii", n.file()), {false, false, false}, {1, 2, 2.5}, {0, 0, 0});
        }
    }
    SECTION("a zero sform column") {
        for (const float bad : bad_values) {
            Nifti n(false);
            n.put<float>(80, bad);
            put_sform(n, {0, 0, 0, 1, 0, 2, 0, 2, 0, 0, 2, 3});
            check_geometry(s.file("s.nii", n.file()), {false, false, false}, {1, 2, 2}, {1, 2, 3});
        }
    }
}

// A NaN there read as no direction at all: the sform's spacing silently fell back to pixdim,
// the qform's rotation to none, where nibabel's affine is NaN.
TEST_CASE("nifti: a transform that is not finite is an error naming its field", "[io][nifti][errors]") {
    Scratch s;
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    SECTION("sform") {
        for (const float bad : {nan, inf}) {
            Nifti n(false);
            put_sform(n, {1.5, 0, 0, 1, 0, 2, bad, 2, 0, 0, 2.5, 3});
            const std::string path = s.file("s.nii", n.file());
            // srow_y[2]: row y of the sform, column 2, so index axis 2's direction.
            CHECK_THROWS_WITH(read_volume_info(path),
                              Contains(path) && Contains("srow_y[2] is ") &&
                                  Contains("a non-finite direction component of index axis 2"));
        }
    }
    SECTION("qform") {
        for (const float bad : {nan, inf}) {
            Nifti n(false);
            n.put<float>(260, bad);
            const std::string path = s.file("q.nii", n.file());
            CHECK_THROWS_WITH(read_volume_info(path), Contains(path) && Contains("quatern_b/c/d"));
        }
    }
    SECTION("a quaternion not used (the sform wins) is not read") {
        Nifti n(false);
        n.put<float>(260, nan);
        put_sform(n, {1.5, 0, 0, 1, 0, 2, 0, 2, 0, 0, 2.5, 3});
        check_geometry(s.file("s.nii", n.file()), {false, false, false}, {1.5, 2, 2.5}, {1, 2, 3});
    }
}
