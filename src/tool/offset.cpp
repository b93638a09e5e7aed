#include "dexelmill/tool/offset.h"

#include <cmath>

namespace dexelmill {

namespace {

constexpr double kHalfPi = 1.57079632679489661923;

/// The outward normal's angle psi = atan2(nz, nr) of a piece at height z (meridianNormal).
double normalAngle(const ProfilePiece& piece, double z) {
    double nr = 0.0, nz = 0.0;
    meridianNormal(piece, pieceRadius(piece, z), z, nr, nz);
    return std::atan2(nz, nr);
}

/// Appends the arc of radius r round the corner (rc, zc) from normal angle psiA to psiB; nothing
/// where the normal does not turn.
void addCorner(std::vector<ProfilePiece>& out, double rc, double zc, double r, double psiA, double psiB) {
    const double z0 = zc + r * std::sin(psiA), z1 = zc + r * std::sin(psiB);
    if (!(z1 > z0)) return;
    out.push_back(ArcPiece{z0, z1, rc, zc, r});
}

}  // namespace

std::vector<ProfilePiece> offsetPart(const Tool& tool, const ConvexPart& part, double r) {
    const auto& pieces = tool.pieces();
    std::vector<ProfilePiece> out;
    double psi = -kHalfPi;  // the bottom face's normal
    for (std::size_t i = part.first; i < part.last; ++i) {
        const ProfilePiece& p = pieces[i];
        const double z0 = pieceZ0(p), z1 = pieceZ1(p);
        addCorner(out, pieceRadius(p, z0), z0, r, psi, normalAngle(p, z0));
        if (const auto* c = std::get_if<ConePiece>(&p)) {
            double nr = 0.0, nz = 0.0;
            meridianNormal(p, c->r0, c->z0, nr, nz);
            out.push_back(ConePiece{c->z0 + r * nz, c->z1 + r * nz, c->r0 + r * nr, c->r1 + r * nr});
        } else {
            const ArcPiece& a = std::get<ArcPiece>(p);
            const double grow = (a.rho + r) / a.rho;
            out.push_back(ArcPiece{a.zc + grow * (a.z0 - a.zc), a.zc + grow * (a.z1 - a.zc), a.rc, a.zc, a.rho + r});
        }
        psi = normalAngle(p, z1);
    }
    const ProfilePiece& top = pieces[part.last - 1];
    addCorner(out, pieceRadius(top, pieceZ1(top)), pieceZ1(top), r, psi, kHalfPi);
    return out;
}

Interval intersectPieces(const std::vector<ProfilePiece>& pieces, const LocalLine& line) {
    Interval hull;
    for (const ProfilePiece& p : pieces) hull = hull.hull(intersectPiece(p, line));
    if (hull.isEmpty()) return hull;
    return {hull.lo + line.vShift, hull.hi + line.vShift};
}

}  // namespace dexelmill
