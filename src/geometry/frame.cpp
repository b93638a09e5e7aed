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
    // Eq. (2) written as d = (f - (f.n) n) / |f - (f.n) n|, e = n x d: the same frame as
    // e = n x f / |n x f|, d = e x n, but n x f loses its relative accuracy when f is within a
    // hair of the axis. Projecting out n twice keeps d perpendicular to n to rounding however
    // small the perpendicular part is (one projection leaves about eps |f| along n).
    Vec3 fPerp = feed - glm::dot(feed, fr.n) * fr.n;
    fPerp -= glm::dot(fPerp, fr.n) * fr.n;
    const double s = glm::length(fPerp);
    if (flen > tol::kZeroMove && s > tol::kParallel * flen) {
        fr.d = fPerp / s;
        fr.e = glm::cross(fr.n, fr.d);
        fr.plunge = false;
    } else {
        perpendicularPair(fr.n, fr.d, fr.e);
        fr.plunge = true;
    }
    return fr;
}

}  // namespace dexelmill
