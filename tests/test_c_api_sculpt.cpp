// The C API's sculpting calls (voxmesh_sculpt_*) against voxmesh::Sculpt: the same dabs give
// the same dirty blocks, block meshes and welded mesh bit for bit, and the same refusals.
#ifdef VOXMESH_TEST_C_API
#include <catch2/catch.hpp>
#include <voxmesh/fields.hpp>
#include <voxmesh/io.hpp>
#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxmesh.h>
#include <voxmesh/voxmesh.hpp>

#include "support/c_api.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace {

using capitest::c_view;
using capitest::MeshPtr;
using capitest::require_same;
using capitest::SculptPtr;

template <class T>
bool same_bytes(const T* c, std::size_t count, std::span<const T> cpp) {
    if (cpp.empty()) return c == nullptr && count == 0;
    return c && count == cpp.size() && std::memcmp(c, cpp.data(), cpp.size_bytes()) == 0;
}

// Every block of the C sculpt against the C++ one's: place, cells and mesh bytes.
void require_same_blocks(const voxmesh_sculpt* c, const voxmesh::Sculpt& cpp) {
    REQUIRE(voxmesh_sculpt_block_count(c) == cpp.block_count());
    std::size_t grid[3] = {0, 0, 0};
    voxmesh_sculpt_block_grid(c, grid);
    for (int a = 0; a < 3; ++a) CHECK(grid[a] == cpp.block_grid()[a]);
    for (std::size_t i = 0; i < cpp.block_count(); ++i) {
        voxmesh_block b{};
        REQUIRE(voxmesh_sculpt_get_block(c, i, &b) == VOXMESH_OK);
        const voxmesh::BlockMesh want = cpp.block(i);
        CHECK(b.index == want.index);
        for (int a = 0; a < 3; ++a) {
            CHECK(b.coord[a] == want.coord[a]);
            CHECK(b.cell_begin[a] == want.cell_begin[a]);
            CHECK(b.cell_end[a] == want.cell_end[a]);
        }
        CHECK(b.vertex_count == want.vertex_count());
        CHECK(b.triangle_count == want.triangle_count());
        CHECK(same_bytes(b.positions, 3 * b.vertex_count, want.positions));
        CHECK(same_bytes(b.normals, b.normals ? 3 * b.vertex_count : 0, want.normals));
        CHECK(same_bytes(b.indices, 3 * b.triangle_count, want.indices));
    }
}

std::string cpp_error(const std::function<void()>& body) {
    try {
        body();
    } catch (const voxmesh::Error& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace

TEST_CASE("C API sculpt: dabs give the C++ Sculpt's dirty blocks, block meshes and mesh", "[capi][sculpt]") {
    voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Sphere, 40, voxmesh::ScalarType::F32);
    voxmesh::VolumeView cpp_view = field.volume.view();
    cpp_view.spacing = {0.5, 0.75, 1.0};
    cpp_view.origin = {-3, 2, 1};
    const voxmesh_volume_view view = c_view(cpp_view);

    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    options.iso = field.iso;
    options.block_size = 12;
    options.threads = 2;
    voxmesh::SculptOptions cpp_options;
    cpp_options.iso = field.iso;
    cpp_options.block_size = 12;
    cpp_options.threads = 2;

    voxmesh_sculpt* made = nullptr;
    REQUIRE(voxmesh_sculpt_new(&view, &options, &made) == VOXMESH_OK);
    SculptPtr c(made, voxmesh_sculpt_free);
    voxmesh::Sculpt cpp(cpp_view, cpp_options);
    CHECK(voxmesh_sculpt_backend(c.get()) == VOXMESH_BACKEND_CPU);
    CHECK(std::string(voxmesh_sculpt_device_name(c.get())) == "cpu");

    // The samples are a copy with the view's geometry.
    const voxmesh_volume_view copy = voxmesh_sculpt_get_view(c.get());
    CHECK(copy.data != view.data);
    CHECK(copy.data == voxmesh_sculpt_data(c.get()));
    CHECK(copy.type == VOXMESH_F32);
    for (int a = 0; a < 3; ++a) {
        CHECK(copy.dims[a] == view.dims[a]);
        CHECK(copy.spacing[a] == view.spacing[a]);
        CHECK(copy.origin[a] == view.origin[a]);
    }
    CHECK(std::memcmp(copy.data, view.data, field.volume.byte_size()) == 0);

    CHECK(voxmesh_sculpt_dirty(c.get()));
    voxmesh_update_result first{};
    REQUIRE(voxmesh_sculpt_update(c.get(), &first) == VOXMESH_OK);
    const voxmesh::UpdateResult cpp_first = cpp.update();
    CHECK(first.remeshed == cpp_first.remeshed);
    CHECK(first.remeshed == voxmesh_sculpt_block_count(c.get()));
    CHECK_FALSE(voxmesh_sculpt_dirty(c.get()));
    require_same_blocks(c.get(), cpp);

    // Each kind of dab, in samples and in world units, then a region set.
    const double a[3] = {12, 20, 20}, b[3] = {-1.0, 14.0, 21.0}, s[3] = {20, 8, 20};
    REQUIRE(voxmesh_sculpt_apply(c.get(), VOXMESH_BRUSH_ADD, a, 5, 2, VOXMESH_UNITS_SAMPLES) == VOXMESH_OK);
    cpp.add({12, 20, 20}, 5, 2);
    REQUIRE(voxmesh_sculpt_apply(c.get(), VOXMESH_BRUSH_SUBTRACT, b, 3, 1.5, VOXMESH_UNITS_WORLD) == VOXMESH_OK);
    cpp.subtract({-1.0, 14.0, 21.0}, 3, 1.5, voxmesh::Units::World);
    REQUIRE(voxmesh_sculpt_apply(c.get(), VOXMESH_BRUSH_SMOOTH, s, 6, 0.8, VOXMESH_UNITS_SAMPLES) == VOXMESH_OK);
    cpp.smooth({20, 8, 20}, 6, 0.8);
    const double lo[3] = {30, 30, 30}, hi[3] = {35, 36, 39};
    REQUIRE(voxmesh_sculpt_set_region(c.get(), lo, hi, -5, VOXMESH_UNITS_SAMPLES) == VOXMESH_OK);
    cpp.set_region({30, 30, 30}, {35, 36, 39}, -5);
    CHECK(voxmesh_sculpt_dirty(c.get()));

    voxmesh_update_result after{};
    REQUIRE(voxmesh_sculpt_update(c.get(), &after) == VOXMESH_OK);
    const voxmesh::UpdateResult cpp_after = cpp.update();
    CHECK(after.remeshed == cpp_after.remeshed);
    REQUIRE(after.changed_count == cpp_after.changed.size());
    REQUIRE(after.changed_count > 0);
    CHECK(std::vector<std::size_t>(after.changed, after.changed + after.changed_count) == cpp_after.changed);
    CHECK(after.remeshed < voxmesh_sculpt_block_count(c.get()));  // only what the dabs reached
    require_same_blocks(c.get(), cpp);

    // mesh() is the C++ Sculpt's, which is extract's canonical mesh of the edited samples.
    voxmesh_mesh* welded = nullptr;
    REQUIRE(voxmesh_sculpt_mesh(c.get(), &welded) == VOXMESH_OK);
    MeshPtr mesh(welded, voxmesh_mesh_free);
    require_same(mesh.get(), cpp.mesh());
    voxmesh::Options extract_options;
    extract_options.iso = field.iso;
    extract_options.backend = voxmesh::Backend::Cpu;
    voxmesh::VolumeView edited = cpp_view;
    edited.data = voxmesh_sculpt_get_view(c.get()).data;
    require_same(mesh.get(), voxmesh::extract(edited, extract_options));
    CHECK(voxmesh_mesh_stats(mesh.get()).backend == VOXMESH_BACKEND_AUTO);  // not an extract
    CHECK(std::string(voxmesh_sculpt_warnings(c.get())).empty());

    // An update with nothing dirty re-meshes nothing; the result may be NULL.
    REQUIRE(voxmesh_sculpt_update(c.get(), &after) == VOXMESH_OK);
    CHECK(after.remeshed == 0);
    CHECK(after.changed_count == 0);
    CHECK(voxmesh_sculpt_update(c.get(), nullptr) == VOXMESH_OK);
}

TEST_CASE("C API sculpt: samples written through data, normals off, inside_below, u8", "[capi][sculpt]") {
    voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Gyroid, 24, voxmesh::ScalarType::U8);
    const voxmesh_volume_view view = c_view(field.volume.view());
    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    options.iso = field.iso;
    options.normals = 0;
    options.inside_below = 1;
    options.block_size = 8;
    voxmesh_sculpt* made = nullptr;
    REQUIRE(voxmesh_sculpt_new(&view, &options, &made) == VOXMESH_OK);
    SculptPtr c(made, voxmesh_sculpt_free);

    // A slab of samples set through data, then invalidate_all: the mesh is extract's.
    auto* samples = static_cast<std::uint8_t*>(voxmesh_sculpt_data(c.get()));
    std::memset(samples + 24 * 24 * 5, 255, 24 * 24 * 3);
    REQUIRE(voxmesh_sculpt_invalidate_all(c.get()) == VOXMESH_OK);
    CHECK(voxmesh_sculpt_dirty(c.get()));
    voxmesh_mesh* welded = nullptr;
    REQUIRE(voxmesh_sculpt_mesh(c.get(), &welded) == VOXMESH_OK);  // updates first
    MeshPtr mesh(welded, voxmesh_mesh_free);
    CHECK_FALSE(voxmesh_sculpt_dirty(c.get()));
    CHECK(voxmesh_mesh_normals(mesh.get()) == nullptr);
    voxmesh::VolumeView edited = field.volume.view();
    edited.data = samples;
    voxmesh::Options extract_options;
    extract_options.iso = field.iso;
    extract_options.backend = voxmesh::Backend::Cpu;
    extract_options.normals = false;
    extract_options.inside_below = true;
    const voxmesh::Mesh want = voxmesh::extract(edited, extract_options);
    REQUIRE(want.triangle_count() > 0);
    require_same(mesh.get(), want);
    voxmesh_block block{};
    bool some = false;
    for (std::size_t i = 0; i < voxmesh_sculpt_block_count(c.get()); ++i) {
        REQUIRE(voxmesh_sculpt_get_block(c.get(), i, &block) == VOXMESH_OK);
        CHECK(block.normals == nullptr);
        some = some || block.triangle_count > 0;
    }
    CHECK(some);
}

TEST_CASE("C API sculpt: a model voxelized is the C++ from_mesh's", "[capi][sculpt]") {
    const std::string path = std::string(VOXMESH_TEST_DATA) + "/unit_sphere.stl";
    voxmesh_mesh* model = nullptr;
    REQUIRE(voxmesh_read_mesh(path.c_str(), &model) == VOXMESH_OK);
    MeshPtr model_ptr(model, voxmesh_mesh_free);
    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    options.block_size = 16;
    voxmesh_voxelize_options grid = voxmesh_default_voxelize_options();
    grid.resolution = 32;
    grid.band = 4;
    voxmesh_sculpt* made = nullptr;
    REQUIRE(voxmesh_sculpt_from_mesh(model, &grid, &options, &made) == VOXMESH_OK);
    SculptPtr c(made, voxmesh_sculpt_free);
    voxmesh::SculptOptions cpp_options;
    cpp_options.block_size = 16;
    voxmesh::Sculpt cpp = voxmesh::Sculpt::from_mesh(voxmesh::read_mesh(path), 32, cpp_options);

    // Brushes in world units with the voxel spacing as the strength scale (from_mesh's).
    const double center[3] = {0.0, 0.0, 1.0};
    REQUIRE(voxmesh_sculpt_apply(c.get(), VOXMESH_BRUSH_ADD, center, 0.3, 2, VOXMESH_UNITS_WORLD) == VOXMESH_OK);
    cpp.add({0.0, 0.0, 1.0}, 0.3, 2, voxmesh::Units::World);
    voxmesh_mesh* welded = nullptr;
    REQUIRE(voxmesh_sculpt_mesh(c.get(), &welded) == VOXMESH_OK);
    MeshPtr mesh(welded, voxmesh_mesh_free);
    const voxmesh::Mesh want = cpp.mesh();
    require_same(mesh.get(), want);
    voxmesh_topology topology{};
    REQUIRE(voxmesh_analyze_topology(mesh.get(), &topology) == VOXMESH_OK);
    CHECK(topology.boundary_edges == 0);
    CHECK(topology.nonmanifold_edges == 0);
    CHECK(topology.euler == 2);

    // NULL: from_mesh(model, 128)'s grid. More padding: a larger volume around the same model.
    REQUIRE(voxmesh_sculpt_from_mesh(model, nullptr, &options, &made) == VOXMESH_OK);
    c.reset(made);
    const voxmesh::Sculpt default_grid = voxmesh::Sculpt::from_mesh(voxmesh::read_mesh(path), 128, cpp_options);
    const voxmesh_volume_view view = voxmesh_sculpt_get_view(c.get());
    for (int a = 0; a < 3; ++a) CHECK(view.dims[a] == default_grid.view().dims[a]);
    CHECK(std::memcmp(view.data, default_grid.view().data, 4 * view.dims[0] * view.dims[1] * view.dims[2]) == 0);
    grid.padding = 7;
    REQUIRE(voxmesh_sculpt_from_mesh(model, &grid, &options, &made) == VOXMESH_OK);
    c.reset(made);
    CHECK(voxmesh_sculpt_get_view(c.get()).dims[0] == 32 + 2 * 7);
    grid.field = VOXMESH_FIELD_OCCUPANCY;
    CHECK(voxmesh_sculpt_from_mesh(model, &grid, &options, &made) == VOXMESH_ERROR);
    CHECK(made == nullptr);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("distance field"));
    grid.field = 5;
    CHECK(voxmesh_sculpt_from_mesh(model, &grid, &options, &made) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("voxmesh_sculpt_from_mesh: unknown field 5"));
}

TEST_CASE("C API sculpt: refusals give the C++ messages, a status and no object", "[capi][sculpt]") {
    std::vector<std::int16_t> i16(8 * 8 * 8);
    voxmesh::VolumeView cpp_view;
    cpp_view.data = i16.data();
    cpp_view.type = voxmesh::ScalarType::I16;
    cpp_view.dims = {8, 8, 8};
    voxmesh_volume_view view = c_view(cpp_view);
    voxmesh_sculpt* made = reinterpret_cast<voxmesh_sculpt*>(&view);  // must come back NULL
    CHECK(voxmesh_sculpt_new(&view, nullptr, &made) == VOXMESH_ERROR);
    CHECK(made == nullptr);
    CHECK(std::string(voxmesh_last_error()) == cpp_error([&] { voxmesh::Sculpt{cpp_view}; }));

    std::vector<float> f(8 * 8 * 8, 1.0f);
    f[100] = NAN;
    cpp_view.data = f.data();
    cpp_view.type = voxmesh::ScalarType::F32;
    view = c_view(cpp_view);
    CHECK(voxmesh_sculpt_new(&view, nullptr, &made) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == cpp_error([&] { voxmesh::Sculpt{cpp_view}; }));
    f[100] = -1;

    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    options.block_size = 1;
    CHECK(voxmesh_sculpt_new(&view, &options, &made) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("block size"));
    options = voxmesh_default_sculpt_options();
    options.backend = VOXMESH_BACKEND_HYBRID;
    CHECK(voxmesh_sculpt_new(&view, &options, &made) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("hybrid"));
    options.backend = 9;
    CHECK(voxmesh_sculpt_new(&view, &options, &made) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("voxmesh_sculpt_new: unknown backend 9"));
    options = voxmesh_default_sculpt_options();
    view.type = 42;
    CHECK(voxmesh_sculpt_new(&view, &options, &made) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("voxmesh_sculpt_new: unknown scalar type 42"));
    view.type = VOXMESH_F32;
    CHECK(voxmesh_sculpt_new(nullptr, &options, &made) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_new: the volume is NULL");
    CHECK(voxmesh_sculpt_from_mesh(nullptr, nullptr, &options, &made) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_from_mesh: the model is NULL");

    REQUIRE(voxmesh_sculpt_new(&view, nullptr, &made) == VOXMESH_OK);
    SculptPtr c(made, voxmesh_sculpt_free);
    const double center[3] = {4, 4, 4};
    CHECK(voxmesh_sculpt_apply(c.get(), 7, center, 2, 1, VOXMESH_UNITS_SAMPLES) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("voxmesh_sculpt_apply: unknown brush 7"));
    CHECK(voxmesh_sculpt_apply(c.get(), VOXMESH_BRUSH_ADD, center, 2, 1, 5) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("voxmesh_sculpt_apply: unknown units 5"));
    CHECK(voxmesh_sculpt_apply(c.get(), VOXMESH_BRUSH_ADD, nullptr, 2, 1, 0) == VOXMESH_ERROR);
    voxmesh::Sculpt cpp(cpp_view);
    CHECK(voxmesh_sculpt_apply(c.get(), VOXMESH_BRUSH_ADD, center, -2, 1, 0) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == cpp_error([&] { cpp.add({4, 4, 4}, -2, 1); }));
    const double lo[3] = {0, 0, 0};
    CHECK(voxmesh_sculpt_set_region(c.get(), lo, nullptr, 1, 0) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_set_region: hi is NULL");

    voxmesh_block block{};
    CHECK(voxmesh_sculpt_get_block(c.get(), voxmesh_sculpt_block_count(c.get()), &block) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("does not exist"));
    static_cast<float*>(voxmesh_sculpt_data(c.get()))[100] = INFINITY;
    CHECK(voxmesh_sculpt_invalidate_all(c.get()) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("infinite"));

    // NULL sculpts: the queries answer "nothing", freeing does nothing.
    CHECK(voxmesh_sculpt_block_count(nullptr) == 0);
    CHECK(voxmesh_sculpt_dirty(nullptr) == 0);
    CHECK(voxmesh_sculpt_data(nullptr) == nullptr);
    CHECK(voxmesh_sculpt_get_view(nullptr).data == nullptr);
    CHECK(std::string(voxmesh_sculpt_warnings(nullptr)).empty());
    CHECK(voxmesh_sculpt_update(nullptr, nullptr) == VOXMESH_ERROR);
    voxmesh_sculpt_free(nullptr);
}

// With a device (PoCL in CI) update re-meshes there and gives the CPU's meshes; without one
// (the [fallback] run, the build without OpenCL) it re-meshes on the CPU and says so.
TEST_CASE("C API sculpt: the OpenCL backend, or the CPU with a warning", "[capi][sculpt][fallback]") {
    voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Sphere, 24, voxmesh::ScalarType::F32);
    const voxmesh_volume_view view = c_view(field.volume.view());
    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    options.iso = field.iso;
    options.backend = VOXMESH_BACKEND_OPENCL;
    options.block_size = 8;
    voxmesh_sculpt* made = nullptr;
    REQUIRE(voxmesh_sculpt_new(&view, &options, &made) == VOXMESH_OK);
    SculptPtr c(made, voxmesh_sculpt_free);
    const std::string warnings = voxmesh_sculpt_warnings(c.get());
    if (voxmesh_device_count() == 0) {
        CHECK(voxmesh_sculpt_backend(c.get()) == VOXMESH_BACKEND_CPU);
        CHECK(std::string(voxmesh_sculpt_device_name(c.get())) == "cpu");
        CHECK_THAT(warnings, Catch::Contains("OpenCL") && Catch::Contains("CPU") && Catch::EndsWith("\n"));
    } else {
        voxmesh_device first{};
        REQUIRE(voxmesh_get_device(0, &first) == VOXMESH_OK);
        CHECK(voxmesh_sculpt_backend(c.get()) == VOXMESH_BACKEND_OPENCL);
        CHECK(std::string(voxmesh_sculpt_device_name(c.get())) == first.name);
        CHECK(warnings.empty());
    }
    const double center[3] = {8, 12, 12};
    REQUIRE(voxmesh_sculpt_apply(c.get(), VOXMESH_BRUSH_ADD, center, 4, 2, VOXMESH_UNITS_SAMPLES) == VOXMESH_OK);
    voxmesh_mesh* welded = nullptr;
    REQUIRE(voxmesh_sculpt_mesh(c.get(), &welded) == VOXMESH_OK);
    MeshPtr mesh(welded, voxmesh_mesh_free);
    voxmesh::VolumeView edited = field.volume.view();
    edited.data = voxmesh_sculpt_get_view(c.get()).data;
    voxmesh::Options cpu;
    cpu.iso = field.iso;
    cpu.backend = voxmesh::Backend::Cpu;
    const voxmesh::Mesh want = voxmesh::extract(edited, cpu);
    // Indices always identical; positions bit-identical on the CPU and on fp64 devices (PoCL).
    REQUIRE(voxmesh_mesh_triangle_count(mesh.get()) == want.triangle_count());
    CHECK(std::memcmp(voxmesh_mesh_indices(mesh.get()), want.indices.data(), want.indices.size() * 4) == 0);
}
#endif  // VOXMESH_TEST_C_API
