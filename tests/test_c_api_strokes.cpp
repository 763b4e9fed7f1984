// The C API's voxmesh_sculpt_from_function and stroke scripts against voxmesh::Sculpt: the same
// samples, the same dabs and meshes bit for bit, the frames told to the callback, a callback
// that stops the run, and the parser's refusals with nothing applied.
#ifdef VOXMESH_TEST_C_API
#include <catch2/catch.hpp>
#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxmesh.h>
#include <voxmesh/voxmesh.hpp>

#include "support/c_api.hpp"
#include "support/mesh_checks.hpp"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

using capitest::MeshPtr;
using capitest::require_same;
using capitest::SculptPtr;

double ball(double x, double y, double z) {
    return 9.5 - std::sqrt((x - 12.2) * (x - 12.2) + (y - 11.7) * (y - 11.7) + (z - 12.9) * (z - 12.9));
}

struct Calls {
    std::atomic<long> count{0};
    double scale = 1, offset = 0;
};

double c_ball(double x, double y, double z, void* user) {
    Calls* calls = static_cast<Calls*>(user);
    ++calls->count;
    return calls->offset + calls->scale * ball(x, y, z);
}

const char kScript[] =
    "# two strokes and a smooth\n"
    "add 12 12 21 4 2\n"
    "\n"
    "subtract 12 3 12 3.5 1.5   # a dent\n"
    "units world\n"
    "smooth 6 6 6 2 0.5\n"
    "set 1 1 1 0.5 -4\n";

struct Told {
    std::vector<voxmesh_stroke_frame> frames;
    std::size_t stop_after = static_cast<std::size_t>(-1);
};

int tell(const voxmesh_stroke_frame* frame, void* user) {
    Told* told = static_cast<Told*>(user);
    told->frames.push_back(*frame);
    return frame->frame == told->stop_after ? 1 : 0;
}

const std::size_t kDims[3] = {25, 24, 26};

SculptPtr c_sculpt(const voxmesh_sculpt_options& options) {
    Calls calls;
    voxmesh_sculpt* made = nullptr;
    REQUIRE(voxmesh_sculpt_from_function(kDims, VOXMESH_F32, c_ball, &calls, &options, &made) == VOXMESH_OK);
    return SculptPtr(made, voxmesh_sculpt_free);
}

voxmesh::Sculpt cpp_sculpt(const voxmesh::SculptOptions& options) {
    return voxmesh::Sculpt::from_function({kDims[0], kDims[1], kDims[2]}, voxmesh::ScalarType::F32, ball, options);
}

void require_same_mesh(voxmesh_sculpt* c, voxmesh::Sculpt& cpp) {
    voxmesh_mesh* welded = nullptr;
    REQUIRE(voxmesh_sculpt_mesh(c, &welded) == VOXMESH_OK);
    MeshPtr mesh(welded, voxmesh_mesh_free);
    REQUIRE(voxmesh_mesh_triangle_count(mesh.get()) > 0);
    require_same(mesh.get(), cpp.mesh());
}

std::vector<voxmesh::ScriptDab> script_dabs(const std::string& text) {
    std::istringstream in(text);
    return voxmesh::parse_stroke_script(in);
}

}  // namespace

TEST_CASE("C API sculpt_from_function: the C++ from_function's samples, on every type it takes", "[capi][sculpt]") {
    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    options.threads = 3;
    options.block_size = 8;
    options.iso = 100.5;
    voxmesh::SculptOptions cpp_options;
    cpp_options.threads = 3;
    cpp_options.block_size = 8;
    cpp_options.iso = 100.5;
    const std::size_t samples = kDims[0] * kDims[1] * kDims[2];
    for (const int type : {VOXMESH_U8, VOXMESH_U16, VOXMESH_F32}) {
        INFO("type " << type);
        Calls calls;
        calls.scale = 20;  // integer types: a surface between the rounded samples 100 and 101
        calls.offset = 100;
        voxmesh_sculpt* made = nullptr;
        REQUIRE(voxmesh_sculpt_from_function(kDims, type, c_ball, &calls, &options, &made) == VOXMESH_OK);
        SculptPtr c(made, voxmesh_sculpt_free);
        CHECK(calls.count == static_cast<long>(samples));  // the user pointer reached f
        const voxmesh::ScalarType cpp_type = type == VOXMESH_U8    ? voxmesh::ScalarType::U8
                                             : type == VOXMESH_U16 ? voxmesh::ScalarType::U16
                                                                   : voxmesh::ScalarType::F32;
        voxmesh::Sculpt cpp = voxmesh::Sculpt::from_function(
            {kDims[0], kDims[1], kDims[2]}, cpp_type, [](double x, double y, double z) { return 100 + 20 * ball(x, y, z); },
            cpp_options);
        const voxmesh_volume_view view = voxmesh_sculpt_get_view(c.get());
        REQUIRE(view.type == type);
        CHECK(std::memcmp(view.data, cpp.view().data, voxmesh::scalar_size(cpp_type) * samples) == 0);
        require_same_mesh(c.get(), cpp);
    }

    voxmesh_sculpt* made = reinterpret_cast<voxmesh_sculpt*>(&options);  // must come back NULL
    Calls calls;
    CHECK(voxmesh_sculpt_from_function(kDims, VOXMESH_I16, c_ball, &calls, nullptr, &made) == VOXMESH_ERROR);
    CHECK(made == nullptr);
    CHECK_THROWS_WITH(voxmesh::Sculpt::from_function({kDims[0], kDims[1], kDims[2]}, voxmesh::ScalarType::I16, ball),
                      std::string(voxmesh_last_error()));  // the C++ message itself
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("not i16"));
    CHECK(voxmesh_sculpt_from_function(kDims, 42, c_ball, &calls, nullptr, &made) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("voxmesh_sculpt_from_function: unknown scalar type 42"));
    CHECK(voxmesh_sculpt_from_function(kDims, VOXMESH_F32, nullptr, &calls, nullptr, &made) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_from_function: the function is NULL");
    CHECK(voxmesh_sculpt_from_function(nullptr, VOXMESH_F32, c_ball, &calls, nullptr, &made) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_from_function: dims is NULL");
    const voxmesh_sample_function nan_at_one = [](double x, double y, double z, void*) {
        return x == 3 && y == 4 && z == 5 ? NAN : 1.0;
    };
    CHECK(voxmesh_sculpt_from_function(kDims, VOXMESH_F32, nan_at_one, nullptr, nullptr, &made) == VOXMESH_ERROR);
    CHECK(made == nullptr);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("returned NaN"));
    CHECK(voxmesh_sculpt_from_function(kDims, VOXMESH_F32, c_ball, &calls, nullptr, nullptr) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_from_function: the sculpt pointer is NULL");
}

TEST_CASE("C API stroke scripts: the C++ run_strokes' meshes, each frame told, from memory and from a file",
          "[capi][sculpt]") {
    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    options.threads = 2;
    options.block_size = 8;
    voxmesh::SculptOptions cpp_options;
    cpp_options.threads = 2;
    cpp_options.block_size = 8;

    voxmesh::Sculpt cpp = cpp_sculpt(cpp_options);
    const std::vector<voxmesh::ScriptDab> dabs = script_dabs(kScript);
    REQUIRE(dabs.size() == 4);
    voxmesh::run_strokes(cpp, dabs, {});

    SculptPtr c = c_sculpt(options);
    Told told;
    REQUIRE(voxmesh_sculpt_run_strokes(c.get(), kScript, std::strlen(kScript), "k.txt", tell, &told) == VOXMESH_OK);
    CHECK_FALSE(voxmesh_sculpt_dirty(c.get()));  // each dab was followed by an update
    require_same_mesh(c.get(), cpp);
    REQUIRE(told.frames.size() == dabs.size());
    const int brushes[] = {VOXMESH_BRUSH_ADD, VOXMESH_BRUSH_SUBTRACT, VOXMESH_BRUSH_SMOOTH, VOXMESH_BRUSH_SET};
    for (std::size_t i = 0; i < dabs.size(); ++i) {
        const voxmesh_stroke_frame& f = told.frames[i];
        INFO("frame " << i);
        CHECK(f.frame == i);
        CHECK(f.line == dabs[i].line);
        CHECK(f.brush == brushes[i]);
        CHECK(f.units == (i < 2 ? VOXMESH_UNITS_SAMPLES : VOXMESH_UNITS_WORLD));
        for (int a = 0; a < 3; ++a) CHECK(f.center[a] == dabs[i].dab.center[a]);
        CHECK(f.radius == dabs[i].dab.radius);
        CHECK(f.strength == dabs[i].dab.strength);
        CHECK(f.edit_seconds >= 0);
        CHECK(f.update_seconds >= 0);
        CHECK(f.blocks_remeshed >= f.blocks_changed);
    }
    CHECK(told.frames[0].line == 2);
    CHECK(told.frames[1].blocks_changed > 0);  // the dent changes the surface

    // The same script from a file, and with no callback.
    const vmtest::TempDir dir;
    const std::string path = dir.file("c_api_strokes.txt");
    std::ofstream(path) << kScript;
    c = c_sculpt(options);
    REQUIRE(voxmesh_sculpt_run_stroke_script(c.get(), path.c_str(), nullptr, nullptr) == VOXMESH_OK);
    require_same_mesh(c.get(), cpp);
    std::remove(path.c_str());
    CHECK(voxmesh_sculpt_run_stroke_script(c.get(), path.c_str(), nullptr, nullptr) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::Contains("c_api_strokes.txt"));

    // An empty script applies nothing.
    c = c_sculpt(options);
    REQUIRE(voxmesh_sculpt_run_strokes(c.get(), nullptr, 0, nullptr, tell, &told) == VOXMESH_OK);
    voxmesh::Sculpt untouched = cpp_sculpt(cpp_options);
    require_same_mesh(c.get(), untouched);
}

TEST_CASE("C API stroke scripts: a callback that stops, a malformed line, NULL arguments", "[capi][sculpt]") {
    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    options.block_size = 8;
    voxmesh::SculptOptions cpp_options;
    cpp_options.block_size = 8;

    // Stopped after frame 1: the first two dabs applied and meshed, an Error naming the frame.
    SculptPtr c = c_sculpt(options);
    Told told;
    told.stop_after = 1;
    REQUIRE(voxmesh_sculpt_run_strokes(c.get(), kScript, std::strlen(kScript), nullptr, tell, &told) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) ==
          "voxmesh_sculpt_run_strokes: on_frame stopped the strokes after frame 1 (line 4)");
    CHECK(told.frames.size() == 2);
    voxmesh::Sculpt cpp = cpp_sculpt(cpp_options);
    std::vector<voxmesh::ScriptDab> dabs = script_dabs(kScript);
    dabs.resize(2);
    voxmesh::run_strokes(cpp, dabs, {});
    require_same_mesh(c.get(), cpp);

    // A malformed line anywhere: nothing applied, the name and line in the message.
    c = c_sculpt(options);
    const std::string bad = std::string(kScript) + "add 1 2 3 four 1\n";
    REQUIRE(voxmesh_sculpt_run_strokes(c.get(), bad.data(), bad.size(), "bad.txt", tell, &told) == VOXMESH_ERROR);
    CHECK_THAT(std::string(voxmesh_last_error()), Catch::StartsWith("bad.txt:8:"));
    voxmesh::Sculpt untouched = cpp_sculpt(cpp_options);
    require_same_mesh(c.get(), untouched);
    // A NUL inside `size` bytes: named by its value, the whole message kept.
    const std::string nul = std::string(kScript) + std::string("car\0ve 1 2 3 4 1\n", 17);
    REQUIRE(voxmesh_sculpt_run_strokes(c.get(), nul.data(), nul.size(), "nul.txt", nullptr, nullptr) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "nul.txt:8: control byte 0x00 in the script (not a text file?)");
    require_same_mesh(c.get(), untouched);
    // Only `size` bytes are read: cut after its first dab's line, the script is that dab alone.
    const std::size_t first_dab = std::strchr(std::strchr(kScript, '\n') + 1, '\n') + 1 - kScript;
    REQUIRE(voxmesh_sculpt_run_strokes(c.get(), kScript, first_dab, nullptr, nullptr, nullptr) == VOXMESH_OK);
    voxmesh::Sculpt one = cpp_sculpt(cpp_options);
    dabs.resize(1);
    voxmesh::run_strokes(one, dabs, {});
    require_same_mesh(c.get(), one);

    CHECK(voxmesh_sculpt_run_strokes(nullptr, kScript, 3, nullptr, nullptr, nullptr) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_run_strokes: the sculpt is NULL");
    CHECK(voxmesh_sculpt_run_strokes(c.get(), nullptr, 3, nullptr, nullptr, nullptr) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_run_strokes: the text is NULL");
    CHECK(voxmesh_sculpt_run_stroke_script(c.get(), nullptr, nullptr, nullptr) == VOXMESH_ERROR);
    CHECK(std::string(voxmesh_last_error()) == "voxmesh_sculpt_run_stroke_script: the path is NULL");
}
#endif
