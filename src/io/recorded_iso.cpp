// The iso a volume file records for meshing (see recorded_iso in include/voxmesh/io.hpp).
#include <voxmesh/io.hpp>

#include <charconv>
#include <cmath>

namespace voxmesh {

std::optional<double> recorded_iso(const VolumeInfo& info, const std::string& name) {
    const auto found = info.key_values.find(kRecordedIsoKey);
    if (found == info.key_values.end()) return std::nullopt;
    const std::string& text = found->second;
    double value = 0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(value))
        throw Error("'" + name + "': its " + kRecordedIsoKey + " ('" + text + "') is not a finite number");
    return value;
}

}  // namespace voxmesh
