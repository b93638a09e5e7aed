#include "refine/detail/pieces.h"

#include <algorithm>

namespace dexelmill::detail {

namespace {

/// A sub-triangle must face its parent's way at a cosine above this: refinement follows the
/// surface, it never turns a piece of it over (a smooth part tilts the halves by the curvature
/// over half an edge, a few degrees; a crease the parent cut across by up to 45 degrees).
constexpr double kMinCosine = 0.1;
/// A sub-triangle whose doubled area is below this times its longest squared edge is a sliver:
/// the split that makes it is refused (checkMesh's degenerate limit is far below).
constexpr double kSliver = 1e-4;

/// A sub-triangle with an angle wider than acos(this) (170 degrees) is a cap: its corner there lies
/// nearly on its opposite side, and its normal is noise, which a measure along it, or a picture,
/// shows as a spike. (Bear, `--refine 1`: a split point 0.005 mm off the side through its
/// neighbours made a piece facing down at (45.83, 58.40, -3.98), measured 0.29 h off.)
constexpr double kCapCosine = -0.98481;

/// Whether the sub-triangle (a, b, c) of a parent with unit normal `n` is acceptable.
bool goodPiece(const std::array<Vec3, 6>& p, const Local& t, const Vec3& n) {
    const Vec3 s = glm::cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]);
    const double len = glm::length(s);
    const double longest = std::max({glm::dot(p[t[1]] - p[t[0]], p[t[1]] - p[t[0]]),
                                      glm::dot(p[t[2]] - p[t[1]], p[t[2]] - p[t[1]]),
                                      glm::dot(p[t[0]] - p[t[2]], p[t[0]] - p[t[2]])});
    if (!(len > kSliver * longest && glm::dot(s, n) > kMinCosine * len)) return false;
    for (int k = 0; k < 3; ++k) {
        const Vec3 u = p[t[(k + 1) % 3]] - p[t[k]], v = p[t[(k + 2) % 3]] - p[t[k]];
        if (glm::dot(u, v) < kCapCosine * glm::length(u) * glm::length(v)) return false;
    }
    return true;
}

}  // namespace

int splitPieces(const std::array<Vec3, 6>& p, unsigned mask, const Vec3& n, std::array<Local, 4>& out) {
    const int bits = int(mask & 1u) + int((mask >> 1) & 1u) + int((mask >> 2) & 1u);
    // Rotation r: local corner i is the triangle's corner (i + r) % 3.
    int r = 0;
    if (bits == 1) r = mask == 1u ? 0 : (mask == 2u ? 1 : 2);
    if (bits == 2) r = ((mask == 3u ? 2 : (mask == 6u ? 0 : 1)) + 1) % 3;  // the unsplit edge to local 2
    const auto c = [&](int i) { return (i + r) % 3; };
    const auto m = [&](int i) { return 3 + (i + r) % 3; };
    int count = 0;
    if (bits == 1) {
        out[0] = {c(0), m(0), c(2)};
        out[1] = {m(0), c(1), c(2)};
        count = 2;
    } else if (bits == 2) {
        out[0] = {m(0), c(1), m(1)};
        const std::array<Local, 2> viaC0{Local{c(0), m(0), m(1)}, Local{c(0), m(1), c(2)}};
        const std::array<Local, 2> viaM0{Local{c(0), m(0), c(2)}, Local{m(0), m(1), c(2)}};
        const bool c0First = glm::length(p[c(0)] - p[m(1)]) <= glm::length(p[m(0)] - p[c(2)]);
        const std::array<Local, 2>& first = c0First ? viaC0 : viaM0;
        const std::array<Local, 2>& second = c0First ? viaM0 : viaC0;
        if (goodPiece(p, first[0], n) && goodPiece(p, first[1], n)) {
            out[1] = first[0], out[2] = first[1];
        } else {
            out[1] = second[0], out[2] = second[1];
        }
        count = 3;
    } else if (bits == 3) {
        out[0] = {c(0), m(0), m(2)};
        out[1] = {m(0), c(1), m(1)};
        out[2] = {m(2), m(1), c(2)};
        out[3] = {m(0), m(1), m(2)};
        count = 4;
    }
    for (int i = 0; i < count; ++i)
        if (!goodPiece(p, out[i], n)) return 0;
    return count;
}

}  // namespace dexelmill::detail
