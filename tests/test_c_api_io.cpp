// The C API's bytes in memory, raw and NRRD volumes, file facts, chunked OpenCL options,
// per-device stats and keep_largest_components against the C++ calls they wrap.
#ifdef VOXMESH_TEST_C_API
#include <catch2/catch.hpp>
#include <voxmesh/fields.hpp>
#include <voxmesh/io.hpp>
#include <voxmesh/voxmesh.h>
#include <voxmesh/voxmesh.hpp>

#include "support/c_api.hpp"
#include "support/io_scratch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace {

using capitest::BytesPtr;
using capitest::c_view;
using capitest::extract_c;
using capitest::MeshPtr;
using capitest::require_same;
using capitest::VolumePtr;

std::string text(const voxmesh_bytes* bytes) {
    const unsigned char* data = voxmesh_bytes_data(bytes);
    return data ? std::string(reinterpret_cast<const char*>(data), voxmesh_bytes_size(bytes)) : std::string();
}

std::string text(const std::vector<unsigned char>& bytes) { return std::string(bytes.begin(), bytes.end()); }

void require_same(const voxmesh_volume* c, const voxmesh::Volume& cpp) {
    require_same(voxmesh_volume_get_view(c), cpp);
}

void require_same(const voxmesh_volume_info& c, const voxmesh::VolumeInfo& cpp) {
    CHECK(std::string(c.format) == cpp.format);
    CHECK(std::string(c.encoding) == cpp.encoding);
    CHECK(c.big_endian == cpp.big_endian);
    for (int a = 0; a < 3; ++a) CHECK(c.flipped[a] == cpp.flipped[a]);
    CHECK(c.rotation_dropped == cpp.rotation_dropped);
    CHECK(c.value_scale == cpp.value_scale);
    CHECK(c.value_offset == cpp.value_offset);
    for (std::size_t i = 0; i < 9; ++i) CHECK(c.directions[i] == cpp.directions[i]);
    for (std::size_t c3 = 0; c3 < 3; ++c3) CHECK(c.world_origin[c3] == cpp.world_origin[c3]);
}

}  // namespace

TEST_CASE("C API: meshes to and from bytes are write_mesh_to_memory's and read_mesh_from_memory's", "[capi]") {
    voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Sphere, 20, voxmesh::ScalarType::F32);
    voxmesh_options options = voxmesh_default_options();
    options.iso = field.iso;
    const MeshPtr mesh = extract_c(c_view(field.volume.view()), options);
    voxmesh_mesh* made = nullptr;
    voxmesh::Options cpp;
    cpp.iso = field.iso;
    const voxmesh::Mesh expected = voxmesh::extract(field.volume.view(), cpp);
    for (const char* name : {"part.stl", "part.ply", "part.obj"}) {
        CAPTURE(name);
        voxmesh_bytes* written = nullptr;
        REQUIRE(voxmesh_write_mesh_to_memory(mesh.get(), name, &written) == VOXMESH_OK);
        const BytesPtr bytes(written, voxmesh_bytes_free);
        const std::vector<unsigned char> want = voxmesh::write_mesh_to_memory(expected, name);
        CHECK(text(bytes.get()) == text(want));
        REQUIRE(voxmesh_read_mesh_from_memory(voxmesh_bytes_data(bytes.get()), voxmesh_bytes_size(bytes.get()), name,
                                              &made) == VOXMESH_OK);
        const MeshPtr back(made, voxmesh_mesh_free);
        require_same(back.get(), voxmesh::read_mesh_from_memory(want.data(), want.size(), name));
    }
    voxmesh_bytes* none = reinterpret_cast<voxmesh_bytes*>(&options);  // must come back NULL
    CHECK(voxmesh_write_mesh_to_memory(mesh.get(), "part.xyz", &none) == VOXMESH_ERROR);
    CHECK(none == nullptr);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("part.xyz"));
    const char junk[] = "solid nothing\nfacet normal 0 0\n";
    CHECK(voxmesh_read_mesh_from_memory(junk, sizeof junk - 1, "junk.stl", &made) == VOXMESH_ERROR);
    CHECK(made == nullptr);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("'junk.stl'"));
    CHECK(voxmesh_read_mesh_from_memory(nullptr, 10, "a.stl", &made) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_read_mesh_from_memory: the data is NULL");
    CHECK(voxmesh_bytes_size(nullptr) == 0);
    CHECK(voxmesh_bytes_data(nullptr) == nullptr);
    voxmesh_bytes_free(nullptr);
}

TEST_CASE("C API: volumes from bytes, raw files and NRRD writes, with what the file said", "[capi]") {
    const iotest::Scratch scratch;
    for (const char* file : {"headsq.nrrd", "mri_someones_anatomy.nii.gz"}) {
        CAPTURE(file);
        const std::string path = std::string(VOXMESH_TEST_DATA) + "/" + file;
        voxmesh::VolumeInfo want_info;
        const voxmesh::Volume want = voxmesh::read_volume(path, want_info);
        voxmesh_volume* made = nullptr;
        REQUIRE(voxmesh_read_volume(path.c_str(), &made) == VOXMESH_OK);
        VolumePtr from_file(made, voxmesh_volume_free);
        require_same(from_file.get(), want);
        require_same(voxmesh_volume_get_info(from_file.get()), want_info);

        const std::string bytes = iotest::read_file(path);
        REQUIRE(voxmesh_read_volume_from_memory(bytes.data(), bytes.size(), file, &made) == VOXMESH_OK);
        VolumePtr from_bytes(made, voxmesh_volume_free);
        require_same(from_bytes.get(), want);
        require_same(voxmesh_volume_get_info(from_bytes.get()), want_info);
    }
    CHECK(std::string(voxmesh_volume_get_info(nullptr).format).empty());
    CHECK(voxmesh_volume_get_info(nullptr).value_scale == 1);
    CHECK(voxmesh_volume_get_info(nullptr).directions[4] == 1);  // the identity

    // Raw: big-endian u16 after a 3-byte header, a negative spacing flipping x.
    voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Gyroid, 9, voxmesh::ScalarType::U16);
    std::string raw = "abc";
    const auto* samples = static_cast<const std::uint16_t*>(field.volume.data);
    for (std::size_t i = 0; i < field.volume.sample_count(); ++i) {
        raw += static_cast<char>(samples[i] >> 8);
        raw += static_cast<char>(samples[i] & 0xff);
    }
    const std::string raw_path = scratch.file("gyroid.raw", raw);
    voxmesh_raw_layout layout = voxmesh_default_raw_layout();
    CHECK(layout.type == VOXMESH_U8);
    CHECK(layout.spacing[2] == 1);
    layout.dims[0] = layout.dims[1] = layout.dims[2] = 9;
    layout.type = VOXMESH_U16;
    layout.big_endian = 1;
    layout.offset = 3;
    layout.spacing[0] = -0.5;
    layout.origin[1] = 7;
    voxmesh::RawLayout cpp_layout;
    cpp_layout.dims = {9, 9, 9};
    cpp_layout.type = voxmesh::ScalarType::U16;
    cpp_layout.big_endian = true;
    cpp_layout.offset = 3;
    cpp_layout.spacing = {-0.5, 1, 1};
    cpp_layout.origin = {0, 7, 0};
    voxmesh_volume* made = nullptr;
    REQUIRE(voxmesh_read_raw(raw_path.c_str(), &layout, &made) == VOXMESH_OK);
    VolumePtr from_raw(made, voxmesh_volume_free);
    require_same(from_raw.get(), voxmesh::read_raw(raw_path, cpp_layout));
    const voxmesh_volume_info raw_info = voxmesh_volume_get_info(from_raw.get());
    require_same(raw_info, voxmesh::read_raw_info(raw_path, cpp_layout));
    CHECK(raw_info.flipped[0] == 1);
    layout.offset = 4;  // one byte short now
    CHECK(voxmesh_read_raw(raw_path.c_str(), &layout, &made) == VOXMESH_ERROR);
    CHECK(made == nullptr);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("gyroid.raw"));
    layout.type = 99;
    CHECK(voxmesh_read_raw(raw_path.c_str(), &layout, &made) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("voxmesh_read_raw: unknown scalar type 99"));

    // NRRD out: write_nrrd_to_memory's bytes, in a file or in memory, reading back the same.
    voxmesh_volume_view view = voxmesh_volume_get_view(from_raw.get());
    const voxmesh::Volume raw_volume = voxmesh::read_raw(raw_path, cpp_layout);
    const std::string want = text(voxmesh::write_nrrd_to_memory(raw_volume.view(), "out.nrrd"));
    voxmesh_bytes* written = nullptr;
    REQUIRE(voxmesh_write_nrrd_to_memory(&view, "out.nrrd", &written) == VOXMESH_OK);
    const BytesPtr bytes(written, voxmesh_bytes_free);
    CHECK(text(bytes.get()) == want);
    const std::string nrrd_path = scratch.dir + "/out.nrrd";
    REQUIRE(voxmesh_write_nrrd(nrrd_path.c_str(), &view) == VOXMESH_OK);
    CHECK(iotest::read_file(nrrd_path) == want);
    view.spacing[1] = 0;
    CHECK(voxmesh_write_nrrd(nrrd_path.c_str(), &view) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("spacing"));
    CHECK(iotest::read_file(nrrd_path) == want);  // nothing lost
}

TEST_CASE("C API: the world transform and mesh_to_world are the C++ library's", "[capi]") {
    // A NRRD whose axes are permuted and one mirrored: x along world z, y along world x, z
    // along -y (determinant -1).
    iotest::Scratch scratch;
    const voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Sphere, 12, voxmesh::ScalarType::F32);
    std::string text = "NRRD0004\ntype: float\ndimension: 3\nsizes: 12 12 12\nendian: little\nencoding: raw\n"
                       "space: left-posterior-superior\nspace directions: (0,0,2) (1.5,0,0) (0,-1,0)\n"
                       "space origin: (5,-3,7)\n\n";
    text.append(static_cast<const char*>(field.volume.data), field.volume.byte_size());
    const std::string path = scratch.file("permuted.nrrd", text);
    voxmesh::VolumeInfo info;
    const voxmesh::Volume cpp_volume = voxmesh::read_volume(path, info);
    REQUIRE(info.rotation_dropped);
    voxmesh_volume* made = nullptr;
    REQUIRE(voxmesh_read_volume(path.c_str(), &made) == VOXMESH_OK);
    VolumePtr volume(made, voxmesh_volume_free);
    require_same(voxmesh_volume_get_info(volume.get()), info);

    voxmesh_options options = voxmesh_default_options();
    options.iso = field.iso;
    MeshPtr mesh = extract_c(voxmesh_volume_get_view(volume.get()), options);
    voxmesh::Options cpp_options;
    cpp_options.iso = field.iso;
    voxmesh::Mesh cpp_mesh = voxmesh::extract(cpp_volume.view(), cpp_options);
    REQUIRE(cpp_mesh.triangle_count() > 0);
    const voxmesh::Mesh before = cpp_mesh;
    REQUIRE(voxmesh_mesh_to_world(mesh.get(), volume.get()) == VOXMESH_OK);
    voxmesh::to_world(cpp_mesh, info);
    require_same(mesh.get(), cpp_mesh);
    CHECK(cpp_mesh.indices != before.indices);  // a mirroring turns every triangle over
    CHECK(voxmesh_mesh_to_world(nullptr, volume.get()) == VOXMESH_ERROR);
    CHECK(voxmesh_mesh_to_world(mesh.get(), nullptr) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("the volume"));
}

// A world frame beyond the float range: an error, the mesh left as extracted (it was filled
// with inf, and voxmesh_mesh_to_world said VOXMESH_OK).
TEST_CASE("C API: mesh_to_world refuses a world beyond floats and keeps the mesh", "[capi]") {
    iotest::Scratch scratch;
    std::vector<float> samples(6 * 6 * 6, 0.f);
    for (std::size_t k = 1; k < 5; ++k)
        for (std::size_t j = 1; j < 5; ++j)
            for (std::size_t i = 1; i < 5; ++i) samples[i + 6 * (j + 6 * k)] = 1.f;
    // World x: 2.9e38 + 8e36 * i + 6e36 * j, past FLT_MAX at the box's far corner (i = j = 4.5).
    std::string text = "NRRD0004\ntype: float\ndimension: 3\nsizes: 6 6 6\nendian: little\nencoding: raw\n"
                       "space: right-anterior-superior\nspace directions: (8e36,0,0) (6e36,8e36,0) (0,0,1)\n"
                       "space origin: (2.9e38,0,0)\n\n";
    text.append(reinterpret_cast<const char*>(samples.data()), samples.size() * sizeof(float));
    const std::string path = scratch.file("far.nrrd", text);
    voxmesh_volume* made = nullptr;
    REQUIRE(voxmesh_read_volume(path.c_str(), &made) == VOXMESH_OK);
    VolumePtr volume(made, voxmesh_volume_free);
    voxmesh_options options = voxmesh_default_options();
    options.iso = 0.5;
    MeshPtr mesh = extract_c(voxmesh_volume_get_view(volume.get()), options);
    const std::size_t n = 3 * voxmesh_mesh_vertex_count(mesh.get());
    REQUIRE(n > 0);
    const std::vector<float> before(voxmesh_mesh_positions(mesh.get()), voxmesh_mesh_positions(mesh.get()) + n);
    CHECK(voxmesh_mesh_to_world(mesh.get(), volume.get()) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("beyond the range of float"));
    CHECK(std::equal(before.begin(), before.end(), voxmesh_mesh_positions(mesh.get())));
}

TEST_CASE("C API: keep_largest_components is the C++ call's", "[capi]") {
    // Two balls, the larger one second: it alone is kept, then both in their order.
    std::vector<float> samples(40 * 24 * 24);
    for (std::size_t z = 0; z < 24; ++z)
        for (std::size_t y = 0; y < 24; ++y)
            for (std::size_t x = 0; x < 40; ++x) {
                const auto d2 = [&](double cx, double cy, double cz) {
                    return (x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz);
                };
                const double small = 4 - std::sqrt(d2(8, 12, 12)), large = 8 - std::sqrt(d2(27, 12, 12));
                samples[x + 40 * (y + 24 * z)] = static_cast<float>(std::max(small, large));
            }
    voxmesh::VolumeView cpp_view;
    cpp_view.data = samples.data();
    cpp_view.dims = {40, 24, 24};
    const voxmesh_volume_view view = c_view(cpp_view);
    voxmesh_mesh* made = nullptr;
    REQUIRE(voxmesh_extract(&view, nullptr, &made) == VOXMESH_OK);
    const MeshPtr both(made, voxmesh_mesh_free);
    const voxmesh::Mesh cpp_both = voxmesh::extract(cpp_view, voxmesh::Options{});
    for (std::size_t count : {1u, 2u, 5u}) {
        CAPTURE(count);
        REQUIRE(voxmesh_keep_largest_components(both.get(), count, &made) == VOXMESH_OK);
        const MeshPtr kept(made, voxmesh_mesh_free);
        require_same(kept.get(), voxmesh::keep_largest_components(cpp_both, count));
    }
    voxmesh_topology topology{};
    REQUIRE(voxmesh_keep_largest_components(both.get(), 1, &made) == VOXMESH_OK);
    const MeshPtr largest(made, voxmesh_mesh_free);
    REQUIRE(voxmesh_analyze_topology(largest.get(), &topology) == VOXMESH_OK);
    CHECK(topology.components == 1);
    CHECK(voxmesh_mesh_triangle_count(largest.get()) > voxmesh_mesh_triangle_count(both.get()) / 2);
    CHECK(voxmesh_keep_largest_components(both.get(), 0, &made) == VOXMESH_ERROR);
    CHECK(made == nullptr);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("count must be at least 1"));
}

TEST_CASE("C API: chunk_planes and memory_budget, and per-device stats", "[capi]") {
    voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Sphere, 32, voxmesh::ScalarType::F32);
    const voxmesh_volume_view view = c_view(field.volume.view());
    voxmesh_options options = voxmesh_default_options();
    CHECK(options.chunk_planes == 0);
    CHECK(options.memory_budget == 0);
    options.iso = field.iso;
    options.threads = 2;
    voxmesh::Options cpp;
    cpp.iso = field.iso;
    cpp.threads = 2;
    const bool device = voxmesh_device_count() > 0;
    options.backend = device ? VOXMESH_BACKEND_OPENCL : VOXMESH_BACKEND_CPU;
    cpp.backend = device ? voxmesh::Backend::OpenCL : voxmesh::Backend::Cpu;
    if (device) {
        options.devices = nullptr;
        options.device_count = 0;
        options.chunk_planes = 5;
        cpp.chunk_planes = 5;
    }
    voxmesh_mesh* made = nullptr;
    REQUIRE(voxmesh_extract(&view, &options, &made) == VOXMESH_OK);
    const MeshPtr mesh(made, voxmesh_mesh_free);
    voxmesh::Stats want;
    const voxmesh::Mesh expected = voxmesh::extract(field.volume.view(), cpp, want);
    REQUIRE(voxmesh_mesh_triangle_count(mesh.get()) == expected.triangle_count());
    CHECK(std::memcmp(voxmesh_mesh_indices(mesh.get()), expected.indices.data(), expected.indices.size() * 4) == 0);

    REQUIRE(voxmesh_mesh_device_stats_count(mesh.get()) == want.devices.size());
    REQUIRE(!want.devices.empty());
    std::size_t chunks = 0, voxels = 0;
    for (std::size_t i = 0; i < want.devices.size(); ++i) {
        voxmesh_device_stats got{};
        REQUIRE(voxmesh_mesh_get_device_stats(mesh.get(), i, &got) == VOXMESH_OK);
        CHECK(std::string(got.name) == want.devices[i].name.substr(0, sizeof got.name - 1));
        CHECK(got.chunks == want.devices[i].chunks);
        CHECK(got.voxels == want.devices[i].voxels);
        CHECK(got.wall_s > 0);
        chunks += got.chunks;
        voxels += got.voxels;
    }
    if (device) CHECK(chunks >= 32 / 5);  // 31 planes of cells in chunks of 5
    CHECK(voxels >= field.volume.sample_count());
    voxmesh_device_stats none{};
    CHECK(voxmesh_mesh_get_device_stats(mesh.get(), want.devices.size(), &none) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("did not take part"));

    // A memory budget too small for one plane is the C++ call's refusal or its smaller chunks.
    if (device) {
        options.chunk_planes = 0;
        options.memory_budget = 1;
        cpp.chunk_planes = 0;
        cpp.memory_budget = 1;
        std::string cpp_message = "(no error)";
        try {
            voxmesh::extract(field.volume.view(), cpp);
        } catch (const voxmesh::Error& e) {
            cpp_message = e.what();
        }
        const voxmesh_status status = voxmesh_extract(&view, &options, &made);
        voxmesh_mesh_free(made);
        CHECK(std::string(status == VOXMESH_OK ? "(no error)" : voxmesh_last_error()) == cpp_message);
    }
    // A mesh no extract made has no device stats.
    CHECK(voxmesh_mesh_device_stats_count(nullptr) == 0);
}
#endif  // VOXMESH_TEST_C_API
