// "NXxNYxNZ", as every message naming a volume's or grid's dimensions writes them.
#pragma once

#include <array>
#include <cstddef>
#include <string>

namespace voxmesh::detail {

inline std::string dims_text(const std::array<std::size_t, 3>& d) {
    return std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]);
}

}  // namespace voxmesh::detail
