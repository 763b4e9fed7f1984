// The library's own environment settings (VOXMESH_ISA, VOXMESH_HUGE_PAGES), read the same way.
#pragma once

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <optional>
#include <string>

namespace voxmesh::detail {

// Variable `name` in lower case; nullopt where it is unset or empty (the default applies).
inline std::optional<std::string> env_word(const char* name) {
    const char* raw = std::getenv(name);
    if (!raw || !*raw) return std::nullopt;
    std::string value(raw);
    std::transform(value.begin(), value.end(), value.begin(), [](unsigned char c) { return std::tolower(c); });
    return value;
}

}  // namespace voxmesh::detail
