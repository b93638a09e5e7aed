/// @file uv_sphere.h
/// @brief Test support: a closed, outward-facing UV sphere about the origin.
#pragma once

#include <cmath>

#include "dexelmill/surface/mesh.h"

namespace dexelmill::testing {

/// A pole vertex at each end, `rings` - 1 rings of `sectors` vertices between, all on the sphere
/// of radius r.
inline Mesh uvSphere(int rings, int sectors, double r) {
    Mesh m;
    m.vertices.push_back(Vec3(0, 0, r));
    for (int i = 1; i < rings; ++i) {
        const double th = M_PI * i / rings;
        for (int j = 0; j < sectors; ++j) {
            const double ph = 2 * M_PI * j / sectors;
            m.vertices.push_back(r * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
        }
    }
    m.vertices.push_back(Vec3(0, 0, -r));
    const auto at = [&](int i, int j) { return std::uint32_t(1 + (i - 1) * sectors + (j % sectors)); };
    const std::uint32_t south = std::uint32_t(m.vertices.size() - 1);
    for (int j = 0; j < sectors; ++j) {
        m.triangles.push_back({0, at(1, j), at(1, j + 1)});
        for (int i = 1; i + 1 < rings; ++i) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
        m.triangles.push_back({at(rings - 1, j), south, at(rings - 1, j + 1)});
    }
    return m;
}

}  // namespace dexelmill::testing
