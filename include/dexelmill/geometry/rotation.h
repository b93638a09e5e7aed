/// @file rotation.h
/// @brief Turning a vector about a unit axis (Rodrigues' formula).
#pragma once

#include <cmath>

#include "dexelmill/geometry/types.h"

namespace dexelmill {

/// @brief v turned by `angle` (radians, right-handed) about the unit vector `axis`.
inline Vec3 rotateAbout(const Vec3& v, const Vec3& axis, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    return v * c + glm::cross(axis, v) * s + axis * (glm::dot(axis, v) * (1.0 - c));
}

}  // namespace dexelmill
