#include "dexelmill/sweep/sweep.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"
#include "sweep/parts.h"

// The symbols of the move's frame are in sweep/parts.h.

namespace dexelmill {

namespace {

/// Real roots of a v^2 + 2 b v + c = 0 (numerically stable form). Returns how many (0, 1 or 2).
int quadraticRoots(double a, double b, double c, double& r1, double& r2) {
    if (a == 0.0) {
        if (b == 0.0) return 0;
        r1 = r2 = -c / (2.0 * b);
        return 1;
    }
    const double disc = b * b - a * c;
    if (disc < 0.0) return 0;
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    if (q == 0.0) {  // b == 0 and c == 0: a double root at 0
        r1 = r2 = 0.0;
        return 2;
    }
    r1 = q / a;
    r2 = c / q;
    return 2;
}

/// True when an arc piece ends (at height z) where its tangent is horizontal in the profile,
/// i.e. where its surface normal is the axis: a flat face there joins it without a kink.
bool arcEndIsFlat(const ArcPiece& a, double z) {
    return std::abs(std::abs(z - a.zc) - a.rho) <= tol::kProfileJoint;
}

/// True when a flat face at height z (the piece's lowest or highest) meets the piece at an angle:
/// a rim, or a cone's apex when the piece's radius there is 0.
bool faceMeetsAtAngle(const ProfilePiece& piece, double z) {
    const auto* a = std::get_if<ArcPiece>(&piece);
    return !(a && arcEndIsFlat(*a, z));
}

/// True when the slope of the profile jumps at height zj, where `below` ends and `above` starts.
bool slopeJumps(const ProfilePiece& below, const ProfilePiece& above, double zj) {
    const double sBelow = pieceSlope(below, zj), sAbove = pieceSlope(above, zj);
    return std::abs(sBelow - sAbove) > tol::kSlope * std::max(1.0, std::abs(sBelow));
}

/// The tool-frame line coefficients of the foundation's static queries (tool.h): height
/// z0 + zv t, squared axis distance A t^2 + 2 B t + C, with t the local line parameter.
LocalLine localLine(const Vec3& o, const Vec3& w) {
    LocalLine l;
    l.z0 = o.z;
    l.zv = w.z;
    l.A = w.x * w.x + w.y * w.y;
    l.B = o.x * w.x + o.y * w.y;
    l.C = o.x * o.x + o.y * o.y;
    l.vShift = 0.0;
    return l;
}

/// The relative rounding of a sum of three terms, computed as one: the height of a point over a
/// rim (o.z + v w.z - zr), known to this fraction of the terms' magnitudes.
constexpr double kRimHeightRounding = 4.0 * std::numeric_limits<double>::epsilon();

/// The line o + v w inside the static part (the tool at one pose): the hull of its pieces'
/// intervals, which is exact because the part is convex.
Interval staticPart(const MoveSweep::Part& part, const Vec3& o, const Vec3& w) {
    const LocalLine l = localLine(o, w);
    Interval hull;
    for (const ProfilePiece& p : part.pieces) hull = hull.hull(intersectPiece(p, l));
    return hull;
}

/// Support value max over the part of (z xn + R(z) xr): the part's extent in a direction with
/// axial component xn and radial component xr >= 0, measured from the tip.
double partSupport(const InlineList<ProfilePiece, 4>& pieces, double xn, double xr) {
    double h = -kInf;
    for (const ProfilePiece& p : pieces) {
        if (const auto* c = std::get_if<ConePiece>(&p)) {
            h = std::max({h, c->z0 * xn + c->r0 * xr, c->z1 * xn + c->r1 * xr});
        } else {
            const ArcPiece& a = std::get<ArcPiece>(p);
            // On the arc the outward normal (xr, xn) is reached at z = zc + rho xn / |(xn, xr)|
            // (the callers' directions are unit vectors, so no overflow to guard against).
            const double len = std::sqrt(xn * xn + xr * xr);
            const double z = std::clamp(a.zc + a.rho * xn / len, a.z0, a.z1);
            const double dz = z - a.zc;
            const double radius = a.rc + std::sqrt(std::max(0.0, a.rho * a.rho - dz * dz));
            h = std::max(h, z * xn + radius * xr);
        }
    }
    return h;
}

/// Whether the plane segments [(x0, y0), (x1, y1)] and [(0, 0), (fd, 0)] come within sqrt(r2) of
/// each other. Two segments that do not cross are nearest at an end of one of them, so the
/// distance is the least of the four ends' distances to the other segment. Divisions are what
/// such a test costs most (a turning sweep asks it for every line it is queried on), so it takes
/// one, and only where no end is near and the segments do not cross.
bool segmentsNear(double x0, double y0, double x1, double y1, double fd, double r2) {
    const double lo = std::min(0.0, fd), hi = std::max(0.0, fd);
    const auto toSecond = [&](double x, double y) {
        const double dx = x < lo ? lo - x : x > hi ? x - hi : 0.0;
        return dx * dx + y * y;
    };
    if (toSecond(x0, y0) <= r2 || toSecond(x1, y1) <= r2) return true;
    const double ux = x1 - x0, uy = y1 - y0;
    if ((y0 < 0.0) != (y1 < 0.0)) {
        // The first segment crosses the x-axis at x = x0 + ux y0 / (y0 - y1); with D = y0 - y1
        // (not 0, as the signs differ), x D = x0 D + ux y0, compared with lo D and hi D.
        const double D = y0 - y1, xD = x0 * D + ux * y0;
        if (D > 0.0 ? (xD >= lo * D && xD <= hi * D) : (xD <= lo * D && xD >= hi * D)) return true;
    }
    const double uu = ux * ux + uy * uy;
    if (!(uu > 0.0)) return false;
    const double inv = 1.0 / uu;
    const auto toFirst = [&](double x) {
        const double t = std::clamp(((x - x0) * ux - y0 * uy) * inv, 0.0, 1.0);
        const double dx = x0 + t * ux - x, dy = y0 + t * uy;
        return dx * dx + dy * dy;
    };
    return toFirst(0.0) <= r2 || toFirst(fd) <= r2;
}

}  // namespace

MoveSweep::MoveSweep(const Tool& tool, const Move& move) : MoveSweep(tool, move.start, move.end, move.axis) {}

MoveSweep::MoveSweep(const MoveSweep&) = default;
MoveSweep::MoveSweep(MoveSweep&&) noexcept = default;
MoveSweep& MoveSweep::operator=(const MoveSweep&) = default;
MoveSweep& MoveSweep::operator=(MoveSweep&&) noexcept = default;
MoveSweep::~MoveSweep() = default;

std::size_t MoveSweep::partCount() const { return parts_.size(); }

MoveSweep::PartPieces MoveSweep::partPieces(const Tool& tool) {
    const std::vector<ConvexPart>& convex = tool.convexParts();
    if (convex.size() > kMaxParts)
        throw Error("tool '" + tool.description() + "' has " + std::to_string(convex.size()) +
                    " convex parts; the sweep handles at most " + std::to_string(kMaxParts));
    PartPieces out;
    for (const ConvexPart& cp : convex) {
        out.first[out.parts] = tool.pieces().data() + cp.first;
        out.count[out.parts++] = cp.last - cp.first;
    }
    return out;
}

MoveSweep::PartPieces MoveSweep::partPieces(const std::vector<ProfilePiece>& pieces) {
    PartPieces out;
    out.first[0] = pieces.data();
    out.count[0] = pieces.size();
    out.parts = 1;
    return out;
}

MoveSweep::MoveSweep(const Tool& tool, const Vec3& start, const Vec3& end, const Vec3& axis)
    : MoveSweep(partPieces(tool), start, end, axis) {}

MoveSweep::MoveSweep(const std::vector<ProfilePiece>& pieces, const Vec3& start, const Vec3& end, const Vec3& axis)
    : MoveSweep(partPieces(pieces), start, end, axis) {}

MoveSweep::MoveSweep(const PartPieces& partList, const Vec3& start, const Vec3& end, const Vec3& axis)
    : start_(start) {
    const Vec3 f = end - start;
    frame_ = ToolFrame::make(axis, f);  // validates the axis
    feedLength_ = glm::length(f);
    creaseU_ = sweep_tol::kCrease / feedLength_;
    const Vec3& n = frame_.n;
    const double fn = glm::dot(f, n);
    if (feedLength_ <= tol::kZeroMove) {
        kind_ = SweepKind::Static;
        feedLocal_ = Vec3(0.0);
    } else if (frame_.plunge) {
        kind_ = SweepKind::Plunge;
        feedLocal_ = Vec3(0.0, 0.0, fn);
    } else {
        // d.f as the length of f's part perpendicular to n (d is that part normalised): dotting f
        // itself with d would add (n.f)(n.d), a rounding error large against a tiny d.f.
        const double fd = glm::dot(f - fn * n, frame_.d);
        if (std::abs(fn) <= sweep_tol::kHorizontal * feedLength_) {
            kind_ = SweepKind::Horizontal;
            feedLocal_ = Vec3(fd, 0.0, 0.0);
        } else {
            kind_ = SweepKind::General;
            feedLocal_ = Vec3(fd, 0.0, fn);
        }
    }
    const double fd = feedLocal_.x, fnl = feedLocal_.z;
    const double flen = glm::length(feedLocal_);
    if (kind_ == SweepKind::General) {
        invF2_ = 1.0 / (flen * flen);
        invFn_ = 1.0 / fnl;
        kappa_ = std::abs(fnl) / flen;
        qDir_ = Vec3(-fnl / flen, 0.0, fd / flen);
    }
    // A rim at height z, radius r between faces with meridian unit normals (nr0, nz0) below and
    // (nr1, nz1) above.
    const auto rimAt = [&](double z, double r, double nr0, double nz0, double nr1, double nz1) {
        return Circle{z, r, fd * z / flen, nr0 + nr1, nz0 + nz1};
    };
    const auto sideNormal = [](const ProfilePiece& p, double z, double& nr, double& nz) {
        meridianNormal(p, pieceRadius(p, z), z, nr, nz);
    };

    parts_.reserve(partList.parts);
    staticProfiles_.reserve(partList.parts);
    for (std::size_t k = 0; k < partList.parts; ++k) {
        Part& part = parts_.emplace_back();
        part.pieces.assign(partList.first[k], partList.first[k] + partList.count[k]);
        const std::size_t nPieces = part.pieces.size();
        part.z0 = pieceZ0(part.pieces.front());
        part.z1 = pieceZ1(part.pieces.back());
        const ProfilePiece& bottom = part.pieces.front();
        const ProfilePiece& top = part.pieces.back();
        const double rBottom = pieceRadius(bottom, part.z0), rTop = pieceRadius(top, part.z1);
        StaticProfile& profile = staticProfiles_.emplace_back();
        profile.z0 = part.z0, profile.z1 = part.z1;
        profile.sides.reserve(nPieces);
        for (std::size_t i = 0; i < part.pieces.size(); ++i) {
            const ProfilePiece& p = part.pieces[i];
            ProfileSide side;
            side.z1 = pieceZ1(p);
            if (const auto* a = std::get_if<ArcPiece>(&p))
                side.arc = true, side.rc = a->rc, side.zc = a->zc, side.invRho = 1.0 / a->rho;
            else meridianNormal(p, 0.0, 0.0, side.nr, side.nz);
            side.creaseAbove = i + 1 < part.pieces.size() && slopeJumps(p, part.pieces[i + 1], side.z1);
            profile.sides.push_back(side);
        }
        profile.bottomFace = {rBottom, faceMeetsAtAngle(bottom, part.z0)};
        profile.topFace = {rTop, faceMeetsAtAngle(top, part.z1)};

        // The largest radius and the heights where it is reached (R is concave: an interval).
        part.rMax = -kInf;
        for (const ProfilePiece& p : part.pieces) {
            const double pz0 = pieceZ0(p), pz1 = pieceZ1(p);
            double zPeak0, zPeak1, r;
            if (const auto* c = std::get_if<ConePiece>(&p)) {
                if (c->r0 == c->r1) zPeak0 = pz0, zPeak1 = pz1, r = c->r0;
                else if (c->r0 > c->r1) zPeak0 = zPeak1 = pz0, r = c->r0;
                else zPeak0 = zPeak1 = pz1, r = c->r1;
            } else {
                const ArcPiece& a = std::get<ArcPiece>(p);
                zPeak0 = zPeak1 = std::clamp(a.zc, pz0, pz1);
                r = pieceRadius(p, zPeak0);
            }
            const double same = tol::kLength * std::max(1.0, r);
            if (r > part.rMax + same) {
                part.rMax = r, part.zMax0 = zPeak0, part.zMax1 = zPeak1;
            } else if (r >= part.rMax - same) {
                part.rMax = std::max(part.rMax, r);
                part.zMax0 = std::min(part.zMax0, zPeak0), part.zMax1 = std::max(part.zMax1, zPeak1);
            }
        }

        if (kind_ == SweepKind::General || kind_ == SweepKind::Horizontal) {
            // Cones and cylinders: Eq. (28), the generators at azimuth phi with
            // cos(phi) = k (n.f) / (d.f) graze (k = dR/dz); Eq. (30), each sweeps the planar strip
            // O + t S + u f. Horizontal moves: cos(phi) = 0, the generators at +-e.
            part.strips.reserve(2 * nPieces);
            for (const ProfilePiece& p : part.pieces) {
                const auto* c = std::get_if<ConePiece>(&p);
                if (!c) continue;
                const double cosPhi = coneSlope(*c) * fnl / fd;
                if (std::abs(cosPhi) > 1.0) continue;  // no generator grazes: steeper than the flank
                const double sinPhi = std::sqrt(std::max(0.0, 1.0 - cosPhi * cosPhi));
                for (double sgn : {1.0, -1.0}) {
                    GrazingStrip s;
                    const Vec3 radial(cosPhi, sgn * sinPhi, 0.0);
                    s.origin = c->r0 * radial + Vec3(0.0, 0.0, c->z0);
                    s.span = (c->r1 - c->r0) * radial + Vec3(0.0, 0.0, c->z1 - c->z0);
                    s.normal = glm::cross(s.span, feedLocal_);
                    // The cone's outward normal (radial, -dR/dz) is perpendicular to S and f.
                    s.outward = (glm::dot(s.normal, radial) < 0.0 ? -1.0 : 1.0) / glm::length(s.normal);
                    s.degenerate = tol::kParallel * glm::length(s.span) * flen;
                    if (glm::length(s.normal) > s.degenerate) part.strips.push_back(s);
                    if (sinPhi == 0.0) break;  // a single generator
                }
            }
        }

        if (kind_ == SweepKind::General) {
            for (const ProfilePiece& p : part.pieces) {
                const auto* a = std::get_if<ArcPiece>(&p);
                if (!a) continue;
                if (a->rc == 0.0) {
                    part.capsules.push_back({a->zc, a->rho, a->z0, a->z1});
                    continue;
                }
                // Torus: the grazing normals are N(psi) = cos(psi) q + sin(psi) e; the grazing
                // point at height zc + rho fd cos(psi) / |f| lies on the piece when that height
                // is in [z0, z1].
                GrazingTorus t;
                t.rc = a->rc, t.zc = a->zc, t.rho = a->rho;
                // cos(psi) = (z - zc) |f| / (rho fd). The lowest grazing point is rho (1 - fd / |f|)
                // above the torus's bottom; decide "the piece reaches it" by comparing products,
                // not through acos of a value one rounding away from -1 (off by 1e-8 rad, more
                // than the whole bottom stretch of a nearly horizontal move).
                const double scale = flen / (a->rho * fd);
                t.cosLo = (a->z0 - a->zc) * flen <= -a->rho * fd ? -1.0 : (a->z0 - a->zc) * scale;
                t.cosHi = (a->z1 - a->zc) * flen >= a->rho * fd ? 1.0 : (a->z1 - a->zc) * scale;
                if (t.cosLo > t.cosHi) continue;
                const double psiA = std::acos(t.cosHi), psiB = std::acos(t.cosLo);
                if (!(psiB > psiA)) continue;
                for (double side : {1.0, -1.0}) {
                    TorusArc& arc = t.arc[t.arcs++];
                    arc.side = side;
                    const double mid = side * 0.5 * (psiA + psiB);
                    arc.cosMid = std::cos(mid), arc.sinMid = std::sin(mid);
                    arc.T = std::tan(0.25 * (psiB - psiA));
                    for (double end : {-1.0, 1.0}) {
                        const double psi = mid + end * 0.5 * (psiB - psiA);
                        const double cp = std::cos(psi), sp = std::sin(psi);
                        const Vec3 pt = torusPoint(t, -fnl * cp / flen, sp, fd * cp / flen);
                        (end < 0 ? arc.endLo : arc.endHi) = pt;
                    }
                }
                // Where the two mirror arcs meet (psi = 0 or pi: the d-n plane), they share the
                // point bit for bit, so that both see the same sign of g there: a line in the
                // plane of symmetry of the move crosses the curve exactly at the junction.
                if (t.cosLo == -1.0) t.arc[1].endLo = t.arc[0].endHi;
                if (t.cosHi == 1.0) t.arc[1].endHi = t.arc[0].endLo;
                part.tori.push_back(t);
            }
            // Rims: the bottom and top faces' edges, and joints where the slope jumps. A rim point
            // grazes where its cone of normals holds one perpendicular to f; its sweep is an
            // elliptic cylinder. Points of a rim that do not graze lie inside the shadow cylinder,
            // so they are harmless extra candidates.
            part.rims.reserve(nPieces + 1);
            double nr0, nz0, nr1, nz1;
            if (rBottom > 0.0 && faceMeetsAtAngle(bottom, part.z0)) {
                sideNormal(bottom, part.z0, nr1, nz1);
                part.rims.push_back(rimAt(part.z0, rBottom, 0.0, -1.0, nr1, nz1));
            }
            for (std::size_t i = 0; i + 1 < part.pieces.size(); ++i) {
                const double zj = pieceZ1(part.pieces[i]);
                if (!slopeJumps(part.pieces[i], part.pieces[i + 1], zj)) continue;
                sideNormal(part.pieces[i], zj, nr0, nz0);
                sideNormal(part.pieces[i + 1], zj, nr1, nz1);
                part.rims.push_back(rimAt(zj, pieceRadius(part.pieces[i], zj), nr0, nz0, nr1, nz1));
            }
            if (rTop > 0.0 && faceMeetsAtAngle(top, part.z1)) {
                sideNormal(top, part.z1, nr0, nz0);
                part.rims.push_back(rimAt(part.z1, rTop, nr0, nz0, 0.0, 1.0));
            }
        }

        if (kind_ == SweepKind::Horizontal) {
            for (const ProfilePiece& p : part.pieces)
                if (const auto* a = std::get_if<ArcPiece>(&p)) part.meridianArcs.push_back(*a);
            if (rBottom > 0.0) part.disks.push_back({part.z0, rBottom});
            if (rTop > 0.0) part.disks.push_back({part.z1, rTop});
        }
    }

    // The oriented boxes: e, and for a moving tool q across the feed and f / |f| along it (the
    // shadow cylinder's cross-section is bounded in e and q); else d and n.
    if (kind_ == SweepKind::General || kind_ == SweepKind::Horizontal)
        boxAxes_ = {Vec3(0.0, 1.0, 0.0), Vec3(-fnl / flen, 0.0, fd / flen), feedLocal_ / flen};
    else
        boxAxes_ = {Vec3(0.0, 1.0, 0.0), Vec3(1.0, 0.0, 0.0), Vec3(0.0, 0.0, 1.0)};
    for (int i = 0; i < 3; ++i)
        worldBoxAxes_[i] = boxAxes_[i].x * frame_.d + boxAxes_[i].y * frame_.e + boxAxes_[i].z * frame_.n;
    for (Part& part : parts_) {
        for (int i = 0; i < 3; ++i) {
            const Vec3& a = boxAxes_[i];
            const double xr = std::sqrt(a.x * a.x + a.y * a.y);
            const double along = glm::dot(a, feedLocal_);
            part.box[i] = {-partSupport(part.pieces, -a.z, xr) + std::min(0.0, along),
                           partSupport(part.pieces, a.z, xr) + std::max(0.0, along)};
        }
    }

    // The box: the support function of the sweep in +-x, +-y, +-z is the part's support from the
    // start tip plus max(0, f . direction).
    for (int i = 0; i < 3; ++i) {
        for (double sgn : {1.0, -1.0}) {
            const double xn = sgn * frame_.n[i];
            const double xr = std::sqrt(std::max(0.0, 1.0 - xn * xn));
            double h = -kInf;
            for (const Part& part : parts_) h = std::max(h, partSupport(part.pieces, xn, xr));
            const double along = std::max(0.0, sgn * f[i]);
            if (sgn > 0) bounds_.hi[i] = start[i] + h + along;
            else bounds_.lo[i] = start[i] - h - along;
        }
    }
}

MoveSweep::LocalLine MoveSweep::toLocal(const Line& line) const {
    LocalLine q;
    const Vec3& w = line.dir;
    const Vec3 rel = line.origin - start_;
    // Re-anchor the line at its point nearest the start tip: keeps the local numbers small.
    q.vShift = -glm::dot(rel, w);
    const Vec3 a = rel + q.vShift * w;
    q.o = Vec3(glm::dot(a, frame_.d), glm::dot(a, frame_.e), glm::dot(a, frame_.n));
    q.w = Vec3(glm::dot(w, frame_.d), glm::dot(w, frame_.e), glm::dot(w, frame_.n));
    q.c = glm::cross(q.w, feedLocal_);
    q.c2 = glm::dot(q.c, q.c);
    q.co = glm::dot(q.c, q.o);
    const double par = sweep_tol::kParallelFeed * feedLength_;
    q.parallel = q.c2 <= par * par;
    return q;
}

Interval MoveSweep::boxLocal(const Part& part, const LocalLine& q) const {
    Interval range = Interval::all();
    for (int i = 0; i < 3; ++i) {
        const double oa = glm::dot(q.o, boxAxes_[i]), wa = glm::dot(q.w, boxAxes_[i]);
        const double lo = part.box[i].lo - sweep_tol::kBoxSlack - oa, hi = part.box[i].hi + sweep_tol::kBoxSlack - oa;
        if (wa == 0.0) {
            if (lo > 0.0 || hi < 0.0) return Interval::empty();
            continue;
        }
        const double v0 = lo / wa, v1 = hi / wa;
        range = range.intersect(wa > 0.0 ? Interval{v0, v1} : Interval{v1, v0});
    }
    return range;
}

template <bool kTrace>
Interval MoveSweep::intersectLocal(const Part& part, const LocalLine& q, [[maybe_unused]] EndTrace* trace) const {
    const Vec3& o = q.o;
    const Vec3& w = q.w;
    if (kind_ == SweepKind::Static) {
        if constexpr (kTrace) trace->lo.pose = trace->hi.pose = 0;
        return staticPart(part, o, w);
    }
    if (q.parallel) {
        // A line parallel to the move: the static interval stretched along it by the move.
        const Interval first = staticPart(part, o, w), last = staticPart(part, o - feedLocal_, w);
        if constexpr (kTrace) {
            trace->lo.pose = first.isEmpty() || last.lo < first.lo ? 1 : 0;
            trace->hi.pose = first.isEmpty() || last.hi > first.hi ? 1 : 0;
        }
        return first.hull(last);
    }
    // Early rejection, seen along f: the part lies within rMax of its axis segment, whose ends
    // project at signed distances g / |c| from the projected line (g = c . P - c . o). When both
    // ends are farther than rMax on the same side, the line misses the shadow cylinder.
    const double g0 = q.c.z * part.z0 - q.co, g1 = q.c.z * part.z1 - q.co;
    const double reach = part.rMax + sweep_tol::kBoxSlack;
    if ((g0 > 0.0) == (g1 > 0.0) && std::min(g0 * g0, g1 * g1) > reach * reach * q.c2) return Interval::empty();
    // The oriented box pays only where the exact work is root finding (a flat or ball end mill's
    // closed forms cost little more than the box).
    if (!part.tori.empty() && boxLocal(part, q).isEmpty()) return Interval::empty();

    const double fd = feedLocal_.x, fn = feedLocal_.z;
    Extremes<kTrace> ex;
    if constexpr (kTrace) ex.lo = &trace->lo.sources, ex.hi = &trace->hi.sources;

    if (kind_ == SweepKind::Plunge) {
        // The shadow cylinder is rho = rMax; its point at height z is swept by the tool at u when
        // z - u fn lies where R = rMax.
        double r1, r2;
        const int n = quadraticRoots(w.x * w.x + w.y * w.y, o.x * w.x + o.y * w.y,
                                     o.x * o.x + o.y * o.y - part.rMax * part.rMax, r1, r2);
        for (int i = 0; i < n; ++i) {
            const double v = i ? r2 : r1;
            const double z = o.z + v * w.z;
            const double ua = (z - part.zMax1) / fn, ub = (z - part.zMax0) / fn;
            ex.add(v, std::min(ua, ub), std::max(ua, ub), kNoSource);
        }
    } else {
        // Eq. (31): o + v w = O + t S + u f, solved by triple products with D = w . (S x f).
        for (const GrazingStrip& s : part.strips) {
            const double D = glm::dot(w, s.normal);
            if (std::abs(D) <= s.degenerate) continue;
            const Vec3 r = o - s.origin;
            const double invD = 1.0 / D;
            const double t = -glm::dot(r, q.c) * invD;
            if (t < -sweep_tol::kParam || t > 1.0 + sweep_tol::kParam) continue;
            const double v = -glm::dot(r, s.normal) * invD;
            const double u = glm::dot(r, glm::cross(w, s.span)) * invD;
            ex.add(v, u, Source::of(Source::Strip, std::uint32_t(&s - part.strips.data())));
        }

        if (kind_ == SweepKind::Horizontal) {
            // The profile seen along f: arcs as circles in the (e, n) plane on either side.
            for (const ArcPiece& a : part.meridianArcs) {
                const double zSlack = sweep_tol::kParam * (a.z1 - a.z0);
                for (double side : {1.0, -1.0}) {
                    const double y0 = o.y - side * a.rc, z0 = o.z - a.zc;
                    double r1, r2;
                    const int n = quadraticRoots(w.y * w.y + w.z * w.z, y0 * w.y + z0 * w.z,
                                                 y0 * y0 + z0 * z0 - a.rho * a.rho, r1, r2);
                    for (int i = 0; i < n; ++i) {
                        const double v = i ? r2 : r1;
                        const Vec3 p = o + v * w;
                        if (p.z < a.z0 - zSlack || p.z > a.z1 + zSlack) continue;
                        if (a.rc > 0.0 && side * p.y < a.rc) continue;  // the inner half: not the tool's
                        ex.add(v, p.x / fd, kNoSource);
                    }
                    if (a.rc == 0.0) break;  // a sphere: one circle
                }
            }
            // The flat faces graze: a disk of radius r at height z sweeps a stadium in its plane.
            for (const Circle& disk : part.disks) {
                if (std::abs(w.z) <= tol::kParallel) {
                    // A line lying in the face's plane (method.md section 5: closed convention,
                    // the face's points are removed) crosses the stadium's sides y = +-r.
                    if (std::abs(o.z - disk.z) > tol::kLength || w.y == 0.0) continue;
                    for (double side : {1.0, -1.0}) {
                        const double v = (side * disk.r - o.y) / w.y;
                        ex.add(v, (o.x + v * w.x) / fd, kNoSource);
                    }
                    continue;
                }
                const double v = (disk.z - o.z) / w.z;
                const Vec3 p = o + v * w;
                const double s2 = disk.r * disk.r - p.y * p.y;
                if (s2 < 0.0) continue;
                const double s = std::sqrt(s2);
                ex.add(v, (p.x - s) / fd, (p.x + s) / fd, kNoSource);
            }
        } else {
            // Sphere: the grazing great circle perpendicular to f sweeps a cylinder of radius rho
            // about the centre's path (with the start and end spheres: a capsule).
            for (const GrazingCapsule& cap : part.capsules) {
                const Vec3 r(o.x, o.y, o.z - cap.zc);
                const double rf = glm::dot(r, feedLocal_), wf = glm::dot(w, feedLocal_);
                double r1, r2;
                const int n = quadraticRoots(q.c2 * invF2_, glm::dot(r, w) - rf * wf * invF2_,
                                             glm::dot(r, r) - rf * rf * invF2_ - cap.rho * cap.rho, r1, r2);
                const double zSlack = sweep_tol::kParam * (cap.z1 - cap.z0);
                for (int i = 0; i < n; ++i) {
                    const double v = i ? r2 : r1;
                    const double u = (rf + v * wf) * invF2_;
                    const double z = o.z + v * w.z - u * fn;  // height of the grazing point
                    if (z < cap.z0 - zSlack || z > cap.z1 + zSlack) continue;
                    ex.add(v, u, Source::of(Source::Capsule, std::uint32_t(&cap - part.capsules.data())));
                }
            }

            // Torus: Eq. (36) and Algorithm 1 (see torusCrossings).
            if (!part.tori.empty()) {
                const TorusLine tl{o, w, q.c, q.c2, q.co, feedLocal_};
                for (const GrazingTorus& tor : part.tori)
                    torusCrossings(tor, std::uint32_t(&tor - part.tori.data()), tl, ex);
            }

            // Rims: the sweep of a rim circle (radius r at height zr) is an elliptic cylinder.
            // Seen along f it is the ellipse with semi-axes r along e and r kappa along q,
            // kappa = |fn| / |f|, centred at q = fd zr / |f|. The projected line o + v w crosses it
            // where, with dq = o.q - fd zr / |f| (the rim's qc) and a = kappa^2 w.e^2 + (w.q)^2,
            //   v = (-(kappa^2 o.e w.e + dq w.q) +- kappa sqrt(r^2 a - (o.e w.q - w.e dq)^2)) / a,
            // a form in which nothing cancels when the move is nearly horizontal (kappa -> 0).
            // The feed parameter follows from the axial row: u = (o.z + v w.z - zr) / fn. That
            // height is known to about kRimHeightRounding of its terms, so where fn is small
            // enough for this to pass kParam in u (a tiny move nearly across the axis: fn at
            // rounding level makes u anything), u is taken in the rim's plane instead: the circle
            // centred at u fd on the d axis passes through the point where
            //   u = (x -+ sqrt(r^2 - y^2)) / fd   (x, y the point's d and e coordinates),
            // and of the two the one nearer the axial row's is the one it gives. Where that choice
            // is unsure, the two points of the rim lie within the height's rounding of each
            // other, so either answer is right to that.
            const auto feedAt = [&](double v, const Circle& rim) {
                const double height = o.z + v * w.z - rim.z;
                const double u = height * invFn_;
                const double rounding = kRimHeightRounding * (std::abs(o.z) + std::abs(v * w.z) + std::abs(rim.z));
                if (!(rounding * std::abs(invFn_) > sweep_tol::kParam) || fd == 0.0) return u;
                const double x = o.x + v * w.x, y = o.y + v * w.y;
                const double half = std::sqrt(std::max(0.0, rim.r * rim.r - y * y));
                const double u0 = (x - half) / fd, u1 = (x + half) / fd;
                return std::abs(u0 - u) <= std::abs(u1 - u) ? u0 : u1;
            };
            const double kappa2 = kappa_ * kappa_;
            const double oq = glm::dot(o, qDir_), wq = glm::dot(w, qDir_);
            const double a = kappa2 * w.y * w.y + wq * wq;
            const double invA = 1.0 / a;
            for (const Circle& rim : part.rims) {
                const double dq = oq - rim.qc;
                const double cross = o.y * wq - w.y * dq;
                const double disc = rim.r * rim.r * a - cross * cross;
                if (disc < 0.0 || a == 0.0) continue;
                const double b = kappa2 * o.y * w.y + dq * wq;
                const double c = kappa2 * (o.y * o.y - rim.r * rim.r) + dq * dq;
                const double qq = -(b + std::copysign(kappa_ * std::sqrt(disc), b));
                const double roots[2] = {qq * invA, qq != 0.0 ? c / qq : qq * invA};
                const Source src = Source::of(Source::Rim, std::uint32_t(&rim - part.rims.data()));
                for (double v : roots) ex.add(v, feedAt(v, rim), src);
            }
        }
    }

    if (ex.empty()) return Interval::empty();  // the line misses the shadow cylinder
    // Each end: the boundary crossing when a tool pose in the move puts it there, otherwise the
    // static tool at the nearer end of the move.
    Interval statics[2];
    bool have[2] = {false, false};
    auto staticAt = [&](int end) -> const Interval& {
        if (!have[end]) {
            statics[end] = staticPart(part, end ? o - feedLocal_ : o, w);
            have[end] = true;
        }
        return statics[end];
    };
    Interval out;
    if (ex.hiU1 >= 0.0 && ex.hiU0 <= 1.0) {
        out.hi = ex.vHi;
        if constexpr (kTrace) trace->hi.pose = -1, trace->hi.u0 = ex.hiU0, trace->hi.u1 = ex.hiU1;
    } else {
        const int pose = ex.hiU0 > 1.0 ? 1 : 0;
        const Interval& s = staticAt(pose);
        if (s.isEmpty()) return s;
        out.hi = s.hi;
        if constexpr (kTrace) trace->hi.pose = pose;
    }
    if (ex.loU1 >= 0.0 && ex.loU0 <= 1.0) {
        out.lo = ex.vLo;
        if constexpr (kTrace) trace->lo.pose = -1, trace->lo.u0 = ex.loU0, trace->lo.u1 = ex.loU1;
    } else {
        const int pose = ex.loU0 > 1.0 ? 1 : 0;
        const Interval& s = staticAt(pose);
        if (s.isEmpty()) return s;
        out.lo = s.lo;
        if constexpr (kTrace) trace->lo.pose = pose;
    }
    return out;
}

// The box holds the sweep loosely where it is round: a line may pass a corner of the box beside
// the tool (a fifth of the box's cross-section about a cylinder). At feed parameter s the part
// lies within rMax of its axis through the tip at s (fd, 0, fn), at heights z with z - s fn in
// [z0, z1]. So the sweep lies where z is in [z0 + min(0, fn), z1 + max(0, fn)] and (d, e) within
// rMax of the segment from (0, 0) to (fd, 0): the line's stretch at those heights must come
// that near the segment.
Interval MoveSweep::roundBound(const Part& part, Interval range, const Vec3& o, const Vec3& w, double invWz) const {
    const double zLo = part.z0 + std::min(0.0, feedLocal_.z) - sweep_tol::kBoxSlack - o.z;
    const double zHi = part.z1 + std::max(0.0, feedLocal_.z) + sweep_tol::kBoxSlack - o.z;
    if (w.z == 0.0) {
        if (zLo > 0.0 || zHi < 0.0) return Interval::empty();
    } else {
        const double v0 = zLo * invWz, v1 = zHi * invWz;
        range = range.intersect(w.z > 0.0 ? Interval{v0, v1} : Interval{v1, v0});
        if (range.isEmpty()) return range;
    }
    const double reach = part.rMax + sweep_tol::kBoxSlack;
    if (!segmentsNear(o.x + range.lo * w.x, o.y + range.lo * w.y, o.x + range.hi * w.x, o.y + range.hi * w.y,
                      feedLocal_.x, reach * reach))
        return Interval::empty();
    return range;
}

// The slabs of boxLocal in world coordinates: with a = rel + vShift w (toLocal), q.o . b_i =
// a . W_i and q.w . b_i = w . W_i, W_i the box axis b_i in the world, so each slab's range in the
// line's own parameter is the local one shifted by vShift. So a line is tested without its frame,
// which only a line that meets a box needs (most of a move's window misses it). A line along the
// tool axis takes bound(LocalLine)'s narrower range.
template <bool kRound>
Interval MoveSweep::boxBound(const Line& line) const {
    const Vec3& w = line.dir;
    if (kind_ != SweepKind::Static && glm::dot(w, frame_.d) == 0.0 && glm::dot(w, frame_.e) == 0.0)
        return bound(toLocal(line));
    const Vec3 rel = line.origin - start_;
    double oa[3], wa[3];
    for (int i = 0; i < 3; ++i) oa[i] = glm::dot(rel, worldBoxAxes_[i]), wa[i] = glm::dot(w, worldBoxAxes_[i]);
    // The line in the frame (d, e, n), e being the first box axis, for roundBound: made once a
    // box meets it.
    Vec3 o(0.0), wl(0.0);
    double invWz = 0.0;
    bool framed = false;
    Interval hull;
    for (const Part& part : parts_) {
        Interval range = Interval::all();
        for (int i = 0; i < 3 && !range.isEmpty(); ++i) {
            const double lo = part.box[i].lo - sweep_tol::kBoxSlack - oa[i];
            const double hi = part.box[i].hi + sweep_tol::kBoxSlack - oa[i];
            if (wa[i] == 0.0) {
                if (lo > 0.0 || hi < 0.0) range = Interval::empty();
                continue;
            }
            const double v0 = lo / wa[i], v1 = hi / wa[i];
            range = range.intersect(wa[i] > 0.0 ? Interval{v0, v1} : Interval{v1, v0});
        }
        if constexpr (kRound) {
            if (range.isEmpty()) continue;
            if (!framed) {
                o = Vec3(glm::dot(rel, frame_.d), oa[0], glm::dot(rel, frame_.n));
                wl = Vec3(glm::dot(w, frame_.d), wa[0], glm::dot(w, frame_.n));
                invWz = wl.z == 0.0 ? 0.0 : 1.0 / wl.z;
                framed = true;
            }
            range = roundBound(part, range, o, wl, invWz);
        }
        hull = hull.hull(range);
    }
    return hull;
}

Interval MoveSweep::bound(const Line& line) const {
    return boxBound<false>(line);
}

Interval MoveSweep::narrowBound(const Line& line) const {
    return boxBound<true>(line);
}

Interval MoveSweep::narrowBound(const Line& line, const Interval& within) const {
    if (!std::isfinite(within.lo) || !std::isfinite(within.hi)) return narrowBound(line).intersect(within);
    const Vec3 rel = line.origin - start_;
    const Vec3& w = line.dir;
    const Vec3 o(glm::dot(rel, frame_.d), glm::dot(rel, frame_.e), glm::dot(rel, frame_.n));
    const Vec3 wl(glm::dot(w, frame_.d), glm::dot(w, frame_.e), glm::dot(w, frame_.n));
    const double invWz = wl.z == 0.0 ? 0.0 : 1.0 / wl.z;
    Interval hull;
    for (const Part& part : parts_) hull = hull.hull(roundBound(part, within, o, wl, invWz));
    return hull;
}

Interval MoveSweep::bound(const LocalLine& q) const {
    Interval hull;
    for (const Part& part : parts_) {
        Interval range = boxLocal(part, q);
        if (range.isEmpty()) continue;
        if (q.w.x == 0.0 && q.w.y == 0.0 && kind_ != SweepKind::Static) {
            // A line along the axis: at distance r from the axis of the tool at u, it is inside
            // that tool only where R(z) >= r. r is at least the distance rMin from the swept axis,
            // and {z : R(z) >= rMin} is one interval [zLo, zHi] (R is concave on a part), so the
            // line is inside the sweep only at heights [zLo + min(0, fn), zHi + max(0, fn)].
            const double fd = feedLocal_.x, fn = feedLocal_.z;
            const double x = std::clamp(q.o.x, std::min(0.0, fd), std::max(0.0, fd));
            const double dx = q.o.x - x;  // mm-sized: no need for hypot's overflow care
            const double rMin = std::sqrt(dx * dx + q.o.y * q.o.y) - sweep_tol::kBoxSlack;
            const Interval z = part.widerThan(rMin);
            if (z.isEmpty()) continue;
            const double zLo = z.lo + std::min(0.0, fn) - sweep_tol::kBoxSlack;
            const double zHi = z.hi + std::max(0.0, fn) + sweep_tol::kBoxSlack;
            const double v0 = (zLo - q.o.z) / q.w.z, v1 = (zHi - q.o.z) / q.w.z;
            range = range.intersect(q.w.z > 0.0 ? Interval{v0, v1} : Interval{v1, v0});
            if (range.isEmpty()) continue;
        }
        hull = hull.hull(range);
    }
    if (hull.isEmpty()) return hull;
    return {hull.lo + q.vShift, hull.hi + q.vShift};
}

std::size_t MoveSweep::intersectParts(const Line& line, Interval* out) const {
    return intersectParts(toLocal(line), out);
}

std::size_t MoveSweep::intersectParts(const LocalLine& q, Interval* out) const {
    for (std::size_t i = 0; i < parts_.size(); ++i) {
        const Interval iv = intersectLocal<false>(parts_[i], q, nullptr);
        out[i] = iv.isEmpty() ? Interval::empty() : Interval{iv.lo + q.vShift, iv.hi + q.vShift};
    }
    return parts_.size();
}

std::size_t MoveSweep::intersectParts(const Line& line, LineHit* out) const {
    return intersectParts(line, out, [](std::size_t, const Interval&) { return kEndLo | kEndHi; });
}

std::size_t MoveSweep::intersectParts(const Line& line, LineHit* out, const EndFilter& wanted) const {
    return intersectParts(toLocal(line), out, wanted);
}

std::size_t MoveSweep::intersectParts(const LocalLine& q, LineHit* out, const EndFilter& wanted) const {
    for (std::size_t i = 0; i < parts_.size(); ++i) {
        EndTrace trace;
        const Interval iv = intersectLocal<true>(parts_[i], q, &trace);
        LineHit& hit = out[i];
        hit = LineHit{};
        if (iv.isEmpty()) continue;
        hit.range = {iv.lo + q.vShift, iv.hi + q.vShift};
        const unsigned ends = wanted(i, hit.range);
        if (ends) hermite(i, q, iv, trace, ends, hit);
    }
    return parts_.size();
}

MoveSweep::EndPoses MoveSweep::endPoses(const Line& line, std::size_t index) const {
    const LocalLine q = toLocal(line);
    EndTrace trace;
    const Interval iv = intersectLocal<true>(parts_[index], q, &trace);
    EndPoses out;
    if (iv.isEmpty()) return out;
    out.range = {iv.lo + q.vShift, iv.hi + q.vShift};
    const auto at = [](const EndTrace::End& end) {
        return end.pose >= 0 ? double(end.pose) : std::clamp(0.5 * (end.u0 + end.u1), 0.0, 1.0);
    };
    out.uLo = at(trace.lo);
    out.uHi = at(trace.hi);
    return out;
}

Interval MoveSweep::intersect(const Line& line) const {
    if (parts_.size() == 1) {
        const LocalLine q = toLocal(line);
        const Interval iv = intersectLocal<false>(parts_[0], q, nullptr);
        return iv.isEmpty() ? Interval::empty() : Interval{iv.lo + q.vShift, iv.hi + q.vShift};
    }
    Interval parts[kMaxParts];
    const std::size_t n = intersectParts(line, parts);
    Interval hull;
    for (std::size_t i = 0; i < n; ++i) hull = hull.hull(parts[i]);
    return hull;
}

std::vector<Interval> MoveSweep::intersectAll(const Line& line) const {
    Interval parts[kMaxParts];
    const std::size_t n = intersectParts(line, parts);
    std::vector<Interval> ivs;
    for (std::size_t i = 0; i < n; ++i)
        if (!parts[i].isEmpty()) ivs.push_back(parts[i]);
    std::sort(ivs.begin(), ivs.end(), [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
    std::vector<Interval> merged;
    for (const Interval& iv : ivs) {
        if (!merged.empty() && iv.lo <= merged.back().hi) merged.back().hi = std::max(merged.back().hi, iv.hi);
        else merged.push_back(iv);
    }
    return merged;
}

}  // namespace dexelmill
