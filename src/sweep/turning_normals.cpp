// The Hermite data of a turning sweep's output ends (TurningSweep::intersect): the outward normal
// of the swept volume at each end, from the tool at the pose that made it, and whether the end
// lies on a crease.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <boost/container/small_vector.hpp>

#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/sweep/turning.h"

namespace dexelmill {

namespace {

/// An output end within this many tolerances of two faces of its pose's tool whose normals differ,
/// or of the tangent plane of a grazing rim's swept surface, takes its Hermite data from that rim.
constexpr double kRimReach = 4.0;

/// Two faces at a rim whose normals differ by less than this angle (rad) meet smoothly: about the
/// resolution of the normals the stock keeps (PackedNormal::kMaxAngleError).
constexpr double kRimAngle = 1e-4;

/// Near a rim, an end takes its Hermite data from the normal velocities a1 and a2 of the rim's two
/// faces there (endNormal). Where both are below this fraction of the speed, the rim slides along
/// itself: the swept rim's normal, square to the velocity across the rim, turns with the ratio of
/// two small numbers that the end's pose (near the one that sweeps S there, not at it) does not
/// give. Both faces graze there, and their sheets meet at a crease. A cylinder turning about an
/// axis through its tip slides its rims so exactly where its side grazes: an end 1.1 tolerances
/// below such a rim took a normal 53 degrees off the side's (normal velocities 5e-5 of the speed).
constexpr double kRimSlide = 0.02;

/// Where the normal velocity of the face an end lies on is at most this fraction of the other
/// face's, that face grazes and the end lies on its sheet of the envelope. At a ball end's top rim
/// an end on the cylinder, at a pose whose side moved at 0.011 of the speed across itself and
/// whose top at 0.33, was marked sharp with no crease near; below a stepped shank's shoulder, the
/// side at 1.6e-5 and the shoulder at 0.042.
constexpr double kGrazeRatio = 0.1;

/// contactPose's search for the pose where a part reaches farthest along a line: its first step
/// in u, most doublings of it (from 1e-6 to the whole move), and its golden-section steps, which
/// leave the pose known to 0.618^30 ~ 5e-7 of the bracket's width.
constexpr double kContactStep = 1e-6;
constexpr int kContactDoublings = 20;
constexpr int kContactGoldenSteps = 30;

/// A face of a convex part at a pose (forEachFace): its squared distance from a point (to the end
/// faces, the disks; to a lateral piece, to its point at the same height, or its nearer end),
/// which orders the faces as the distance does without a square root each, and its outward normal
/// there in the meridian plane, (across the axis, along it).
struct Face {
    double gap2;
    double nr, nz;
    bool covered = false;  ///< a disk inside the tool (MeridianFace::covered)
    bool edge = false;     ///< and its rim an edge of the tool (MeridianFace::edge)
    /// The normal in space, at a point whose direction across the axis is `radial`.
    Vec3 normal(const Vec3& radial, const Vec3& axis) const { return nr * radial + nz * axis; }
};

/// Visits the faces of a convex part (TurningSweep::meridianFaces) at pose `ps`, with their
/// squared gaps to x, in order up the meridian; faces k and k + 1 meet at a rim. Sets x's distance
/// rho from the axis and its unit direction `radial` across the axis (any, on the axis).
template <class Faces, class Visit>
void forEachFace(const Faces& faces, const ToolPose& ps, const Vec3& x, double& rho, Vec3& radial, Visit&& visit) {
    using Kind = decltype(faces.front().kind);
    const Vec3 d = x - ps.tip;
    const double z = glm::dot(d, ps.axis);
    radial = d - z * ps.axis;
    rho = glm::length(radial);
    if (rho > 0.0) {
        radial /= rho;
    } else {  // on the axis: any direction across it
        const Vec3 other = std::abs(ps.axis.x) < 0.9 ? Vec3(1.0, 0.0, 0.0) : Vec3(0.0, 1.0, 0.0);
        radial = glm::normalize(glm::cross(ps.axis, other));
    }
    for (const auto& f : faces) {
        if (f.kind == Kind::Disk) {  // the distance to a disk of radius r0 at height z0
            const double dr = std::max(rho - f.r0, 0.0), dz = z - f.z0;
            visit(Face{dr * dr + dz * dz, f.nr, f.nz, f.covered, f.edge});
            continue;
        }
        // The lateral point at x's height, clamped to the piece.
        const double zc = std::clamp(z, f.z0, f.z1);
        const double R = f.radius(zc);
        double nr = 0.0, nz = 0.0;
        f.normal(R, zc, nr, nz);
        const double dr = rho - R, dz = z - zc;
        visit(Face{dr * dr + dz * dz, nr, nz});
    }
}

}  // namespace

double TurningSweep::MeridianFace::radius(double z) const {
    switch (kind) {
    case Kind::Disk: return r0;
    case Kind::Cone: return r0 + std::clamp((z - z0) / (z1 - z0), 0.0, 1.0) * (r1 - r0);
    default: {
        const double dz = std::clamp(z, z0, z1) - zc;
        return rc + std::sqrt(std::max(0.0, rho * rho - dz * dz));
    }
    }
}

void TurningSweep::MeridianFace::normal(double R, double z, double& nrOut, double& nzOut) const {
    if (kind != Kind::Arc) {
        nrOut = nr, nzOut = nz;
        return;
    }
    const double mr = std::max(0.0, R - rc), mz = z - zc, len = std::sqrt(mr * mr + mz * mz);
    nrOut = len == 0.0 ? 1.0 : mr / len;  // the circle's centre: the equator's normal
    nzOut = len == 0.0 ? 0.0 : mz / len;
}

std::vector<TurningSweep::MeridianFace> TurningSweep::meridianFaces(const std::vector<ProfilePiece>& pieces,
                                                                    const ConvexPart& part) {
    std::vector<MeridianFace> faces;
    MeridianFace bottom;
    bottom.z0 = bottom.z1 = part.z0;
    bottom.r0 = pieceRadius(pieces[part.first], part.z0);
    bottom.nz = -1.0;
    faces.push_back(bottom);
    for (std::size_t i = part.first; i < part.last; ++i) {
        MeridianFace f;
        f.z0 = pieceZ0(pieces[i]);
        f.z1 = pieceZ1(pieces[i]);
        if (const auto* c = std::get_if<ConePiece>(&pieces[i])) {
            f.kind = MeridianFace::Kind::Cone;
            f.r0 = c->r0;
            f.r1 = c->r1;
            meridianNormal(pieces[i], c->r0, c->z0, f.nr, f.nz);
        } else {
            const ArcPiece& a = std::get<ArcPiece>(pieces[i]);
            f.kind = MeridianFace::Kind::Arc;
            f.rc = a.rc;
            f.zc = a.zc;
            f.rho = a.rho;
        }
        faces.push_back(f);
    }
    MeridianFace top;
    top.z0 = top.z1 = part.z1;
    top.r0 = pieceRadius(pieces[part.last - 1], part.z1);
    top.nz = 1.0;
    faces.push_back(top);
    return faces;
}

void TurningSweep::markCoveredDisks(std::vector<std::vector<MeridianFace>>& faces, const std::vector<ConvexPart>& parts,
                                    bool ball) {
    // Neighbouring parts meet at one height (Tool::convexParts): the wider disk there covers the
    // narrower, and a joint where the radius does not step (a concave joint) covers both.
    for (std::size_t p = 0; p + 1 < parts.size(); ++p) {
        if (parts[p].z1 != parts[p + 1].z0) continue;
        MeridianFace& top = faces[p].back();
        MeridianFace& bottom = faces[p + 1].front();
        // Tool::convexParts cuts a profile only at a step or a concave joint: an edge either way.
        top.covered = top.edge = bottom.r0 >= top.r0 - tol::kProfileJoint;
        bottom.covered = bottom.edge = top.r0 >= bottom.r0 - tol::kProfileJoint;
    }
    // The ball's equator is as wide as the part cut there (ballEnd).
    if (ball && !faces.empty()) faces.front().front().covered = true;
}

Vec3 TurningSweep::faceNormal(const ToolPose& pose, std::size_t part, const Vec3& x, int* face, bool* alone) const {
    double rho = 0.0;
    Vec3 radial(0.0);
    Face nearest{std::numeric_limits<double>::infinity(), 0.0, 0.0};
    double second = std::numeric_limits<double>::infinity();  // the next face's squared gap
    int k = 0;
    forEachFace(faces_[part], pose, x, rho, radial, [&](const Face& f) {
        if (f.gap2 < nearest.gap2) {
            second = nearest.gap2;
            nearest = f;
            if (face) *face = k;
        } else {
            second = std::min(second, f.gap2);
        }
        ++k;
    });
    // endNormal's test for a rim takes only faces within kRimReach tolerances. (Where no face's
    // gap is a number, neither is x: endNormal decides.)
    const double reach = kRimReach * epsilon_;
    if (alone) *alone = nearest.gap2 < std::numeric_limits<double>::infinity() && second > reach * reach;
    return nearest.normal(radial, pose.axis);
}

bool TurningSweep::smoothJoint(const std::vector<MeridianFace>& faces, std::size_t k) {
    // The top of the face below the rim (the bottom disk's height, or its piece's top).
    const double z = faces[k].z1, radius = faces[k].radius(z);
    double across[2], along[2];
    for (const std::size_t side : {0, 1})  // the face below the rim, then the one above
        faces[k + side].normal(radius, z, across[side], along[side]);
    return across[0] * across[1] + along[0] * along[1] >= std::cos(kRimAngle);
}

std::optional<TurningSweep::Rim> TurningSweep::rim(std::size_t part, int k) const {
    const std::vector<MeridianFace>& faces = faces_[part];
    if (k < 0 || std::size_t(k) + 1 >= faces.size()) return std::nullopt;
    Rim r;
    r.z = faces[std::size_t(k)].z1;
    r.radius = faces[std::size_t(k)].radius(r.z);
    if (!(r.radius > 0.0) || smoothJoint(faces, std::size_t(k))) return std::nullopt;
    for (const int side : {0, 1})  // the face below the rim, then the one above
        faces[std::size_t(k + side)].normal(r.radius, r.z, r.across[side], r.along[side]);
    return r;
}

// An end a linear node made lies on the surface of its band at a pose M(s) of the node's move
// (MoveSweep::endPoses), which note h's rigid motion carries within epsilon of the tool at the
// true pose u = ua + s (ub - ua). The node's own Hermite data would give the normal of its
// fixed-axis move, whose velocity lacks the turn's: where a rim sweeps the envelope, its normal
// is across the rim and the velocity, and off by as much as the two velocities' directions
// differ. So the end takes the part's Hermite data at that true pose (endNormal). There a face
// where a band is cut (note i) is no face at all: it lies inside the part, and an end it made lies
// within epsilon of the part's lateral face at the band's rim.
void TurningSweep::nodeEndNormal(const Line& line, double t, std::size_t band, std::uint32_t heap, bool upper,
                                 Vec3& normal, bool& sharp) const {
    std::unique_ptr<LinearNode> scratch;  // a node made for this query alone
    const LinearNode& node = linearNode(band, heap, scratch);
    const MoveSweep::EndPoses ends = node.sweep.endPoses(line);
    const double s = upper ? ends.uHi : ends.uLo;
    endNormal(line, t, node.middleU + (s - 0.5) * node.width, models_[band].part, upper, normal, sharp);
}

// The pose near u where the part reaches farthest along the line: the pose that sweeps S at the
// end there. The part's end on the line, hi(u) (lo(u) for a lower end), peaks there, smoothly
// where a face grazes and with a kink where a rim sweeps S; the end's pose lies within the
// search's reach of it. Steps out from u, doubling from kContactStep, bracket the peak where
// hi falls again, and golden-section steps find it within 0.618^kContactGoldenSteps of the
// bracket's width.
double TurningSweep::contactPose(const Line& line, double u, std::size_t part, bool upper, Interval& range) const {
    const auto at = [&](double w) {
        return tool_.intersectPart(parts_[part], LocalLine::make(law_.pose(law_.phase(w)), line));
    };
    // How far out the part's end on the line lies in its interval r: the end's parameter, negated
    // for a lower end.
    const auto outOf = [upper](const Interval& r) {
        if (r.isEmpty()) return -std::numeric_limits<double>::infinity();
        return upper ? r.hi : -r.lo;
    };
    const auto out = [&](double w) { return outOf(at(w)); };
    const auto done = [&](double w) {
        range = at(w);
        return w;
    };
    range = at(u);
    const double f0 = outOf(range);
    // The side on which the end grows, then steps doubling along it until the end shrinks: a
    // bracket [a, c] about a peak at b.
    double h = kContactStep;
    const double up = u + h <= 1.0 ? out(u + h) : f0, down = u - h >= 0.0 ? out(u - h) : f0;
    if (!(std::max(up, down) > f0)) return u;
    const double dir = up >= down ? 1.0 : -1.0;
    double a = u, b = u + dir * h, fb = std::max(up, down);
    for (int k = 0; k < kContactDoublings; ++k) {
        h *= 2.0;
        const double c = std::clamp(b + dir * h, 0.0, 1.0), fc = out(c);
        if (!(fc < fb)) {
            if (c == 0.0 || c == 1.0) return done(c);  // growing up to the first or last pose
            a = b, b = c, fb = fc;
            continue;
        }
        // A golden-section search of [a, c] (ordered), which holds a peak as high as b's.
        double lo = std::min(a, c), hi = std::max(a, c);
        const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
        double x1 = hi - ratio * (hi - lo), x2 = lo + ratio * (hi - lo);
        double f1 = out(x1), f2 = out(x2);
        for (int i = 0; i < kContactGoldenSteps; ++i) {
            if (f1 >= f2) {
                hi = x2, x2 = x1, f2 = f1;
                x1 = hi - ratio * (hi - lo), f1 = out(x1);
            } else {
                lo = x1, x1 = x2, f1 = f2;
                x2 = lo + ratio * (hi - lo), f2 = out(x2);
            }
        }
        const double w = f1 >= f2 ? x1 : x2, fw = std::max(f1, f2);
        return done(fw >= fb ? w : b);
    }
    return done(b);
}

// The faces of one convex part at an end point (forEachFace). The nearest face gives the normal;
// a second one within kRimReach tolerances whose normal differs puts the end on or near a rim of
// the pose's tool.
//
// The end's pose is within the search's reach of the pose that grazes there, so where the
// envelope is swept by a rim, the end lies on a face of its pose near that rim. Near means within
// the tolerance of the rim's swept surface, not of the rim: the face leaves that surface at the
// angle gamma between the face's normal and the surface's, so an end on the face as deep as the
// tolerance inside S may lie epsilon / sin(gamma) from the rim, where the face's normal is off by
// gamma. So an end farther than kRimReach tolerances from every other face also takes a rim's
// swept normal where that rim, one of the nearest face's, grazes at the end's azimuth and the end
// lies within kRimReach tolerances of its swept surface's tangent plane there. A face that itself
// sweeps S near the end meets the rim's swept surface tangentially where its grazing points reach
// the rim, so there gamma is small and either normal serves.
//
// Near a rim the faces' normal velocities decide which of them, or the rim, sweeps S at the end.
// At the end's own pose they point the wrong way where that pose lies on the far side of the one
// that sweeps S there, so they are taken at that pose (contactPose). Over 31 seeds of the tests'
// lines near rims, that took the ends wrong from 261 of 18,804 (up to 15 a seed) to 14 (up to 2),
// and near the joints of convex parts from 61 of 23,314 to 8.
void TurningSweep::endNormal(const Line& line, double t, double u, std::size_t part, bool upper, Vec3& normal,
                             bool& sharp, bool atPose) const {
    // The first and last poses are kept: most ends are theirs on a short move. Another pose's
    // phase serves its rims' velocities too.
    const TurnPhase phase = u == startPhase_.u ? startPhase_ : u == endPhase_.u ? endPhase_ : law_.phase(u);
    const ToolPose ps = u == startPhase_.u ? startPose_ : u == endPhase_.u ? endPose_ : law_.pose(phase);
    const Vec3 x = line.at(t);
    if (part >= parts_.size()) {  // a ball: the sphere about its centre at that pose
        const Vec3 d = x - (ps.tip + balls_[part - parts_.size()].zc * ps.axis);
        const double l = glm::length(d);
        normal = l > 0.0 ? d / l : -ps.axis;
        sharp = false;
        return;
    }
    double rho = 0.0;
    Vec3 radial(0.0);
    boost::container::small_vector<Face, 8> faces;
    forEachFace(faces_[part], ps, x, rho, radial, [&](const Face& f) { faces.push_back(f); });
    const double nearRim = kRimReach * epsilon_;
    // A covered disk gives no normal. Where its rim is an edge of the tool, concave or a step, an
    // end near it lies near a crease of S: the first or last pose's, or the envelope's, whose two
    // faces' sheets meet there at an angle as the tool's faces do (a tool turning about its tip
    // sweeps its profile's concave corners as creases).
    bool nearJoint = false;
    for (Face& f : faces)
        if (f.covered) {
            nearJoint = nearJoint || (f.edge && f.gap2 <= nearRim * nearRim);
            f.gap2 = std::numeric_limits<double>::infinity();
        }
    std::size_t nearest = 0;
    for (std::size_t k = 1; k < faces.size(); ++k)
        if (faces[k].gap2 < faces[nearest].gap2) nearest = k;
    normal = faces[nearest].normal(radial, ps.axis);
    sharp = nearJoint;
    const Vec3 tangent = glm::cross(ps.axis, radial);
    // The normal of the surface a rim point sweeps, across the rim's tangent and the point's
    // velocity (MotionLaw::velocity), where it lies within the rim's normal cone (the normals
    // between its two faces', n1 and n2): there the moving rim grazes and the envelope is smooth.
    const auto sweptRim = [&](const Vec3& n1, const Vec3& n2, const Vec3& at) -> std::optional<Vec3> {
        const Vec3 velocity = law_.velocity(phase, at);
        Vec3 n = glm::cross(tangent, velocity);
        const double len = glm::length(n);
        if (len <= tol::kParallel * glm::length(velocity)) return std::nullopt;
        n /= len;
        if (glm::dot(n, n1 + n2) < 0.0) n = -n;
        // n = alpha n1 + beta n2 in the meridian plane: inside the cone when both are non-negative.
        const double c = glm::dot(n1, n2), p1 = glm::dot(n, n1), p2 = glm::dot(n, n2);
        const double det = 1.0 - c * c;
        const double alpha = (p1 - c * p2) / det, beta = (p2 - c * p1) / det;
        if (alpha < 0.0 || beta < 0.0) return std::nullopt;
        return n;
    };
    // A face within reach whose normal differs makes a rim with the nearest, unless the two meet
    // smoothly: near a tangent joint (a taper ball's arc and cone) the curved face's normal at the
    // end's height differs from the other's by its curvature times the height between. On a
    // taper ball turning 150 degrees, an end on the arc 2.5e-3 mm below such a joint was marked
    // sharp, both faces grazing there.
    // The Hermite data decided again at the pose that sweeps S at the end (contactPose), where
    // the part there still meets the line on the end's inner side: the steps out to that pose may
    // pass a gap in S to a pose that meets the line farther on. (An end a node made may lie just
    // beyond the part, within the tolerance its band grew by.) False where it is not.
    const auto atContact = [&]() {
        Interval range;
        const double at = contactPose(line, u, part, upper, range);
        if (at == u || range.isEmpty() || !(upper ? range.lo <= t : range.hi >= t)) return false;
        endNormal(line, upper ? range.hi : range.lo, at, part, upper, normal, sharp, true);
        return true;
    };
    const Face* other = nullptr;
    for (std::size_t k = 0; k < faces.size() && !other; ++k) {
        if (k == nearest || faces[k].gap2 > nearRim * nearRim) continue;
        if ((k + 1 == nearest || nearest + 1 == k) && smoothJoint(faces_[part], std::min(k, nearest))) continue;
        if (glm::dot(faces[k].normal(radial, ps.axis), normal) < std::cos(kRimAngle)) other = &faces[k];
    }
    if (other) {
        // On a rim, a circle about the axis (on the axis, an apex: a point): the swept rim's
        // normal where it grazes; elsewhere the end lies on a crease of the swept volume. So does
        // a rim of the first or last pose, where the rim's swept surface starts or stops and meets
        // that pose's own faces at an angle.
        const Vec3 n1 = normal, n2 = other->normal(radial, ps.axis);
        normal = glm::normalize(n1 + n2);
        sharp = true;
        if (rho <= 0.0 || u <= 0.0 || u >= 1.0) return;
        // The end's pose is only near the one that sweeps S there, and what follows decides by
        // the faces' velocities, which point the wrong way as often as the end's pose lies on the
        // wrong side of that one: so it decides at that pose, where the part reaches farthest
        // along the line, and at the end the part makes there.
        if (!atPose && atContact()) return;
        // The faces' normal velocities (mm per unit of u). Where they have opposite signs, the rim
        // grazes: its swept normal, alpha n1 + beta n2 square to the velocity, unless both are
        // so small that the rim slides along itself (then a crease). Where both advance or both
        // recede, the end lies on the sheet of the face that grazes, the other bounding S only as
        // the last pose's face (where it advances) or the first's (where it recedes): a crease
        // where that pose's face lies within reach, as where neither face grazes.
        const Vec3 velocity = law_.velocity(phase, x);
        const double a1 = glm::dot(n1, velocity), a2 = glm::dot(n2, velocity);
        if ((a1 > 0.0) != (a2 > 0.0)) {
            if (std::max(std::abs(a1), std::abs(a2)) <= kRimSlide * glm::length(velocity)) return;
            normal = glm::normalize(std::abs(a2) * n1 + std::abs(a1) * n2), sharp = nearJoint;
            return;
        }
        // How far the last or first pose's face lies ahead of a face moving across itself at a.
        const auto ahead = [u](double a) { return a > 0.0 ? (1.0 - u) * a : -u * a; };
        if (std::abs(a1) <= kGrazeRatio * std::abs(a2) && ahead(a2) > nearRim) {
            normal = n1, sharp = nearJoint;
        } else if (std::abs(a2) <= kGrazeRatio * std::abs(a1) && ahead(a1) > nearRim) {
            normal = n2, sharp = nearJoint;
        }
        return;
    }
    // The nearest face's rims: below it (faces nearest - 1 and nearest) and above it. Not at the
    // first or last pose, whose own faces bound the sweep where an end they make lies, nor at the
    // pose that sweeps S at the end (contactPose), where the end lies on the face that does: a
    // taper ball turning 134 degrees about its tip took the swept normal of its top rim, 4.2
    // tolerances above such an end, 1 rad off the side's. Where a rim would give the end its
    // swept normal, the end is decided at that pose instead: an APT cutter's end 4.2 tolerances
    // below its top rim took that rim's swept normal, 0.1 rad off, where at the pose that sweeps
    // S it lay 2.4 tolerances from the rim on a side that grazes, and took the side's normal.
    if (atPose || u <= 0.0 || u >= 1.0) return;
    for (const std::size_t below : {nearest - 1, nearest}) {
        if (below >= faces.size() - 1) continue;  // above the top face, or below the bottom one
        if (faces[below].covered || faces[below + 1].covered) continue;  // inside the tool
        const std::optional<Rim> r = rim(part, int(below));
        if (!r) continue;  // a smooth joint, or an apex
        const Vec3 n1 = r->across[0] * radial + r->along[0] * ps.axis;
        const Vec3 n2 = r->across[1] * radial + r->along[1] * ps.axis;
        const Vec3 at = ps.tip + r->z * ps.axis + r->radius * radial;
        const std::optional<Vec3> n = sweptRim(n1, n2, at);
        if (n && std::abs(glm::dot(x - at, *n)) <= nearRim) {
            if (!atContact()) normal = *n;
            return;
        }
    }
}

}  // namespace dexelmill
