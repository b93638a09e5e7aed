// TurningSweep (a move whose tool axis turns) against a brute-force oracle that shares no code
// with the solver: the tool is the oracle's own description of it (tool_models.h: convex parts,
// each heights [za, zb] above the tip and a concave radius function R(z)), and the motion law is
// re-derived here from the Move. Fixed seeds; case counts scale with DEXELMILL_TEST_SCALE.
//
// What is checked, for a unit-direction line and the union O of sweep.intersectAll(line):
//  0. O is sorted and disjoint, and bound(line) holds every interval of it.
//  1. O lies within eps of S: no output point (both ends of each interval and three inner points)
//     is certainly farther than eps + kRounding from S. (The sweep joins two of its intervals
//     where the gap between them lies within eps of its poses; elsewhere O is inside S.)
//  2. Every point of the line deeper than eps inside some T(u) lies in O: no test point outside O
//     (a grid along the line and points just beyond each end of O) has a pose u at which the
//     oracle certifies it deeper than eps + kRounding.
// Both checks fail only on a certificate, so the oracle can never fail a correct solver; where it
// cannot decide, it passes.
//
// Why the certificates hold:
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
//  (e) Check 1 is a branch and bound over u. A node [ua, ub] is settled when x is far enough
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
//  (f) Check 2 looks for a witness pose: a grid over u and a golden-section refinement of a
//      cheap guide (the least of z - za, zb - z and R(z) - rho); only the certified depth at
//      the chosen poses, by (a) to (c), can fail the test, so the guide need not be exact.
// Whether a point is inside a part at all is decided exactly, from R itself; the samples only
// bound distances. The oracle is itself tested first, without the solver: against closed forms
// (a ball on a line, a ball turning in place, a cylinder plunging) and against oracle.h's
// fixed-axis oracle on every tool kind.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/sweep/turning.h"
#include "oracle.h"
#include "oracle_cases.h"
#include "tool_models.h"

using namespace dexelmill;

namespace {

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
Vec3 rotated(const Vec3& v, const Vec3& about, double angle) {
    return v * std::cos(angle) + glm::cross(about, v) * std::sin(angle) +
           about * glm::dot(about, v) * (1.0 - std::cos(angle));
}

/// Distance in the plane from (z, r) to the segment from (z0, r0) to (z1, r1).
double segmentDistance(double z, double r, double z0, double r0, double z1, double r1) {
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
        const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
        double a = double(std::max(best - 1, 0)) / kPoseGrid, b = double(std::min(best + 1, kPoseGrid)) / kPoseGrid;
        double x1 = b - ratio * (b - a), x2 = a + ratio * (b - a);
        double g1 = guide(x, x1), g2 = guide(x, x2);
        for (int i = 0; i < kGoldenSteps; ++i) {
            if (g1 >= g2) {
                b = x2, x2 = x1, g2 = g1;
                x1 = b - ratio * (b - a), g1 = guide(x, x1);
            } else {
                a = x1, x1 = x2, g1 = g2;
                x2 = a + ratio * (b - a), g2 = guide(x, x2);
            }
        }
        for (double u : {double(best) / kPoseGrid, g1 >= g2 ? x1 : x2})
            if (clearance(x, u, depth) >= depth) return u;
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

std::string describe(const Case& c) {
    std::ostringstream s;
    s << std::setprecision(17) << models::name(c.kind) << " " << cases::str(c.model->tool) << "\n   move start "
      << cases::str(c.move.start) << " end " << cases::str(c.move.end) << " axis " << cases::str(c.move.axis)
      << " startAxis " << (c.move.startAxis ? cases::str(*c.move.startAxis) : std::string("none")) << "\n   line origin "
      << cases::str(c.line.origin) << " dir " << cases::str(c.line.dir) << " epsilon " << c.epsilon;
    return s.str();
}

/// Tolerances a case draws from: the default and two coarser ones, where a too-weak bound in the
/// solver's search would skip more.
double randomEpsilon(std::mt19937_64& rng) {
    const double choices[] = {kDefaultTurnTolerance, 1e-3, 1e-2};
    return choices[rng() % 3];
}

/// A random move from near the origin, the start axis `angle` from the end axis (none if
/// `fixed`), the tip travelling `travel` mm in a random direction.
Move randomMove(std::mt19937_64& rng, double angle, double travel, bool fixed = false) {
    Move m;
    m.start = Vec3(cases::uniform(rng, -20, 20), cases::uniform(rng, -20, 20), cases::uniform(rng, -20, 20));
    m.end = m.start + travel * cases::randomUnit(rng);
    m.axis = cases::randomUnit(rng);
    if (!fixed) m.startAxis = glm::normalize(rotated(m.axis, cases::randomPerpendicular(rng, m.axis), angle));
    return m;
}

/// A random line through a point at or near the tool at a random pose: along a dexel direction
/// (+-x, +-y, +-z) if `dexel`, else along a random direction or, every other time, a dexel one.
Line randomLine(std::mt19937_64& rng, const models::Model& model, const Move& m, bool dexel) {
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

Case randomCase(std::mt19937_64& rng, const Move& move, bool dexel = false) {
    Case c;
    c.kind = models::Kind(rng() % int(models::Kind::Count));
    c.model.emplace(models::make(c.kind, rng));
    c.move = move;
    c.line = randomLine(rng, *c.model, move, dexel);
    c.epsilon = randomEpsilon(rng);
    return c;
}

// ---- Checks ---------------------------------------------------------------------------------

struct Tally {
    int cases = 0, hits = 0, failures = 0;
    int linear = 0;  ///< cases the sweep searched by linear nodes (turning.cpp, note h)
    std::string log;

    void fail(const Case& c, const std::string& what) {
        if (++failures <= 5) log += "FAIL case #" + std::to_string(cases - 1) + ": " + what + "\n   " + describe(c) + "\n";
    }
};

/// Offsets (mm) beyond each end of O at which check 2 also looks: where a solver that stops
/// short of the sweep's boundary by more than epsilon leaves deep points.
constexpr double kEndOffsets[] = {2e-4, 1e-3, 1e-2, 1e-1, 1.0};
/// Check 2's grid along the line's reach, and check 1's points inside each interval.
constexpr int kLineGrid = 64;
constexpr double kInnerFractions[] = {0.25, 0.5, 0.75};

/// Runs checks 0 to 2 on one case; returns the solver's output.
std::vector<Interval> checkCase(const Case& c, Tally& tally, std::mt19937_64& rng) {
    ++tally.cases;
    const TurningSweep sweep(c.model->tool, c.move, c.epsilon);
    if (sweep.linearNodes()) ++tally.linear;
    const SweepOracle o(c.model->parts, c.move);
    const std::vector<Interval> out = sweep.intersectAll(c.line);
    if (!out.empty()) ++tally.hits;
    std::ostringstream got;
    got << std::setprecision(17) << "output " << cases::str(out);

    // 0. Structure.
    const Interval bound = sweep.bound(c.line);
    for (std::size_t k = 0; k < out.size(); ++k) {
        if (!(out[k].lo <= out[k].hi) || (k > 0 && !(out[k - 1].hi < out[k].lo)))
            tally.fail(c, "output not sorted and disjoint: " + got.str());
        if (!(bound.lo <= out[k].lo && out[k].hi <= bound.hi)) {
            std::ostringstream s;
            s << std::setprecision(17) << "bound(line) [" << bound.lo << ", " << bound.hi << "] misses an interval: " << got.str();
            tally.fail(c, s.str());
        }
    }

    // 1. O within eps of S (the sweep joins gaps whose points lie within eps of its poses).
    const double margin = sweep.epsilon() + kRounding;
    for (const Interval& iv : out) {
        std::vector<double> ts{iv.lo, iv.hi};
        for (double s : kInnerFractions) ts.push_back(iv.lo + s * (iv.hi - iv.lo));
        for (double t : ts) {
            const Vec3 x = c.line.at(t);
            if (o.certainlyOutside(x, margin)) {
                std::ostringstream s;
                s << std::setprecision(17) << "check 1: output point t = " << t << " is certainly more than " << margin
                  << " mm outside the sweep; " << o.nearest(x) << "; " << got.str();
                tally.fail(c, s.str());
            }
        }
    }

    // 2. Points deeper than epsilon in O.
    auto inO = [&](double t) {
        for (const Interval& iv : out)
            if (iv.contains(t)) return true;
        return false;
    };
    const Interval range = o.lineRange(c.line);
    std::vector<double> ts;
    const double jitter = cases::uniform(rng, 0, 1);
    for (int i = 0; i < kLineGrid; ++i) ts.push_back(range.lo + (i + jitter) / kLineGrid * range.length());
    for (const Interval& iv : out)
        for (double d : kEndOffsets) ts.push_back(iv.lo - d), ts.push_back(iv.hi + d);
    const double depth = sweep.epsilon() + kRounding;
    for (double t : ts) {
        if (inO(t)) continue;
        const Vec3 x = c.line.at(t);
        if (const auto u = o.deepWitness(x, depth)) {
            std::ostringstream s;
            s << std::setprecision(17) << "check 2: t = " << t << " is certified deeper than " << depth
              << " mm inside T(u) at u = " << *u << " but not in the output; " << o.nearest(x) << "; " << got.str();
            tally.fail(c, s.str());
        }
    }
    return out;
}

void report(const Tally& t, bool requireHits = true) {
    INFO(t.cases << " cases (" << t.linear << " by linear nodes), " << t.hits << " with output, " << t.failures
                 << " failures\n" << t.log);
    CHECK(t.failures == 0);
    // The cases must exercise the solver: a good share of the lines meet the sweep.
    if (requireHits) CHECK(t.hits >= t.cases / 4);
}

int scaled(int count) { return std::max(1, int(count * oracle::testScale())); }

double degrees(double d) { return d * kPi / 180.0; }

}  // namespace

// ---- The oracle against closed forms, without the solver --------------------------------------

namespace {

/// A signed offset from a surface: +-10^U(-9, -0.5) mm, so that points fall on both sides at every
/// scale from below kRounding to well clear.
double offset(std::mt19937_64& rng) {
    return (rng() % 2 ? 1.0 : -1.0) * std::pow(10.0, cases::uniform(rng, -9, -0.5));
}

/// Check that the oracle's certificates agree with a known signed distance `exact(x)` (> 0
/// outside S, < 0 inside by the depth in the deepest single pose) at points `near(rng)` around
/// the sweep's surface, and that they are sharp: a point clearly outside (or deep) gets its
/// certificate.
template <class Exact, class Near>
void selfCheck(const std::vector<oracle::Part>& parts, const Move& m, Exact&& exact, Near&& near,
               std::mt19937_64& rng, int points, int& unsound, int& missed, int& decided) {
    const SweepOracle o(parts, m);
    // The closed forms' own rounding, for coordinates below 100 mm.
    constexpr double kExactRounding = 1e-12;
    // Sharpness margins: a point this far outside must be certified (chord error, rounding and
    // the finest node's V w / 2 are all far below), and one this deep must get a witness (the
    // guide's grid and golden search find the deepest pose of these smooth cases to ~1e-6 mm).
    constexpr double kSharpOutside = 1e-5, kSharpDepth = 1e-4;
    constexpr double kDepth = 1e-4;
    for (int i = 0; i < points; ++i) {
        const Vec3 x = near(rng);
        const double e = exact(x);
        const bool outside = o.certainlyOutside(x);
        const bool deep = o.deepWitness(x, kDepth).has_value();
        decided += outside || deep;
        if ((outside && e < kRounding - kExactRounding) || (deep && -e < kDepth - kExactRounding)) ++unsound;
        if ((e > kSharpOutside && !outside) || (-e > kDepth + kSharpDepth && !deep)) ++missed;
    }
}

}  // namespace

TEST_CASE("turning oracle: certificates agree with closed forms (capsule, ball turning in place, plunge)",
          "[sweep][turning]") {
    std::mt19937_64 rng(20261123);
    int unsound = 0, missed = 0, decided = 0;
    const int points = scaled(2000);
    for (int trial = 0; trial < 6; ++trial) {
        const double r = cases::uniform(rng, 1.0, 8.0);
        // A sphere resting on the tip: centre r along the axis.
        const std::vector<oracle::Part> ball{
            models::part(0, 2 * r, [r](double z) { return models::capRadius(r, z); }, r)};

        // Fixed axis along a line: the capsule around the centre's segment.
        Move line = randomMove(rng, 0.0, cases::uniform(rng, 0, 30));
        line.startAxis = line.axis;
        const Vec3 c0 = line.start + r * line.axis, f = line.end - line.start;
        auto capsule = [&](const Vec3& x) {
            const double s = glm::dot(f, f) > 0 ? std::clamp(glm::dot(x - c0, f) / glm::dot(f, f), 0.0, 1.0) : 0.0;
            return glm::length(x - c0 - s * f) - r;
        };
        auto nearCapsule = [&](std::mt19937_64& g) {
            return c0 + cases::uniform(g, 0, 1) * f + (r + offset(g)) * cases::randomUnit(g);
        };
        selfCheck(ball, line, capsule, nearCapsule, rng, points, unsound, missed, decided);

        // Turning in place by up to 170 degrees: spheres centred on an arc of radius r.
        const Move turn = randomMove(rng, degrees(cases::uniform(rng, 1, 170)), 0.0);
        const Vec3 a0 = *turn.startAxis, a1 = turn.axis;
        const double theta = std::acos(std::clamp(glm::dot(a0, a1), -1.0, 1.0));
        const Vec3 b = glm::normalize(a1 - glm::dot(a0, a1) * a0);
        auto arc = [&](const Vec3& x) {
            const Vec3 d = x - turn.start;
            const double p = glm::dot(d, a0), q = glm::dot(d, b);
            const double off = glm::length(d - p * a0 - q * b);
            // The nearest point of the arc [0, theta] of the circle of radius r: at x's own
            // angle when the arc holds it, else at an end.
            double best = oracle::kInf;
            for (double t : {0.0, theta, std::clamp(std::atan2(q, p), 0.0, theta)})
                best = std::min(best, std::hypot(off, std::hypot(p - r * std::cos(t), q - r * std::sin(t))));
            return best - r;
        };
        auto nearArc = [&](std::mt19937_64& g) {
            const double t = cases::uniform(g, 0, theta);
            return turn.start + r * (a0 * std::cos(t) + b * std::sin(t)) + (r + offset(g)) * cases::randomUnit(g);
        };
        selfCheck(ball, turn, arc, nearArc, rng, points, unsound, missed, decided);

        // A flat end mill (a cylinder) plunging along its axis: a longer cylinder.
        const double rc = cases::uniform(rng, 0.5, 10.0), len = cases::uniform(rng, 5.0, 40.0);
        const std::vector<oracle::Part> flat{models::part(0, len, [rc](double) { return rc; }, rc)};
        Move plunge = randomMove(rng, 0.0, 0.0, true);
        const double travel = cases::uniform(rng, -20, 20);
        plunge.end = plunge.start + travel * plunge.axis;
        const double lo = std::min(0.0, travel), hi = std::max(0.0, travel) + len;
        auto cylinder = [&](const Vec3& x) {
            const Vec3 d = x - plunge.start;
            const double z = glm::dot(d, plunge.axis), rho = glm::length(glm::cross(d, plunge.axis));
            const double dz = std::max(lo - z, z - hi), dr = rho - rc;
            if (dz > 0 || dr > 0) return std::hypot(std::max(dz, 0.0), std::max(dr, 0.0));
            // Inside: the depth in the deepest single pose, whose bottom s in [lo, hi - len] is
            // nearest to centring the cylinder on the point.
            const double s = std::clamp(z - 0.5 * len, lo, hi - len);
            return -std::min({-dr, z - s, s + len - z});
        };
        auto nearCylinder = [&](std::mt19937_64& g) {
            // Near the side or near an end face. The side slides along itself, so a point just
            // outside it keeps its distance at every pose that covers its height, and check 1's
            // search needs about |f| / (2 d) nodes to settle it (e): outside the side, the points
            // keep a distance d >= kSideOffset.
            constexpr double kSideOffset = 1e-2;
            const Vec3 across = cases::randomPerpendicular(g, plunge.axis);
            if (g() % 2) {
                const double d = g() % 2 ? -std::abs(offset(g)) : cases::uniform(g, kSideOffset, 0.3);
                return plunge.start + cases::uniform(g, lo, hi) * plunge.axis + (rc + d) * across;
            }
            const double z = g() % 2 ? lo - offset(g) : hi + offset(g);
            return plunge.start + z * plunge.axis + cases::uniform(g, 0, rc) * across;
        };
        selfCheck(flat, plunge, cylinder, nearCylinder, rng, points, unsound, missed, decided);
    }
    INFO(unsound << " unsound certificates, " << missed << " points clearly outside or deep left uncertified, "
                 << decided << " decided");
    CHECK(unsound == 0);
    CHECK(missed == 0);
    // Most points are farther than the chord error from the surface and get decided.
    CHECK(decided >= 18 * points * 3 / 4);
}

TEST_CASE("turning oracle: certificates agree with the fixed-axis oracle (oracle.h) on every tool kind",
          "[sweep][turning]") {
    std::mt19937_64 rng(20261124);
    int unsound = 0, certified = 0;
    const int trials = scaled(200);
    for (int trial = 0; trial < trials; ++trial) {
        const auto kind = models::Kind(trial % int(models::Kind::Count));
        const models::Model model = models::make(kind, rng);
        const Move m = randomMove(rng, 0.0, rng() % 4 == 0 ? 0.0 : cases::uniform(rng, 0, 30), true);
        const SweepOracle o(model.parts, m);
        const oracle::Motion motion{m.start, m.end - m.start, m.axis};
        for (int i = 0; i < 20; ++i) {
            // Points near the surface of a random pose, where the two oracles are most at risk.
            const double u = cases::uniform(rng, 0, 1);
            const oracle::Part& part = model.parts[rng() % model.parts.size()];
            const double z = cases::uniform(rng, part.za - 0.5, part.zb + 0.5);
            const double rho = std::max(0.0, part.radius(std::clamp(z, part.za, part.zb)) + cases::uniform(rng, -0.05, 0.05));
            const Vec3 x = m.start + u * (m.end - m.start) + z * m.axis + rho * cases::randomPerpendicular(rng, m.axis);
            bool inside = false;
            for (const oracle::Part& p : model.parts)
                inside = inside || oracle::phi(p, motion, Line{x, m.axis}, 0.0) <= 0.0;
            const bool outside = o.certainlyOutside(x), deep = o.deepWitness(x, 1e-4).has_value();
            certified += outside || deep;
            if ((outside && inside) || (deep && !inside)) {
                ++unsound;
                INFO(models::name(kind) << " point " << cases::str(x) << " outside " << outside << " deep " << deep);
                CHECK(false);
            }
        }
    }
    CHECK(unsound == 0);
    // The points near the surface are mostly decided.
    CHECK(certified >= trials * 20 / 2);
}

// ---- The solver against the oracle -------------------------------------------------------------

TEST_CASE("turning sweep vs oracle: random tools, turns, moves and lines", "[sweep][turning]") {
    std::mt19937_64 rng(20261123);
    Tally tally;
    for (int i = 0, n = scaled(600); i < n; ++i) {
        double angle = 0.0;
        switch (rng() % 4) {
        case 0: angle = std::pow(10.0, cases::uniform(rng, -7, -1)); break;
        case 1: angle = degrees(cases::uniform(rng, 0, 10)); break;
        case 2: angle = degrees(cases::uniform(rng, 10, 90)); break;
        default: angle = degrees(cases::uniform(rng, 90, 178)); break;
        }
        const double travel = rng() % 5 == 0 ? 0.0 : cases::uniform(rng, 0, 40);
        checkCase(randomCase(rng, randomMove(rng, angle, travel)), tally, rng);
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: turns from 0.001 to 90 degrees", "[sweep][turning]") {
    std::mt19937_64 rng(20261125);
    Tally tally;
    for (double angle : {0.001, 0.01, 0.1, 1.0, 5.0, 15.0, 30.0, 45.0, 60.0, 90.0})
        for (int i = 0, n = scaled(30); i < n; ++i)
            checkCase(randomCase(rng, randomMove(rng, degrees(angle), cases::uniform(rng, 0, 30))), tally, rng);
    report(tally);
    // Both searches are tried: linear nodes on small turns, static poses on large ones.
    CHECK(tally.linear >= tally.cases / 4);
    CHECK(tally.cases - tally.linear >= tally.cases / 10);
}

TEST_CASE("turning sweep vs oracle: a pure rotation about the tip", "[sweep][turning]") {
    std::mt19937_64 rng(20261126);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i)
        checkCase(randomCase(rng, randomMove(rng, degrees(cases::uniform(rng, 0.5, 150)), 0.0)), tally, rng);
    report(tally);
}

TEST_CASE("turning sweep vs oracle: the axis turning through a lattice direction", "[sweep][turning]") {
    std::mt19937_64 rng(20261127);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i) {
        // From (sin a, 0, cos a) through +z to (-sin b, 0, cos b), its coordinates permuted so
        // that the turn passes through +x, +y or +z; with dexel lines most of the time.
        const double a = degrees(cases::uniform(rng, 0.001, 60)), b = degrees(cases::uniform(rng, 0.001, 60));
        const int shift = int(rng() % 3);
        auto lattice = [&](const Vec3& v) { return Vec3(v[(0 + shift) % 3], v[(1 + shift) % 3], v[(2 + shift) % 3]); };
        Move m = randomMove(rng, 0.0, rng() % 3 == 0 ? 0.0 : cases::uniform(rng, 0, 30));
        m.startAxis = lattice(Vec3(std::sin(a), 0, std::cos(a)));
        m.axis = lattice(Vec3(-std::sin(b), 0, std::cos(b)));
        checkCase(randomCase(rng, m, rng() % 4 != 0), tally, rng);
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: the tip moving along the axis", "[sweep][turning]") {
    std::mt19937_64 rng(20261128);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i) {
        Move m = randomMove(rng, degrees(cases::uniform(rng, 0.01, 90)), 0.0);
        // Along the end axis, the start axis or the middle one, either way.
        const Vec3 middle = glm::normalize(*m.startAxis + m.axis);
        const Vec3 along[] = {m.axis, *m.startAxis, middle};
        m.end = m.start + cases::uniform(rng, -30, 30) * along[rng() % 3];
        checkCase(randomCase(rng, m), tally, rng);
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: nearly antipodal axes; opposite axes are refused", "[sweep][turning]") {
    std::mt19937_64 rng(20261129);
    Tally tally;
    for (double angle : {170.0, 179.0, 179.9})
        for (int i = 0, n = scaled(50); i < n; ++i)
            checkCase(randomCase(rng, randomMove(rng, degrees(angle), rng() % 2 ? 0.0 : cases::uniform(rng, 0, 30))),
                      tally, rng);
    report(tally);

    const models::Model model = models::make(models::Kind::Ball, rng);
    Move m = randomMove(rng, 0.0, 10.0);
    m.startAxis = -m.axis;
    CHECK_THROWS_AS(TurningSweep(model.tool, m), Error);
    m.axis = Vec3(0, 0, 1);
    m.startAxis = Vec3(0, 0, -1);
    CHECK_THROWS_AS(TurningSweep(model.tool, m), Error);
}

TEST_CASE("turning sweep vs oracle: a fixed axis (no start axis)", "[sweep][turning]") {
    std::mt19937_64 rng(20261130);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i)
        checkCase(randomCase(rng, randomMove(rng, 0.0, rng() % 5 == 0 ? 0.0 : cases::uniform(rng, 0, 40), true)), tally,
                  rng);
    report(tally);
}

TEST_CASE("turning sweep vs oracle: ball ends swept as capsules, and those searched whole", "[sweep][turning]") {
    std::mt19937_64 rng(20261124);
    Tally tally;
    struct Variant {
        double d, total, angle, epsilon;
        bool bull;
        std::size_t balls;
        const char* what;
    };
    const Variant variants[] = {
        {4.0, 40.0, 5.0, 1e-4, false, 1, "the impeller's ball end turning 5 degrees"},
        {10.0, 15.0, 60.0, 1e-4, false, 1, "turning 60 degrees"},
        {6.0, 12.0, 20.0, 1e-4, true, 1, "a bull nose whose corner radius is half its diameter"},
        {10.0, 7.0, 30.0, 1e-4, false, 0, "a cylinder shorter than the radius: the ball is not inside the tool"},
        {40.0, 45.0, 90.0, 1e-5, false, 0, "a turn that needs more than 256 chords"},
        {3e-4, 1.0, 30.0, 1e-4, false, 0, "a radius below twice the tolerance"},
    };
    for (const Variant& v : variants) {
        const double r = v.d / 2;
        const ToolLengths lengths{v.total, v.total};
        const models::Model model{v.bull ? bullNoseEndMill(v.d, r, lengths) : ballEndMill(v.d, lengths),
                                  {models::part(0, v.total, [r](double z) { return z < r ? models::capRadius(r, z) : r; }, r)}};
        for (int i = 0, n = scaled(40); i < n; ++i) {
            Case c;
            c.kind = v.bull ? models::Kind::Bull : models::Kind::Ball;
            c.model.emplace(model);
            c.move = randomMove(rng, degrees(v.angle), rng() % 4 == 0 ? 0.0 : cases::uniform(rng, 0, 30));
            c.line = randomLine(rng, model, c.move, rng() % 2 == 0);
            c.epsilon = v.epsilon;
            INFO(v.what);
            CHECK(TurningSweep(model.tool, c.move, c.epsilon).capsuleBalls() == v.balls);
            checkCase(c, tally, rng);
        }
    }
    report(tally);
}

TEST_CASE("turning sweep vs oracle: a line the tool cannot reach gets nothing", "[sweep][turning]") {
    std::mt19937_64 rng(20261131);
    Tally tally;
    for (int i = 0, n = scaled(150); i < n; ++i) {
        Case c = randomCase(rng, randomMove(rng, degrees(cases::uniform(rng, 0, 120)), cases::uniform(rng, 0, 40)));
        // The line passes (|f| / 2 + reach + gap) from the middle of the tip's segment, so at
        // least `gap` from every tool point at every pose.
        constexpr double kGap = 0.01;
        const SweepOracle o(c.model->parts, c.move);
        const Vec3 mid = 0.5 * (c.move.start + c.move.end);
        const double away = 0.5 * glm::length(c.move.end - c.move.start) + o.reach() + kGap;
        c.line.origin = mid + away * cases::randomPerpendicular(rng, c.line.dir) + cases::uniform(rng, -30, 30) * c.line.dir;
        const std::vector<Interval> out = checkCase(c, tally, rng);
        INFO(describe(c));
        CHECK(out.empty());
    }
    report(tally, false);
}
