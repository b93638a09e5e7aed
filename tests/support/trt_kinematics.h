/// @file trt_kinematics.h
/// @brief Test support: LinuxCNC's trt forward kinematics for its xyzac-trt and xyzbc-trt sim
/// configs (rot points 0), written out here as formulas: joints and rotary angles (degrees) to the
/// part frame. The tests' reference for the machine module and the motion law, sharing no code
/// with either.
#pragma once

#include <cmath>

#include "dexelmill/geometry/types.h"

namespace dexelmill::testing {

constexpr double kTrtDegree = 3.14159265358979323846 / 180.0;

/// xyzac-trt: y-offset 20, z-offset 10.
inline Vec3 xyzacForward(const Vec3& j, double aDeg, double cDeg) {
    const double a = aDeg * kTrtDegree, c = cDeg * kTrtDegree, dy = 20, dz = 10;
    return {std::cos(c) * j.x + std::sin(c) * std::cos(a) * (j.y - dy) + std::sin(c) * std::sin(a) * (j.z - dz) +
                std::sin(c) * dy,
            -std::sin(c) * j.x + std::cos(c) * std::cos(a) * (j.y - dy) + std::cos(c) * std::sin(a) * (j.z - dz) +
                std::cos(c) * dy,
            -std::sin(a) * (j.y - dy) + std::cos(a) * (j.z - dz) + dz};
}

/// xyzac-trt's tool axis in the part frame, the image of machine +z: the issue's
/// (sin C sin A, cos C sin A, cos A).
inline Vec3 xyzacAxis(double aDeg, double cDeg) {
    const double a = aDeg * kTrtDegree, c = cDeg * kTrtDegree;
    return {std::sin(c) * std::sin(a), std::cos(c) * std::sin(a), std::cos(a)};
}

/// xyzbc-trt: x-offset -20, z-offset -15.
inline Vec3 xyzbcForward(const Vec3& j, double bDeg, double cDeg) {
    const double b = bDeg * kTrtDegree, c = cDeg * kTrtDegree, dx = -20, dz = -15;
    return {std::cos(c) * std::cos(b) * (j.x - dx) + std::sin(c) * j.y - std::cos(c) * std::sin(b) * (j.z - dz) +
                std::cos(c) * dx,
            -std::sin(c) * std::cos(b) * (j.x - dx) + std::cos(c) * j.y + std::sin(c) * std::sin(b) * (j.z - dz) -
                std::sin(c) * dx,
            std::sin(b) * (j.x - dx) + std::cos(b) * (j.z - dz) + dz};
}

}  // namespace dexelmill::testing
