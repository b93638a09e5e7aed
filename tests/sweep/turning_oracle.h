// The brute-force oracle for moves whose tool axis turns (TurningSweep), and its random cases,
// shared by turning_sweep_oracle_test.cpp (membership: checks 0 to 2) and turning_normals_test.cpp
// (Hermite data). It shares no code with the solver: the tool is the oracle's own description of it
// (tool_models.h: convex parts, each heights [za, zb] above the tip and a concave radius function
// R(z)), and the motion law is re-derived here from the Move.
//
// The oracle for a move whose tool axis turns. Why its certificates hold:
//  (a) Meridian distance. The tool is a solid of revolution, so a point's distance to a part (or,
//      from inside, to the part's complement) equals the distance in its meridian half-plane,
//      coordinates (z, rho), from the point (z, rho) to the part's meridian boundary: the bottom
//      face z = za, the curve rho = R(z), the top face z = zb. (For a tool point y in another
//      meridian, |x - y| only shrinks when y is turned about the axis into x's half-plane.) Per
//      part is conservative for the union of parts: a depth inside one part is a lower bound of
//      the depth inside the union, and a distance to the union is the least over the parts.
//  (b) Sampled curve. The curve is sampled at heights z_k. R is concave, so on [z_k, z_k+1] the
//      curve lies above its chord and below the extensions of both neighbouring chords (the
//      vertical lines z = za and z = zb standing in for the missing neighbours at the ends): in a
//      triangle on the chord, whose height err_k bounds the curve's distance from the chord. So
//      the distance to the boundary is at least min_k (distance to chord k - err_k). The samples
//      are refined until every err_k <= kMaxChordError; concavity is checked on the samples.
//  (c) Windows. A boundary point within w of (z, rho) has its height within w of z, so only the
//      chords whose height range meets [z - w, z + w] can be nearer than w: the distance is at
//      least min(w, their bound).
//  (d) Speed. The pose is p(u) = start + u f, a(u) = a0 cos(theta u) + b sin(theta u): the turn
//      by theta u about k = a0 x b, so T(u) is the image of T(0) under a rigid motion and a tool
//      point y moves at y' = f + theta k x (y - p), |y'| <= V = |f| + theta * reach (reach: the
//      largest distance of a tool point from the tip, from the samples and their errors). So the
//      distance from x to T(u) and x's depth inside T(u) both change by at most V |du|.
//  (e) certainlyOutside is a branch and bound over u. A node [ua, ub] is settled when x is far enough
//      outside T at both ends that no pose within half its width h of an end comes within
//      kRounding: by (d), a clearance of kRounding + V h is enough. A sharper bound serves points
//      near the line through the tip along k, about which the turn is (for them the distance
//      hardly changes with u while V is large): a tool point y that comes within D of x (D a
//      lower bound of x's distance from T(ue)) between ue and u moves, while within D of x, at
//      |f| + theta * (its distance from that line) <= |f| + theta (rhoK + |f| h + D), rhoK being
//      x's distance from the line at ue (the line moves with the tip). To get from distance D to
//      kRounding it must travel D - kRounding, so a clearance D with
//      D - h (|f| + theta (rhoK + |f| h + D)) >= kRounding is also enough. x is certainly
//      outside S when every node settles; the search gives up (passes) as soon as some node end
//      has x within kRounding of T, which no refinement can settle since the end stays an end,
//      or at kMaxLevel or kNodeBudget. Its weak spot: near a surface that slides along itself
//      (the side of a tool moving along its axis) the distance stays d at every pose, and
//      settling takes about V / (2 d) nodes, so it decides such points only for d >~ V / 2e5.
//  (f) deepWitness looks for a witness pose: a grid over u and a golden-section refinement of a
//      cheap guide (the least of z - za, zb - z and R(z) - rho); only the certified depth at
//      the chosen poses, by (a) to (c), can fail the test, so the guide need not be exact. Where
//      the guide's peak is no witness but the guide reaches the depth, the golden-section search
//      is made again on the certified depth itself.
// Whether a point is inside a part at all is decided exactly, from R itself; the samples only
// bound distances. The oracle is itself tested first, without the solver: against closed forms
// (a ball on a line, a ball turning in place, a cylinder plunging) and against oracle.h's
// fixed-axis oracle on every tool kind.
#pragma once

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dexelmill/sweep/turning.h"
#include "oracle.h"
#include "oracle_cases.h"
#include "tool_models.h"

namespace turning_oracle {

using namespace dexelmill;

constexpr double kPi = 3.14159265358979323846;

/// The solver's admitted rounding, as a distance (mm): its output ends are ends of exact
/// static-pose intervals computed in double precision with coordinates below 100 mm, whose error
/// as a distance from the tool's surface is ~1e-13 mm (a root near a tangency moves along the
/// line by more, but along the surface, so the distance error stays at the rounding level). The
/// oracle's own rounding (pose, meridian coordinates) is of the same order. 1e-7 leaves a factor
/// of 1e5 to both.
constexpr double kRounding = 1e-7;
/// The largest distance (mm) of the sampled meridian curve from its chords ((b)): the band near
/// a curved surface within which the oracle cannot certify anything.
constexpr double kMaxChordError = 2e-6;
/// Samples of each part's curve before refinement: Chebyshev heights, dense near za and zb where
/// a ball's slope is unbounded.
constexpr int kInitialSamples = 64;
/// A refinement that needs more samples than this means the model is not what (b) assumes.
constexpr std::size_t kMaxSamples = 200000;
/// Rounding of the chords' directions (atan2 of differences of R values up to ~50 mm over height
/// steps down to ~1e-5 mm: ~1e-9 rad at worst). A chord turning the wrong way by less than this is
/// taken as straight; the curve's distance from it is then off by at most its length times this,
/// < 1e-10 mm, far below kRounding. A larger turn the wrong way fails the test: R is not concave.
constexpr double kConcavityTolerance = 1e-8;
/// The widest window (c) (mm): bounds the cost of one distance; a node needing more subdivides.
constexpr double kMaxWindow = 2.0;
/// Branch and bound of check 1: depth and node limits, beyond which it passes undecided. At level
/// 40 a node's half width times V (< 300 mm per unit u here) is below 3e-10 mm.
constexpr int kMaxLevel = 40;
constexpr int kNodeBudget = 100000;
/// Check 2's search: grid poses, then golden-section steps around the best.
constexpr int kPoseGrid = 128;
constexpr int kGoldenSteps = 48;

/// Rodrigues' rotation of `v` by `angle` about the unit vector `about`.
inline Vec3 rotated(const Vec3& v, const Vec3& about, double angle) {
    return v * std::cos(angle) + glm::cross(about, v) * std::sin(angle) +
           about * glm::dot(about, v) * (1.0 - std::cos(angle));
}

/// Distance in the plane from (z, r) to the segment from (z0, r0) to (z1, r1).
inline double segmentDistance(double z, double r, double z0, double r0, double z1, double r1) {
    const double dz = z1 - z0, dr = r1 - r0, len2 = dz * dz + dr * dr;
    const double s = len2 > 0.0 ? std::clamp(((z - z0) * dz + (r - r0) * dr) / len2, 0.0, 1.0) : 0.0;
    return std::hypot(z - (z0 + s * dz), r - (r0 + s * dr));
}

/// One convex part's meridian boundary, sampled with certified chord errors ((b)).
struct Profile {
    oracle::Part part;
    std::vector<double> z, r;  ///< samples of the curve, z ascending from za to zb
    std::vector<double> err;   ///< err[k]: the curve's largest distance from chord k
    double rMax = 0.0;         ///< a bound on R: largest sample plus largest error

    explicit Profile(const oracle::Part& p) : part(p) {
        for (int k = 0; k <= kInitialSamples; ++k)
            z.push_back(p.za + (p.zb - p.za) * 0.5 * (1.0 - std::cos(kPi * k / kInitialSamples)));
        z.front() = p.za, z.back() = p.zb;
        for (;;) {
            r.clear();
            for (double h : z) r.push_back(p.radius(h));
            bounds();
            std::vector<double> finer{z.front()};
            for (std::size_t k = 0; k + 1 < z.size(); ++k) {
                if (err[k] > kMaxChordError) finer.push_back(0.5 * (z[k] + z[k + 1]));
                finer.push_back(z[k + 1]);
            }
            if (finer.size() == z.size()) break;
            if (finer.size() > kMaxSamples) throw std::logic_error("profile refinement does not converge");
            z = std::move(finer);
        }
        rMax = 0.0;
        for (std::size_t k = 0; k < r.size(); ++k) rMax = std::max(rMax, r[k] + (k < err.size() ? err[k] : 0.0));
    }

    /// The chord errors: the height of the triangle on chord k between the neighbouring chords'
    /// extensions, c sin(a1) sin(a2) / sin(a1 + a2) for turning angles a1, a2 at its two ends.
    void bounds() {
        const std::size_t n = z.size() - 1;
        std::vector<double> phi(n);
        for (std::size_t k = 0; k < n; ++k) phi[k] = std::atan2(r[k + 1] - r[k], z[k + 1] - z[k]);
        err.assign(n, 0.0);
        for (std::size_t k = 0; k < n; ++k) {
            const double before = k > 0 ? phi[k - 1] : kPi / 2, after = k + 1 < n ? phi[k + 1] : -kPi / 2;
            double a1 = before - phi[k], a2 = phi[k] - after;
            if (a1 < -kConcavityTolerance || a2 < -kConcavityTolerance)
                throw std::logic_error("oracle part radius is not concave near z = " + std::to_string(z[k]));
            a1 = std::max(a1, 0.0), a2 = std::max(a2, 0.0);
            const double c = std::hypot(z[k + 1] - z[k], r[k + 1] - r[k]);
            if (a1 > 0.0 && a2 > 0.0)
                err[k] = a1 + a2 >= kPi ? oracle::kInf : c * std::sin(a1) * std::sin(a2) / std::sin(a1 + a2);
        }
    }

    /// Signed clearance of the meridian point (z, rho), capped at `cap`: > 0, x is at least that
    /// deep inside the part; < 0, at least that far outside; 0 says nothing.
    double clearance(double zq, double rho, double cap) const {
        const bool inside = zq >= part.za && zq <= part.zb && rho <= part.radius(zq);
        const double w = std::min(cap, kMaxWindow);
        // Every boundary point has za <= z <= zb and rho <= rMax.
        if (std::max({part.za - zq, zq - part.zb, rho - rMax}) >= w) return inside ? w : -w;
        double d = w;
        if (std::abs(zq - part.za) <= w) d = std::min(d, segmentDistance(zq, rho, part.za, 0.0, z.front(), r.front()));
        if (std::abs(zq - part.zb) <= w) d = std::min(d, segmentDistance(zq, rho, part.zb, 0.0, z.back(), r.back()));
        // Chords k with [z_k, z_k+1] meeting [zq - w, zq + w].
        const auto lo = std::lower_bound(z.begin(), z.end(), zq - w);
        const auto hi = std::upper_bound(z.begin(), z.end(), zq + w);
        const std::size_t k0 = lo == z.begin() ? 0 : std::size_t(lo - z.begin()) - 1;
        const std::size_t k1 = std::min(std::size_t(hi - z.begin()), err.size());
        for (std::size_t k = k0; k < k1; ++k)
            d = std::min(d, segmentDistance(zq, rho, z[k], r[k], z[k + 1], r[k + 1]) - err[k]);
        d = std::max(d, 0.0);
        return inside ? d : -d;
    }

    /// The guide of (f): positive inside, growing with depth; no bound on anything.
    double guide(double zq, double rho) const {
        return std::min({zq - part.za, part.zb - zq, part.radius(std::clamp(zq, part.za, part.zb)) - rho});
    }
};

/// The last two points of a golden-section search and f there.
struct Golden {
    double x1, g1, x2, g2;
};

/// Golden-section search for the largest f on [a, b]: `steps` steps, or fewer where `done`
/// accepts the points so far.
template <class F, class Done>
Golden goldenPeak(F&& f, double a, double b, Done&& done, int steps = kGoldenSteps) {
    const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
    Golden g{b - ratio * (b - a), 0.0, a + ratio * (b - a), 0.0};
    g.g1 = f(g.x1), g.g2 = f(g.x2);
    for (int i = 0; i < steps && !done(g); ++i) {
        if (g.g1 >= g.g2) {
            b = g.x2, g.x2 = g.x1, g.g2 = g.g1;
            g.x1 = b - ratio * (b - a), g.g1 = f(g.x1);
        } else {
            a = g.x1, g.x1 = g.x2, g.g1 = g.g2;
            g.x2 = a + ratio * (b - a), g.g2 = f(g.x2);
        }
    }
    return g;
}

/// The oracle for one tool on one move.
class SweepOracle {
  public:
    SweepOracle(const std::vector<oracle::Part>& parts, const Move& m) : start_(m.start), feed_(m.end - m.start) {
        for (const oracle::Part& p : parts) {
            profiles_.emplace_back(p);
            reach_ = std::max(reach_, std::hypot(std::max(std::abs(p.za), std::abs(p.zb)), profiles_.back().rMax));
        }
        a0_ = m.startAxis ? *m.startAxis : m.axis;
        const Vec3 across = m.axis - glm::dot(m.axis, a0_) * a0_;
        theta_ = std::atan2(glm::length(glm::cross(a0_, m.axis)), glm::dot(a0_, m.axis));
        if (theta_ > 0.0) b_ = across / glm::length(across), k_ = glm::cross(a0_, b_);
        speed_ = glm::length(feed_) + theta_ * reach_;
    }

    double speed() const { return speed_; }
    /// The largest distance of a tool point from the tip.
    double reach() const { return reach_; }

    /// The tip and unit axis at u.
    void pose(double u, Vec3& tip, Vec3& axis) const {
        tip = start_ + u * feed_;
        axis = theta_ > 0.0 ? a0_ * std::cos(theta_ * u) + b_ * std::sin(theta_ * u) : a0_;
    }

    /// Signed clearance of x from T(u), capped at `cap` (per part, (a)).
    double clearance(const Vec3& x, double u, double cap) const {
        Vec3 tip, axis;
        pose(u, tip, axis);
        const Vec3 d = x - tip;
        const double zq = glm::dot(d, axis), rho = glm::length(glm::cross(d, axis));
        double best = -oracle::kInf;
        for (const Profile& p : profiles_) best = std::max(best, p.clearance(zq, rho, cap));
        return best;
    }

    double guide(const Vec3& x, double u) const {
        Vec3 tip, axis;
        pose(u, tip, axis);
        const Vec3 d = x - tip;
        const double zq = glm::dot(d, axis), rho = glm::length(glm::cross(d, axis));
        double best = -oracle::kInf;
        for (const Profile& p : profiles_) best = std::max(best, p.guide(zq, rho));
        return best;
    }

    /// Check 1's certificate (e): x is farther than `margin` from every T(u).
    bool certainlyOutside(const Vec3& x, double margin = kRounding) const {
        // Whether x is at least margin outside T at every pose within `half` of u ((e)).
        auto settled = [&](double u, double half) {
            Vec3 tip, axis;
            pose(u, tip, axis);
            const double rhoK = glm::length(glm::cross(k_, x - tip)), f = glm::length(feed_);
            const double local = theta_ * half < 1.0
                                     ? (margin + half * (f + theta_ * (rhoK + f * half))) / (1.0 - theta_ * half)
                                     : oracle::kInf;
            const double need = std::min(margin + half * speed_, local);
            return clearance(x, u, need) <= -need;
        };
        if (!settled(0.0, 0.0) || !settled(1.0, 0.0)) return false;
        struct Node {
            double ua, ub;
            int level;
        };
        std::vector<Node> stack{{0.0, 1.0, 0}};
        int nodes = 0;
        while (!stack.empty()) {
            const Node n = stack.back();
            stack.pop_back();
            const double half = 0.5 * (n.ub - n.ua);
            if (settled(n.ua, half) && settled(n.ub, half)) continue;
            if (n.level == kMaxLevel || ++nodes > kNodeBudget) return false;
            const double um = 0.5 * (n.ua + n.ub);
            if (!settled(um, 0.0)) return false;
            stack.push_back({n.ua, um, n.level + 1});
            stack.push_back({um, n.ub, n.level + 1});
        }
        return true;
    }

    /// Check 2's witness (f): a pose u at which x is certified deeper than `depth` inside T(u).
    std::optional<double> deepWitness(const Vec3& x, double depth) const {
        int best = 0;
        double bestGuide = -oracle::kInf;
        for (int j = 0; j <= kPoseGrid; ++j) {
            const double g = guide(x, double(j) / kPoseGrid);
            if (g > bestGuide) bestGuide = g, best = j;
        }
        const double a = double(std::max(best - 1, 0)) / kPoseGrid, b = double(std::min(best + 1, kPoseGrid)) / kPoseGrid;
        const Golden byGuide = goldenPeak([&](double u) { return guide(x, u); }, a, b, [](const Golden&) { return false; });
        for (double u : {double(best) / kPoseGrid, byGuide.g1 >= byGuide.g2 ? byGuide.x1 : byGuide.x2})
            if (clearance(x, u, depth) >= depth) return u;
        // The guide is at least the depth (each of its terms is a distance to the boundary), so
        // where its peak stays below `depth`, no pose near it is a witness. Where not, the peak
        // may lie off the depth's (near a ball's pole the distance to the top plane is far more
        // than the depth): a golden-section search of the certified clearance over the same cells.
        if (std::max(byGuide.g1, byGuide.g2) < depth && bestGuide < depth) return std::nullopt;
        const Golden byDepth = goldenPeak([&](double u) { return clearance(x, u, depth); }, a, b,
                                          [depth](const Golden& g) { return std::max(g.g1, g.g2) >= depth; });
        if (byDepth.g1 >= depth) return byDepth.x1;
        if (byDepth.g2 >= depth) return byDepth.x2;
        return std::nullopt;
    }

    /// The line parameters where the line comes within `reach` of the tip's segment: S's whole
    /// extent along the line.
    Interval lineRange(const Line& line) const {
        const double t0 = glm::dot(start_ - line.origin, line.dir), t1 = t0 + glm::dot(feed_, line.dir);
        return {std::min(t0, t1) - reach_, std::max(t0, t1) + reach_};
    }

    /// For a report: the largest clearance of x over a fine grid of poses, capped at 10 mm.
    std::string nearest(const Vec3& x) const {
        constexpr int kReportGrid = 4096;
        constexpr double kReportCap = 10.0;
        double best = -oracle::kInf, at = 0.0;
        for (int j = 0; j <= kReportGrid; ++j) {
            const double c = clearance(x, double(j) / kReportGrid, kReportCap);
            if (c > best) best = c, at = double(j) / kReportGrid;
        }
        std::ostringstream s;
        s << std::setprecision(10) << "largest certified clearance on a 4096-pose grid " << best << " mm at u = " << at
          << " (V = " << speed_ << ")";
        return s.str();
    }

  private:
    std::vector<Profile> profiles_;
    Vec3 start_, feed_, a0_, b_{0.0}, k_{0.0};
    double theta_ = 0.0, reach_ = 0.0, speed_ = 0.0;
};

// ---- Cases ----------------------------------------------------------------------------------

struct Case {
    models::Kind kind = models::Kind::Flat;
    std::optional<models::Model> model;
    Move move;
    Line line;
    double epsilon = kDefaultTurnTolerance;
};

inline std::string describe(const Case& c) {
    std::ostringstream s;
    s << std::setprecision(17) << models::name(c.kind) << " " << cases::str(c.model->tool) << "\n   move start "
      << cases::str(c.move.start) << " end " << cases::str(c.move.end) << " axis " << cases::str(c.move.axis)
      << " startAxis " << (c.move.startAxis ? cases::str(*c.move.startAxis) : std::string("none")) << "\n   line origin "
      << cases::str(c.line.origin) << " dir " << cases::str(c.line.dir) << " epsilon " << c.epsilon;
    return s.str();
}

/// Tolerances a case draws from: the default and two coarser ones, where a too-weak bound in the
/// solver's search would skip more.
inline double randomEpsilon(std::mt19937_64& rng) {
    const double choices[] = {kDefaultTurnTolerance, 1e-3, 1e-2};
    return choices[rng() % 3];
}

/// A random move from near the origin, the start axis `angle` from the end axis (none if
/// `fixed`), the tip travelling `travel` mm in a random direction.
inline Move randomMove(std::mt19937_64& rng, double angle, double travel, bool fixed = false) {
    Move m;
    m.start = Vec3(cases::uniform(rng, -20, 20), cases::uniform(rng, -20, 20), cases::uniform(rng, -20, 20));
    m.end = m.start + travel * cases::randomUnit(rng);
    m.axis = cases::randomUnit(rng);
    if (!fixed) m.startAxis = glm::normalize(rotated(m.axis, cases::randomPerpendicular(rng, m.axis), angle));
    return m;
}

/// A random line through a point at or near the tool at a random pose: along a dexel direction
/// (+-x, +-y, +-z) if `dexel`, else along a random direction or, every other time, a dexel one.
inline Line randomLine(std::mt19937_64& rng, const models::Model& model, const Move& m, bool dexel) {
    const SweepOracle o(model.parts, m);
    Vec3 tip, axis;
    o.pose(cases::uniform(rng, 0, 1), tip, axis);
    const oracle::Part& part = model.parts[rng() % model.parts.size()];
    const double z = cases::uniform(rng, part.za - 1.0, part.zb + 1.0);
    const double rho = part.radius(std::clamp(z, part.za, part.zb)) * cases::uniform(rng, 0.0, 1.3);
    const Vec3 point = tip + z * axis + rho * cases::randomPerpendicular(rng, axis);
    Vec3 dir;
    if (!dexel && rng() % 2) {
        dir = cases::randomUnit(rng);
    } else {
        dir = Vec3(0.0);
        dir[int(rng() % 3)] = rng() % 2 ? 1.0 : -1.0;
    }
    return Line{point - cases::uniform(rng, -30, 30) * dir, dir};
}

inline Case randomCase(std::mt19937_64& rng, const Move& move, bool dexel = false) {
    Case c;
    c.kind = models::Kind(rng() % int(models::Kind::Count));
    c.model.emplace(models::make(c.kind, rng));
    c.move = move;
    c.line = randomLine(rng, *c.model, move, dexel);
    c.epsilon = randomEpsilon(rng);
    return c;
}

inline int scaled(int count) { return std::max(1, int(count * oracle::testScale())); }

inline double degrees(double d) { return d * kPi / 180.0; }

}  // namespace turning_oracle
