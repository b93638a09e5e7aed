/// @file rotation.h
/// @brief Turning a vector about a unit axis (Rodrigues' formula).
#pragma once

#include <cmath>

#include "dexelmill/geometry/types.h"

namespace dexelmill {

/// @brief v turned about the unit vector `axis` by the angle whose cosine and sine are c and s.
inline Vec3 rotateAbout(const Vec3& v, const Vec3& axis, double c, double s) {
    return v * c + glm::cross(axis, v) * s + axis * (glm::dot(axis, v) * (1.0 - c));
}

/// @brief v turned by `angle` (radians, right-handed) about the unit vector `axis`.
inline Vec3 rotateAbout(const Vec3& v, const Vec3& axis, double angle) {
    return rotateAbout(v, axis, std::cos(angle), std::sin(angle));
}

}  // namespace dexelmill
