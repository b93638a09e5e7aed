#include "dexelmill/tool/offset.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace dexelmill {

namespace {

constexpr double kHalfPi = 1.57079632679489661923;

/// A step of a tangent chain this small against its arc's radius is level. At a rim where the arc
/// meets a bottom or top face the first or last step is level up to the rounding of the arc's end
/// angle (atan2 of a normal next to +-pi/2): a cone of that height and a fraction of the radius
/// across is too steep to solve reliably. Merging a step this low enlarges the solid by at most
/// its height.
constexpr double kLevelStep = 1e-6;

/// The outward normal's angle psi = atan2(nz, nr) of a piece at height z (meridianNormal).
double normalAngle(const ProfilePiece& piece, double z) {
    double nr = 0.0, nz = 0.0;
    meridianNormal(piece, pieceRadius(piece, z), z, nr, nz);
    return std::atan2(nz, nr);
}

/// How many tangents, at even steps d of the normal angle, a chain round a torus arc of radius
/// rho turning its normal by `turn` needs to stay within `slack` of it: the tangents meet
/// rho / cos(d / 2) from the arc's centre, rho (1 / cos(d / 2) - 1) outside it. At least 1; 0
/// where more than `most` would be needed.
int tangentSteps(double turn, double rho, double slack, int most) {
    const double steps = std::ceil(turn / (2.0 * std::acos(1.0 / (1.0 + slack / rho))));
    return steps <= most ? std::max(1, int(steps)) : 0;
}

/// An arc piece grown by r: the same centre, radius rho + r, its ends moved out along their normals.
ArcPiece grownArc(const ArcPiece& a, double r) {
    const double grow = (a.rho + r) / a.rho;
    return ArcPiece{a.zc + grow * (a.z0 - a.zc), a.zc + grow * (a.z1 - a.zc), a.rc, a.zc, a.rho + r};
}

/// Appends the arc of radius r round the corner (rc, zc) from normal angle psiA to psiB; nothing
/// where the normal does not turn. `angles` gets the arc's end normal angles.
void addCorner(std::vector<ProfilePiece>& out, std::vector<std::array<double, 2>>& angles, double rc, double zc,
               double r, double psiA, double psiB) {
    const double z0 = zc + r * std::sin(psiA), z1 = zc + r * std::sin(psiB);
    if (!(z1 > z0)) return;
    out.push_back(ArcPiece{z0, z1, rc, zc, r});
    angles.push_back({psiA, psiB});
}

/// offsetPart's pieces, with each piece's normal angles at its ends (psi, as normalAngle): taken
/// from the part's own pieces, not read back from the grown arcs' heights, whose difference from
/// the centre's height loses the digits a small growth needs (asin near +-1 magnifies them: for
/// a growth of 1e-4 mm at heights of 13 mm, 1e-9 mm on a chain's vertices).
std::vector<ProfilePiece> offsetPieces(const Tool& tool, const ConvexPart& part, double r,
                                       std::vector<std::array<double, 2>>& angles) {
    const auto& pieces = tool.pieces();
    std::vector<ProfilePiece> out;
    double psi = -kHalfPi;  // the bottom face's normal
    for (std::size_t i = part.first; i < part.last; ++i) {
        const ProfilePiece& p = pieces[i];
        const double z0 = pieceZ0(p), z1 = pieceZ1(p);
        const double psi0 = normalAngle(p, z0), psi1 = normalAngle(p, z1);
        addCorner(out, angles, pieceRadius(p, z0), z0, r, psi, psi0);
        if (const auto* c = std::get_if<ConePiece>(&p)) {
            double nr = 0.0, nz = 0.0;
            meridianNormal(p, c->r0, c->z0, nr, nz);
            out.push_back(ConePiece{c->z0 + r * nz, c->z1 + r * nz, c->r0 + r * nr, c->r1 + r * nr});
        } else {
            const ArcPiece& a = std::get<ArcPiece>(p);
            out.push_back(grownArc(a, r));
        }
        angles.push_back({psi0, psi1});
        psi = psi1;
    }
    const ProfilePiece& top = pieces[part.last - 1];
    addCorner(out, angles, pieceRadius(top, pieceZ1(top)), pieceZ1(top), r, psi, kHalfPi);
    return out;
}

}  // namespace

std::vector<ProfilePiece> offsetPart(const Tool& tool, const ConvexPart& part, double r) {
    std::vector<std::array<double, 2>> angles;
    return offsetPieces(tool, part, r, angles);
}

std::vector<ProfilePiece> mitredOffsetPart(const Tool& tool, const ConvexPart& part, double r) {
    const auto& pieces = tool.pieces();
    return mitredOffsetChain(std::vector<ProfilePiece>(pieces.begin() + std::ptrdiff_t(part.first),
                                                       pieces.begin() + std::ptrdiff_t(part.last)),
                             r);
}

std::vector<ProfilePiece> mitredOffsetChain(const std::vector<ProfilePiece>& pieces, double r, double slack,
                                            int maxCones) {
    std::vector<ProfilePiece> out;
    const double level = kLevelStep * r;
    // Where the chain stands; it starts at the bottom face's rim, moved down by r.
    const ProfilePiece& bottom = pieces.front();
    double rAt = pieceRadius(bottom, pieceZ0(bottom)), zAt = pieceZ0(bottom) - r;
    // A straight step to (rv, zv). A step level to within `level` makes no cone, and only enlarges
    // the solid, by at most the step's height: after a cone, that cone runs on along its own line
    // up to zv (so that a widening cone keeps its surface) and its top widens to rv; before any
    // piece, or after an arc, the next cone starts as wide as rv at the height where the chain
    // stands (before any piece, a wider bottom face; after an arc, a step out at its top).
    const auto lineTo = [&](double rv, double zv) {
        if (zv - zAt > level) {
            out.push_back(ConePiece{zAt, zv, rAt, rv});
            rAt = rv, zAt = zv;
        } else if (!out.empty() && std::holds_alternative<ConePiece>(out.back())) {
            ConePiece& last = std::get<ConePiece>(out.back());
            if (zv > last.z1) {
                const double along = last.r0 + (last.r1 - last.r0) * (zv - last.z0) / (last.z1 - last.z0);
                last.r1 = std::max(last.r1, along);
                last.z1 = zv;
            }
            last.r1 = std::max(last.r1, rv);
            rAt = last.r1, zAt = last.z1;
        } else {
            rAt = std::max(rAt, rv);
        }
    };
    // The corner (rc, zc) turning the normal from psiA to psiB: tangents to the circle of radius
    // r about it, n steps of at most a quarter turn d, meeting at distance r / cos(d / 2).
    const auto corner = [&](double rc, double zc, double psiA, double psiB) {
        if (!(psiB > psiA)) return;
        const int n = int(std::ceil((psiB - psiA) / kHalfPi));
        const double d = (psiB - psiA) / n, far = r / std::cos(0.5 * d);
        for (int i = 0; i < n; ++i) {
            const double psi = psiA + (i + 0.5) * d;
            lineTo(rc + far * std::cos(psi), zc + far * std::sin(psi));
        }
        lineTo(rc + r * std::cos(psiB), zc + r * std::sin(psiB));
    };
    double psi = -kHalfPi;  // the bottom face's normal
    for (const ProfilePiece& p : pieces) {
        const double z0 = pieceZ0(p), z1 = pieceZ1(p);
        corner(pieceRadius(p, z0), z0, psi, normalAngle(p, z0));
        if (const auto* c = std::get_if<ConePiece>(&p)) {
            double nr = 0.0, nz = 0.0;
            meridianNormal(p, c->r0, c->z0, nr, nz);
            lineTo(c->r1 + r * nr, c->z1 + r * nz);
        } else {
            const ArcPiece& a = std::get<ArcPiece>(p);
            const ArcPiece grown = grownArc(a, r);
            // A torus as its tangents at n steps d of the normal angle: they meet rho / cos(d / 2)
            // from the arc's centre, at most rho (1 / cos(d / 2) - 1) outside it, and the chain
            // from the arc's start to its end through those points holds the arc's solid (the
            // arc bulges outwards, its normal angle in [-pi / 2, pi / 2] rising with z).
            const double psiA = normalAngle(p, z0), psiB = normalAngle(p, z1);
            const int n = grown.rc != 0.0 && slack > 0.0 && psiB > psiA
                              ? tangentSteps(psiB - psiA, grown.rho, slack, maxCones)
                              : 0;
            if (n == 0) {
                out.push_back(grown);
                rAt = pieceRadius(grown, grown.z1), zAt = grown.z1;
            } else {
                const double d = (psiB - psiA) / n, far = grown.rho / std::cos(0.5 * d);
                for (int i = 0; i < n; ++i) {
                    const double psiI = psiA + (i + 0.5) * d;
                    lineTo(grown.rc + far * std::cos(psiI), grown.zc + far * std::sin(psiI));
                }
                lineTo(grown.rc + grown.rho * std::cos(psiB), grown.zc + grown.rho * std::sin(psiB));
            }
        }
        psi = normalAngle(p, z1);
    }
    const ProfilePiece& top = pieces.back();
    corner(pieceRadius(top, pieceZ1(top)), pieceZ1(top), psi, kHalfPi);
    return out;
}

OuterPart outerOffsetPart(const Tool& tool, const ConvexPart& part, double r, double slack) {
    OuterPart outer;
    std::vector<std::array<double, 2>> angles;
    outer.pieces = offsetPieces(tool, part, r, angles);
    outer.chains.resize(outer.pieces.size());
    outer.growth = r;
    outer.slack = slack;
    for (std::size_t k = 0; k < outer.pieces.size(); ++k) {
        const auto* a = std::get_if<ArcPiece>(&outer.pieces[k]);
        if (!a || a->rc == 0.0 || !(slack > 0.0)) continue;  // cones, and spheres (closed form)
        std::vector<ConePiece>& out = outer.chains[k];
        // Normal angles of the arc's ends; the outer half's heights rise with the angle.
        const double psiA = angles[k][0], psiB = angles[k][1];
        const int n = tangentSteps(psiB - psiA, a->rho, slack, kMaxTangentCones);
        if (n == 0) continue;
        const double d = (psiB - psiA) / n, corner = a->rho / std::cos(0.5 * d);
        // The chain's vertices: the arc's start, the tangents' meeting points, the arc's end.
        // Where a step is level to rounding (at a bottom or top face's rim), no cone is made of
        // it: at the chain's start the next cone starts as wide, later the last cone is raised
        // and widened to the step's end. Either only enlarges the solid.
        const double level = kLevelStep * a->rho;
        double rPrev = a->rc + a->rho * std::cos(psiA), zPrev = a->z0;
        for (int i = 0; i <= n; ++i) {
            double rv, zv;
            if (i < n) {
                const double psi = psiA + (i + 0.5) * d;
                rv = a->rc + corner * std::cos(psi);
                zv = a->zc + corner * std::sin(psi);
            } else {
                rv = a->rc + a->rho * std::cos(psiB);
                zv = a->z1;
            }
            if (zv - zPrev > level) {
                out.push_back(ConePiece{zPrev, zv, rPrev, rv});
                rPrev = rv, zPrev = zv;
            } else if (!out.empty()) {
                ConePiece& last = out.back();
                last.z1 = std::max(last.z1, zv);
                last.r1 = std::max(last.r1, rv);
                rPrev = last.r1, zPrev = last.z1;
            } else {
                rPrev = std::max(rPrev, rv);
            }
        }
    }
    return outer;
}

Interval intersectOuter(const OuterPart& outer, const LocalLine& line) {
    Interval hull;
    for (std::size_t i = 0; i < outer.pieces.size(); ++i) hull = hull.hull(outerPieceInterval(outer, i, line));
    if (hull.isEmpty()) return hull;
    return {hull.lo + line.vShift, hull.hi + line.vShift};
}

Interval intersectPieces(const std::vector<ProfilePiece>& pieces, const LocalLine& line) {
    Interval hull;
    for (const ProfilePiece& p : pieces) {
        // A piece's interval lies within its slab's: a slab the hull already spans adds nothing.
        const auto* c = std::get_if<ConePiece>(&p);
        const Interval slab = c ? detail::slabRange(line, c->z0, c->z1)
                                : detail::slabRange(line, std::get<ArcPiece>(p).z0, std::get<ArcPiece>(p).z1);
        if (slab.isEmpty() || (!hull.isEmpty() && slab.lo >= hull.lo && slab.hi <= hull.hi)) continue;
        hull = hull.hull(intersectPiece(p, line));
    }
    if (hull.isEmpty()) return hull;
    return {hull.lo + line.vShift, hull.hi + line.vShift};
}

}  // namespace dexelmill
