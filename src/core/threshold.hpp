// "Inside" is value >= iso, decided in the sample's own type so that no sample is
// converted: integers compare against ceil(iso), floats against the smallest float >= iso.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <cmath>
#include <limits>
#include <type_traits>

namespace voxmesh::detail {

enum class Uniform { Mixed, AllInside, AllOutside };

template <class T>
struct Threshold {
    T value{};                        // inside <=> sample >= value
    Uniform uniform = Uniform::Mixed; // set when no sample of type T can cross iso
};

template <class T>
Threshold<T> make_threshold(double iso) {
    if (std::isnan(iso)) throw Error("iso value is NaN");
    Threshold<T> t;
    if constexpr (std::is_integral_v<T>) {
        const double up = std::ceil(iso);
        if (up > static_cast<double>(std::numeric_limits<T>::max())) {
            t.uniform = Uniform::AllOutside;
        } else if (up <= static_cast<double>(std::numeric_limits<T>::lowest())) {
            t.uniform = Uniform::AllInside;
        } else {
            t.value = static_cast<T>(up);
        }
    } else if constexpr (std::is_same_v<T, float>) {
        if (iso > static_cast<double>(std::numeric_limits<float>::max())) {
            t.uniform = Uniform::AllOutside;
        } else if (iso <= static_cast<double>(std::numeric_limits<float>::lowest())) {
            t.uniform = Uniform::AllInside;
        } else {
            float f = static_cast<float>(iso);
            if (static_cast<double>(f) < iso) f = std::nextafter(f, std::numeric_limits<float>::infinity());
            t.value = f;
        }
    } else {
        t.value = iso;
    }
    return t;
}

}  // namespace voxmesh::detail
