/// @file affine.h
/// @brief An affine map of space, p -> m p + t: places a part given in another frame.
#pragma once

#include <array>

#include "dexelmill/geometry/types.h"

namespace dexelmill {

struct Affine {
    std::array<std::array<double, 3>, 3> m{{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};  ///< rows
    Vec3 t{0.0};

    Vec3 apply(const Vec3& p) const {
        Vec3 q = t;
        for (int r = 0; r < 3; ++r) q[r] += m[r][0] * p.x + m[r][1] * p.y + m[r][2] * p.z;
        return q;
    }
    double determinant() const {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    }
};

}  // namespace dexelmill
