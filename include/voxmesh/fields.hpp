// Built-in test and benchmark volumes, generated in memory.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstdint>
#include <string>

namespace voxmesh {

enum class Field {
    Sphere,  // sparse surface: one sphere
    Gyroid,  // dense surface: many triangles
    Blobs,   // smooth random metaballs (seeded)
    Ct,      // CT-like phantom: skull-like shells and noise
};

struct FieldVolume {
    Volume volume;
    double iso = 0;  // a sensible iso value for this field and type
};

// The smallest cube make_field makes: from 8 samples along each axis on, every field in every
// type and for every seed has a surface at its iso.
inline constexpr std::size_t kMinFieldSize = 8;

// A cube of n^3 samples of `field` stored as `type` (f32, u8, u16, i16, ...); n from
// kMinFieldSize to 2^20, else Error.
FieldVolume make_field(Field field, std::size_t n, ScalarType type = ScalarType::F32, std::uint32_t seed = 1);
Field parse_field(const std::string& name);  // "sphere", "gyroid", "blobs", "ct"; throws Error
const char* field_name(Field field);

}  // namespace voxmesh
