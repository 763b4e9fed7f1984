// libFuzzer target: parse_stroke_script, then every dab it gives applied to a small sculpt of
// each type in both units, re-meshed block by block; the welded mesh must be exactly what
// extract() makes of the edited volume. Fuzzed numbers reach the brushes' clipping and
// rounding (huge, tiny and negative coordinates and radii, strengths beyond the type).
#include "fuzz_common.hpp"

#include <voxmesh/sculpt.hpp>

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

namespace {

void check_sculpt(voxmesh::ScalarType type, const std::vector<voxmesh::ScriptDab>& dabs) {
    voxmesh::SculptOptions options;
    options.iso = type == voxmesh::ScalarType::F32 ? 0.0 : 100.5;
    options.threads = 1;
    options.block_size = 4;  // many blocks, many block borders for a few samples
    const double offset = type == voxmesh::ScalarType::F32 ? 0.0 : 100.5;
    voxmesh::Sculpt sculpt = voxmesh::Sculpt::from_function(
        {11, 9, 7}, type, [&](double x, double y, double z) {
            return offset + 10 * (3.5 - std::sqrt((x - 5) * (x - 5) + (y - 4) * (y - 4) + (z - 3) * (z - 3)));
        },
        options);
    std::size_t applied = 0;
    for (const voxmesh::ScriptDab& d : dabs) {
        if (++applied > 12) break;  // enough to mix edits; keeps an input's run short
        try {
            sculpt.apply(d.dab, d.units);
        } catch (const voxmesh::Error&) {
            continue;  // a radius <= 0, a value the type cannot hold, ...: refused, nothing changed
        }
        if (applied % 3 == 0) sculpt.update();
    }
    // A sculpt's samples stay finite: extract must take them.
    const voxmesh::Mesh expected = fuzz::extract_or_abort(sculpt.view(), options.iso);
    const voxmesh::Mesh mesh = sculpt.mesh();
    if (mesh.indices != expected.indices || mesh.positions != expected.positions || mesh.normals != expected.normals)
        std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    std::vector<voxmesh::ScriptDab> dabs;
    try {
        dabs = voxmesh::parse_stroke_script(in, "fuzz");
    } catch (const voxmesh::Error&) {
        return 0;
    }
    for (const auto type : {voxmesh::ScalarType::U8, voxmesh::ScalarType::U16, voxmesh::ScalarType::F32})
        check_sculpt(type, dabs);
    return 0;
}
