// Calls a generic lambda with a value of the C++ type behind a ScalarType, so engines are
// templated on the sample type and read volumes in place.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cstdint>

namespace voxmesh::detail {

template <class F>
decltype(auto) dispatch_scalar(ScalarType type, F&& f) {
    switch (type) {
        case ScalarType::U8: return f(std::uint8_t{});
        case ScalarType::I8: return f(std::int8_t{});
        case ScalarType::U16: return f(std::uint16_t{});
        case ScalarType::I16: return f(std::int16_t{});
        case ScalarType::U32: return f(std::uint32_t{});
        case ScalarType::I32: return f(std::int32_t{});
        case ScalarType::F32: return f(float{});
        case ScalarType::F64: return f(double{});
    }
    throw Error("unknown scalar type");
}

}  // namespace voxmesh::detail
