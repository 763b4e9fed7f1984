// Reading from memory (read_volume_from_memory, read_mesh_from_memory, ...): the same bytes give
// the same volume or mesh as the file, or the same error, word for word; the caller's bytes are
// never written or kept; a header cannot reach a data file beside it. Writing to memory
// (write_mesh_to_memory, write_nrrd_to_memory) gives the file's bytes.
#include <catch2/catch.hpp>
#include <voxmesh/fields.hpp>
#include <voxmesh/io.hpp>

#include "support/io_scratch.hpp"

#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

using Catch::Matchers::Contains;
using namespace voxmesh;
namespace fs = std::filesystem;

namespace {

std::string test_data(const std::string& name) { return std::string(VOXMESH_TEST_DATA) + "/" + name; }

// tests/fuzz_corpus/<target>: small valid files of every encoding each reader knows.
std::vector<std::string> corpus(const char* target) {
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(fs::path(VOXMESH_TEST_DATA) / ".." / "fuzz_corpus" / target))
        files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
    return files;
}

// What a read gives: its result as bytes, or its error message.
struct Outcome {
    bool ok = false;
    std::string text;  // the result's bytes, or the error
    bool operator==(const Outcome&) const = default;
};

template <class Read>
Outcome outcome_of(Read read) {
    try {
        return {true, read()};
    } catch (const Error& e) {
        return {false, e.what()};
    }
}

std::string bytes_of(const Volume& v, const VolumeInfo& info) {
    std::ostringstream s;
    s.write(static_cast<const char*>(v.data), static_cast<std::streamsize>(v.byte_size()));
    s << '|' << static_cast<int>(v.type);
    for (std::size_t a = 0; a < 3; ++a)
        s << '|' << v.dims[a] << ',' << v.spacing[a] << ',' << v.origin[a] << ',' << info.flipped[a];
    s << '|' << info.format << '|' << info.encoding << '|' << info.file_bytes << '|' << info.rotation_dropped;
    return s.str();
}

std::string bytes_of(const Mesh& m) {
    const auto raw = [](const auto& v) { return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(v[0])); };
    return raw(m.positions) + "|" + raw(m.normals) + "|" + raw(m.indices);
}

Outcome volume_from_file(const std::string& path) {
    return outcome_of([&] {
        VolumeInfo info;
        const Volume v = read_volume(path, info);
        return bytes_of(v, info);
    });
}

// Named as the file, so that messages match word for word. Bytes lent and bytes handed over
// (used in place where a file would be mapped) give the same outcome.
Outcome volume_from_memory(const std::string& bytes, const std::string& name) {
    const Outcome lent = outcome_of([&] {
        VolumeInfo info;
        const Volume v = read_volume_from_memory(bytes.data(), bytes.size(), name, info);
        return bytes_of(v, info);
    });
    const Outcome handed_over = outcome_of([&] {
        VolumeInfo info;
        const Volume v = read_volume_from_memory(std::vector<unsigned char>(bytes.begin(), bytes.end()), name, info);
        return bytes_of(v, info);
    });
    CHECK(lent == handed_over);
    return lent;
}

Outcome mesh_from_file(const std::string& path) { return outcome_of([&] { return bytes_of(read_mesh(path)); }); }

Outcome mesh_from_memory(const std::string& bytes, const std::string& name) {
    return outcome_of([&] { return bytes_of(read_mesh_from_memory(bytes.data(), bytes.size(), name)); });
}

// Every prefix length worth trying: the ends, and a spread through the middle.
std::vector<std::size_t> cut_points(std::size_t size) {
    std::vector<std::size_t> cuts{0, 1, 2, size / 2, size > 0 ? size - 1 : 0};
    for (std::size_t k = 1; k < 16; ++k) cuts.push_back(size * k / 16);
    return cuts;
}

// One byte changed at `at` (a digit or header character goes wrong, or a length field).
std::string damaged(std::string bytes, std::size_t at) {
    if (!bytes.empty()) bytes[at % bytes.size()] ^= 0x35;
    return bytes;
}

// For every file of `files`, its truncations and one-byte damages: the file and the same bytes
// in memory give the same outcome. `separate` says which files name a data file beside them
// (not readable from memory).
template <class FromFile, class FromMemory>
void check_same_outcomes(const std::vector<std::string>& files, FromFile from_file, FromMemory from_memory,
                         const std::function<bool(const std::string&)>& separate) {
    iotest::Scratch s;
    std::size_t compared = 0, successes = 0;
    for (const std::string& original : files) {
        const std::string whole = iotest::read_file(original);
        std::vector<std::string> variants{whole};
        for (const std::size_t cut : cut_points(whole.size())) variants.push_back(whole.substr(0, cut));
        for (std::size_t k = 0; k < 12; ++k) variants.push_back(damaged(whole, 7 + whole.size() * k / 12));
        for (const std::string& bytes : variants) {
            // The same name (and so extension) as the original, in a directory of its own.
            const std::string path = s.file(fs::path(original).filename().string(), bytes);
            const Outcome memory = from_memory(bytes, path);
            if (separate(bytes)) {
                CHECK_FALSE(memory.ok);
                continue;
            }
            INFO(original << ", " << bytes.size() << " of " << whole.size() << " bytes");
            const Outcome file = from_file(path);
            CHECK(memory.ok == file.ok);
            if (!memory.ok || !file.ok) CHECK(memory.text == file.text);
            else CHECK(memory == file);
            ++compared;
            successes += file.ok;
        }
    }
    // The comparison saw both kinds: whole files that read, and broken ones that did not.
    CHECK(successes >= files.size() / 2);
    CHECK(compared - successes > files.size());
}

bool names_data_file(const std::string& bytes) {
    return bytes.find("data file:") != std::string::npos || bytes.find("datafile:") != std::string::npos ||
           (bytes.find("ElementDataFile") != std::string::npos && bytes.find("ElementDataFile = LOCAL") == std::string::npos);
}

bool never(const std::string&) { return false; }

// A 3x2x2 i16 NRRD whose x axis runs in the negative direction: reversed on load, in place.
std::string flipped_nrrd() {
    std::string text = "NRRD0004\ntype: int16\ndimension: 3\nsizes: 3 2 2\nspace dimension: 3\n"
                       "space directions: (-1,0,0) (0,1,0) (0,0,1)\nendian: little\nencoding: raw\n";
    if ((text.size() + 1) % 2 != 0) text += "# \n";  // the samples at an even offset: mappable i16
    text += "\n";
    for (std::int16_t i = 0; i < 12; ++i) text.append(reinterpret_cast<const char*>(&i), 2);
    return text;
}

}  // namespace

TEST_CASE("memory: volumes read as from their file, or fail with the same message", "[io][memory]") {
    std::vector<std::string> files = corpus("nrrd");
    for (const char* f : {"nifti", "metaimage", "vtk"})
        for (const std::string& path : corpus(f)) files.push_back(path);
    files.push_back(test_data("headsq.nrrd"));
    files.push_back(test_data("mri_someones_anatomy.nii.gz"));
    check_same_outcomes(files, volume_from_file, volume_from_memory, names_data_file);
}

TEST_CASE("memory: meshes read as from their file, or fail with the same message", "[io][memory]") {
    std::vector<std::string> files;
    for (const char* f : {"stl", "ply", "obj"})
        for (const std::string& path : corpus(f)) files.push_back(path);
    files.push_back(test_data("torus.stl"));
    check_same_outcomes(files, mesh_from_file, mesh_from_memory, never);
}

TEST_CASE("memory: the caller's bytes are only read, and not kept", "[io][memory]") {
    // Axis x is reversed on load: in a copy, never in the caller's bytes.
    iotest::Scratch s;
    const std::string nrrd = flipped_nrrd();
    std::string bytes = nrrd;
    VolumeInfo info;
    Volume v = read_volume_from_memory(bytes.data(), bytes.size(), "scan.nrrd", info);
    CHECK(info.flipped[0]);
    CHECK(bytes == nrrd);
    const Volume from_file = read_volume(s.file("scan.nrrd", nrrd));
    REQUIRE(v.byte_size() == from_file.byte_size());
    CHECK(std::memcmp(v.data, from_file.data, v.byte_size()) == 0);
    // The Volume owns its samples: the caller may reuse its buffer, and writes stay private.
    std::fill(bytes.begin(), bytes.end(), '\x7f');
    CHECK(std::memcmp(v.data, from_file.data, v.byte_size()) == 0);
    bytes = nrrd;
    std::memset(v.data, 0, v.byte_size());
    CHECK(bytes == nrrd);

    const std::string stl = iotest::read_file(test_data("torus.stl"));
    std::string copy = stl;
    const Mesh m = read_mesh_from_memory(copy.data(), copy.size(), "torus.stl");
    CHECK(copy == stl);
    CHECK(m.positions == read_mesh(test_data("torus.stl")).positions);
}

TEST_CASE("memory: a header cannot name a data file beside it", "[io][memory][errors]") {
    const std::string nhdr = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: scan.raw\n";
    CHECK_THROWS_WITH(read_volume_from_memory(nhdr.data(), nhdr.size(), "upload.nhdr"),
                      Contains("'upload.nhdr'") && Contains("separate data file 'scan.raw'"));
    CHECK_THROWS_WITH(read_volume_info_from_memory(nhdr.data(), nhdr.size(), "upload.nhdr"),
                      Contains("separate data file"));
    const std::string mhd = "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\n"
                            "ElementDataFile = /etc/passwd\n";
    CHECK_THROWS_WITH(read_volume_from_memory(mhd.data(), mhd.size(), "upload.mhd"),
                      Contains("'upload.mhd'") && Contains("separate data file '/etc/passwd'"));
}

TEST_CASE("memory: names pick the format; nothing given is an error", "[io][memory][errors]") {
    const std::string stl = iotest::read_file(test_data("torus.stl"));
    CHECK_THROWS_WITH(read_mesh_from_memory(stl.data(), stl.size(), "torus.bin"),
                      Contains("'torus.bin'") && Contains("unknown mesh format"));
    CHECK_THROWS_WITH(read_volume_from_memory(stl.data(), stl.size(), "torus"),
                      Contains("'torus'") && Contains("unknown volume format"));
    CHECK_THROWS_WITH(read_mesh_from_memory(nullptr, 0, "empty.stl"), Contains("'empty.stl'") && Contains("empty"));
    CHECK_THROWS_WITH(read_volume_from_memory(nullptr, 0, "empty.nrrd"), Contains("'empty.nrrd'") && Contains("empty"));
    CHECK_THROWS_WITH(read_volume_from_memory(nullptr, 10, "null.nrrd"), Contains("'null.nrrd'") && Contains("null pointer"));
}

TEST_CASE("memory: raw samples and their info", "[io][memory]") {
    // 3x2x2 big-endian u16 after a 5-byte offset, with the z axis reversed by a negative spacing.
    std::string bytes = "HEAD!";
    for (unsigned i = 0; i < 12; ++i) {
        bytes += static_cast<char>(0);
        bytes += static_cast<char>(i);
    }
    RawLayout layout;
    layout.dims = {3, 2, 2};
    layout.type = ScalarType::U16;
    layout.big_endian = true;
    layout.offset = 5;
    layout.spacing = {1, 1, -2};
    const Volume v = read_raw_from_memory(bytes.data(), bytes.size(), "slab.raw", layout);
    const auto* s = static_cast<const std::uint16_t*>(v.data);
    CHECK(s[0] == 6);   // z reversed: the file's second slice first
    CHECK(s[11] == 5);
    CHECK(v.origin[2] == -2);
    CHECK_THROWS_WITH(read_raw_from_memory(bytes.data(), bytes.size() - 1, "slab.raw", layout),
                      Contains("'slab.raw'") && Contains("holds 28 bytes"));
}

TEST_CASE("memory: read_volume_info_from_memory says what read_volume_info says", "[io][memory]") {
    for (const char* name : {"headsq.nrrd", "mri_someones_anatomy.nii.gz"}) {
        INFO(name);
        const std::string bytes = iotest::read_file(test_data(name));
        const VolumeInfo memory = read_volume_info_from_memory(bytes.data(), bytes.size(), name);
        const VolumeInfo file = read_volume_info(test_data(name));
        CHECK(memory.format == file.format);
        CHECK(memory.type == file.type);
        CHECK(memory.dims == file.dims);
        CHECK(memory.spacing == file.spacing);
        CHECK(memory.origin == file.origin);
        CHECK(memory.flipped == file.flipped);
        CHECK(memory.encoding == file.encoding);
        CHECK(memory.file_bytes == bytes.size());
        CHECK(memory.data_file == name);
        CHECK(memory.key_values == file.key_values);
    }
}

namespace {

// A small closed surface, with normals and without.
Mesh sphere_mesh(bool normals) {
    const FieldVolume field = make_field(Field::Sphere, 20);
    Options options;
    options.iso = field.iso;
    options.normals = normals;
    return extract(field.volume.view(), options);
}

std::string as_string(const std::vector<unsigned char>& bytes) { return {bytes.begin(), bytes.end()}; }

}  // namespace

TEST_CASE("memory: write_mesh_to_memory gives write_mesh's bytes, which read back", "[io][memory]") {
    iotest::Scratch s;
    for (const bool normals : {true, false})
        for (const char* name : {"sphere.stl", "sphere.PLY", "sphere.obj"}) {
            INFO(name << (normals ? " with normals" : ""));
            const Mesh mesh = sphere_mesh(normals);
            REQUIRE(mesh.triangle_count() > 500);
            const std::string path = s.dir + "/" + name;
            write_mesh(path, mesh);
            const std::vector<unsigned char> bytes = write_mesh_to_memory(mesh, name);
            CHECK(as_string(bytes) == iotest::read_file(path));
            // STL and PLY are sized before writing; OBJ's spare room after growing is given back.
            if (std::string(name) == "sphere.obj") CHECK(bytes.capacity() - bytes.size() <= bytes.size() / 8);
            else CHECK(bytes.capacity() == bytes.size());
            const Mesh back = read_mesh_from_memory(bytes.data(), bytes.size(), name);
            CHECK(back.triangle_count() == mesh.triangle_count());
            if (std::string(name) != "sphere.stl") {  // STL welds and drops normals
                CHECK(back.positions == mesh.positions);
                CHECK(back.indices == mesh.indices);
                CHECK(back.normals == mesh.normals);
            }
        }
}

TEST_CASE("memory: write_mesh_to_memory refuses what write_mesh refuses, naming the name", "[io][memory][errors]") {
    Mesh mesh = sphere_mesh(false);
    CHECK_THROWS_WITH(write_mesh_to_memory(mesh, "sphere.vtk"),
                      Contains("cannot write 'sphere.vtk'") && Contains("unknown mesh format '.vtk'"));
    mesh.positions[4] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(write_mesh_to_memory(mesh, "sphere.ply"), Contains("cannot write 'sphere.ply'") && Contains("coordinate"));
    mesh = sphere_mesh(false);
    mesh.indices.push_back(0);
    CHECK_THROWS_AS(write_mesh_to_memory(mesh, "sphere.stl"), Error);
}

TEST_CASE("memory: write_nrrd_to_memory gives write_nrrd's bytes, which read back", "[io][memory]") {
    iotest::Scratch s;
    const FieldVolume field = make_field(Field::Ct, 24, ScalarType::I16);
    VolumeView view = field.volume.view();
    view.spacing = {0.5, 0.75, 2};
    view.origin = {-3, 4, 1e-3};
    const std::map<std::string, std::string> key_values{{"patient", "phantom"}, {"iso", "0.5"}};
    const std::string path = s.dir + "/ct.nrrd";
    write_nrrd(path, view, key_values);
    const std::vector<unsigned char> bytes = write_nrrd_to_memory(view, "ct.nrrd", key_values);
    CHECK(as_string(bytes) == iotest::read_file(path));
    CHECK(bytes.capacity() == bytes.size());  // sized before writing
    VolumeInfo info;
    const Volume back = read_volume_from_memory(bytes.data(), bytes.size(), "ct.nrrd", info);
    CHECK(back.dims == view.dims);
    CHECK(back.spacing == view.spacing);
    CHECK(back.origin == view.origin);
    CHECK(info.key_values == key_values);
    REQUIRE(back.byte_size() == field.volume.byte_size());
    CHECK(std::memcmp(back.data, field.volume.data, back.byte_size()) == 0);

    view.spacing[1] = 0;
    CHECK_THROWS_WITH(write_nrrd_to_memory(view, "ct.nrrd"), Contains("'ct.nrrd'") && Contains("spacing"));
}

TEST_CASE("memory: bytes handed over are used in place where a file would be mapped", "[io][memory]") {
    SECTION("raw NRRD samples: no copy, the vector is kept") {
        const FieldVolume field = make_field(Field::Sphere, 32, ScalarType::F32);
        std::vector<unsigned char> bytes = write_nrrd_to_memory(field.volume.view(), "ball.nrrd");
        const unsigned char* const first = bytes.data();
        const std::size_t size = bytes.size();
        const Volume v = read_volume_from_memory(std::move(bytes), "ball.nrrd");
        CHECK(bytes.empty());
        const auto* samples = static_cast<const unsigned char*>(v.data);
        CHECK(samples >= first);
        CHECK(samples + v.byte_size() == first + size);  // the samples end the file
        CHECK(std::memcmp(v.data, field.volume.data, v.byte_size()) == 0);
    }
    SECTION("a flipped axis is reversed in place, as read from the file") {
        iotest::Scratch s;
        const std::string nrrd = flipped_nrrd();
        const Volume from_file = read_volume(s.file("scan.nrrd", nrrd));
        std::vector<unsigned char> bytes(nrrd.begin(), nrrd.end());
        const unsigned char* const first = bytes.data();
        VolumeInfo info;
        const Volume v = read_volume_from_memory(std::move(bytes), "scan.nrrd", info);
        REQUIRE(info.flipped[0]);
        CHECK(static_cast<const unsigned char*>(v.data) == first + nrrd.size() - 24);  // the samples end it
        CHECK(static_cast<const std::int16_t*>(v.data)[0] == 2);  // the file's row 0 1 2, reversed
        REQUIRE(v.byte_size() == from_file.byte_size());
        CHECK(std::memcmp(v.data, from_file.data, v.byte_size()) == 0);
    }
    SECTION("compressed samples are inflated; the vector is let go") {
        const std::string gz = iotest::read_file(test_data("mri_someones_anatomy.nii.gz"));
        const Volume lent = read_volume_from_memory(gz.data(), gz.size(), "mri.nii.gz");
        const Volume v = read_volume_from_memory(std::vector<unsigned char>(gz.begin(), gz.end()), "mri.nii.gz");
        REQUIRE(v.byte_size() == lent.byte_size());
        CHECK(std::memcmp(v.data, lent.data, v.byte_size()) == 0);
    }
    SECTION("errors name the name") {
        CHECK_THROWS_WITH(read_volume_from_memory(std::vector<unsigned char>{}, "none.nrrd"),
                          Contains("'none.nrrd'") && Contains("empty"));
    }
}
