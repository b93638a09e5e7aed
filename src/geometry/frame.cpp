#include "dexelmill/geometry/frame.h"

#include <cmath>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

void ToolFrame::perpendicularPair(const Vec3& n, Vec3& b1, Vec3& b2) {
    // Cross with the coordinate axis least aligned with n: well conditioned for every n.
    const Vec3 a = std::abs(n.x) <= std::abs(n.y) && std::abs(n.x) <= std::abs(n.z)
                       ? Vec3(1, 0, 0)
                       : (std::abs(n.y) <= std::abs(n.z) ? Vec3(0, 1, 0) : Vec3(0, 0, 1));
    b2 = glm::normalize(glm::cross(n, a));
    b1 = glm::cross(b2, n);
}

ToolFrame ToolFrame::make(const Vec3& axis, const Vec3& feed) {
    const double len = glm::length(axis);
    if (!(len > 0.0) || !std::isfinite(len)) throw Error("tool axis must be a non-zero vector");
    ToolFrame fr;
    fr.n = axis / len;
    const double flen = glm::length(feed);
    const Vec3 nxf = glm::cross(fr.n, feed);
    const double s = glm::length(nxf);
    if (flen > tol::kZeroMove && s > tol::kParallel * flen) {
        // Eq. (2): e = n x f / |n x f|, d = e x n.
        fr.e = nxf / s;
        fr.d = glm::cross(fr.e, fr.n);
        fr.plunge = false;
    } else {
        perpendicularPair(fr.n, fr.d, fr.e);
        fr.plunge = true;
    }
    return fr;
}

}  // namespace dexelmill
