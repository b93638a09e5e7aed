// Cutter profiles: exact line-versus-tool intersections against a brute-force membership oracle.
//
// The oracle shares no code with the tool module's closed forms: each tool type's radius at a
// height is written here again from the tool's defining parameters, membership is "height within
// the tool and distance from the axis within that radius", and the interval ends are found by
// dense sampling along the line followed by bisection.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <random>
#include <sstream>
#include <utility>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/tool/builders.h"
#include "dexelmill/tool/line_query.h"

using namespace dexelmill;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double deg(double d) { return d * kPi / 180.0; }

/// Agreement required between the closed forms and the oracle (mm). The oracle bisects to well
/// below this.
constexpr double kAgree = 1e-6;
/// Samples along a line before bisection.
constexpr int kOracleSamples = 4000;

struct Reference {
    std::string name;
    Tool tool;
    double length;                         // total length
    std::function<double(double)> radius;  // R(z) on [0, length]
    std::vector<double> rims;              // heights of rims / joints to aim at
};

double sq(double x) { return x * x; }

std::vector<Reference> referenceTools() {
    std::vector<Reference> refs;
    {
        const double d = 10, L = 40;
        refs.push_back({"flat", flatEndMill(d, {30, L}), L, [=](double) { return d / 2; }, {0.0, L}});
    }
    {
        const double d = 8, L = 35, r = d / 2;
        refs.push_back({"ball", ballEndMill(d, {25, L}), L,
                        [=](double z) { return z < r ? std::sqrt(std::max(0.0, sq(r) - sq(r - z))) : r; },
                        {r, L}});
    }
    {
        const double d = 12, c = 2.5, L = 45;
        refs.push_back({"bull", bullNoseEndMill(d, c, {30, L}), L,
                        [=](double z) {
                            return z < c ? d / 2 - c + std::sqrt(std::max(0.0, sq(c) - sq(c - z))) : d / 2;
                        },
                        {0.0, c, L}});
    }
    {
        const double tip = 2, a = deg(10), Lc = 20, L = 30;
        refs.push_back({"taper", taperEndMill(tip, a, {Lc, L}), L,
                        [=](double z) { return tip / 2 + std::min(z, Lc) * std::tan(a); }, {0.0, Lc, L}});
    }
    {
        const double tip = 1, a = deg(45), d = 12, L = 30;
        refs.push_back({"chamfer", chamferMill(tip, a, d, {20, L}), L,
                        [=](double z) { return std::min(tip / 2 + z * std::tan(a), d / 2); },
                        {0.0, (d - tip) / 2, L}});
    }
    {
        const double a = deg(30), d = 10, L = 30;
        refs.push_back({"v-bit", chamferMill(0, a, d, {20, L}), L,
                        [=](double z) { return std::min(z * std::tan(a), d / 2); },
                        {0.0, d / 2 / std::tan(a), L}});
    }
    {
        // Tapered ball: sphere of radius rb centred on the axis at height rb, and the flank line
        // at angle a from the axis touching it. The flank is r = rb / cos(a) + (z - rb) tan(a)
        // (the line at distance rb from the centre); below the touching height the sphere.
        const double bd = 3, a = deg(8), Lc = 20, L = 30, rb = bd / 2;
        const double zTouch = rb - rb * std::sin(a);
        refs.push_back({"taper-ball", taperBallMill(bd, a, {Lc, L}), L,
                        [=](double z) {
                            if (z < zTouch) return std::sqrt(std::max(0.0, sq(rb) - sq(rb - z)));
                            return rb / std::cos(a) + (std::min(z, Lc) - rb) * std::tan(a);
                        },
                        {zTouch, Lc, L}});
    }
    {
        const double d = 6, p = deg(118), L = 40;
        refs.push_back({"drill", drill(d, p, {30, L}), L,
                        [=](double z) { return std::min(z * std::tan(p / 2), d / 2); },
                        {d / 2 / std::tan(p / 2), L}});
    }
    {
        // SolidWorks' 90 degree chamfer mill: CUTTER/12,0,6,4.5,45,0,73.
        const double L = 73;
        refs.push_back({"apt-chamfer", aptCutter(12, 0, 6, 4.5, deg(45), 0, L), L,
                        [=](double z) { return std::min(1.5 + z, 6.0); }, {0.0, 4.5, L}});
    }
    {
        // APT bull-nose CUTTER/16,3,5,3,0,0,50.
        const double L = 50;
        refs.push_back({"apt-bull", aptCutter(16, 3, 5, 3, 0, 0, L), L,
                        [=](double z) { return z < 3 ? 5 + std::sqrt(std::max(0.0, 9 - sq(3 - z))) : 8.0; },
                        {0.0, 3.0, L}});
    }
    {
        // APT with a conical bottom and a side flank leaning out: CUTTER/10,0,5,1.5,20,5,30.
        const double L = 30, tipR = 5 - 1.5 / std::tan(deg(20));
        refs.push_back({"apt-flanks", aptCutter(10, 0, 5, 1.5, deg(20), deg(5), L), L,
                        [=](double z) {
                            return std::min(tipR + z / std::tan(deg(20)), 5 + (z - 1.5) * std::tan(deg(5)));
                        },
                        {0.0, 1.5, L}});
    }
    {
        // A non-convex profile: a flat D6 head on a D4 neck, then a D8 shank (lollipop-like
        // steps): R jumps at z = 5 and z = 15.
        const double L = 30;
        Tool t("stepped", {ConePiece{0, 5, 3, 3}, ConePiece{5, 15, 2, 2}, ConePiece{15, L, 4, 4}}, 15);
        refs.push_back({"stepped", t, L,
                        [=](double z) { return z < 5 ? 3.0 : (z <= 15 ? (z == 5 ? 3.0 : 2.0) : 4.0); },
                        {0.0, 5.0, 15.0, L}});
    }
    return refs;
}

/// Oracle membership of world point p in the reference tool at `pose`.
bool oracleInside(const Reference& ref, const ToolPose& pose, const Vec3& p) {
    const Vec3 q = p - pose.tip;
    const double z = glm::dot(q, pose.axis);
    if (z < 0.0 || z > ref.length) return false;
    const Vec3 radial = q - z * pose.axis;
    return std::sqrt(glm::dot(radial, radial)) <= ref.radius(z);
}

Vec3 randomUnit(std::mt19937_64& rng) {
    std::normal_distribution<double> n;
    Vec3 v;
    do v = Vec3(n(rng), n(rng), n(rng));
    while (glm::length(v) < 1e-3);
    return glm::normalize(v);
}

/// Any unit vector perpendicular to `n`.
Vec3 perpendicular(const Vec3& n, std::mt19937_64& rng) {
    Vec3 v;
    do v = glm::cross(n, randomUnit(rng));
    while (glm::length(v) < 1e-3);
    return glm::normalize(v);
}

/// The inside runs of the line according to the oracle, found by sampling then bisection.
std::vector<Interval> oracleRuns(const Reference& ref, const ToolPose& pose, const Line& line, double span) {
    // Parameter of the line point nearest the tool's middle; the tool lies within `span` of it.
    const Vec3 mid = pose.tip + 0.5 * ref.length * pose.axis;
    const double v0 = glm::dot(mid - line.origin, line.dir);
    const int samples = kOracleSamples;
    const double step = 2 * span / samples;
    auto in = [&](double v) { return oracleInside(ref, pose, line.at(v)); };
    auto bisect = [&](double outV, double inV) {
        for (int i = 0; i < 60; ++i) {
            const double m = 0.5 * (outV + inV);
            (in(m) ? inV : outV) = m;
        }
        return 0.5 * (outV + inV);
    };
    std::vector<Interval> runs;
    bool prev = in(v0 - span);
    double start = v0 - span;
    for (int i = 1; i <= samples; ++i) {
        const double v = v0 - span + i * step;
        const bool cur = in(v);
        if (cur && !prev) start = bisect(v - step, v);
        if (!cur && prev) runs.push_back({start, bisect(v, v - step)});
        prev = cur;
    }
    if (prev) runs.push_back({start, v0 + span});
    return runs;
}

struct LineCase {
    Line line;
    const char* kind;
};

/// Lines of every family the issue names: random through the tool, along the axis, through the
/// axis region (the torus hole), near-tangent, through rims, perpendicular to the axis.
LineCase makeLine(const Reference& ref, const ToolPose& pose, std::mt19937_64& rng, int which) {
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const double rMax = ref.tool.maxRadius();
    const Vec3& n = pose.axis;
    const Vec3 b1 = perpendicular(n, rng);
    const Vec3 b2 = glm::cross(n, b1);
    auto pointAt = [&](double rho, double z) { return pose.tip + z * n + rho * b1; };
    const double zAny = u01(rng) * ref.length * 1.1 - 0.05 * ref.length;
    switch (which % 6) {
        case 0: {  // random line through a point near the tool
            const Vec3 p = pose.tip + zAny * n + (u01(rng) * 1.3 * rMax) * perpendicular(n, rng);
            return {{p, randomUnit(rng)}, "random"};
        }
        case 1: {  // along the axis at a random radial offset, either direction
            const Vec3 p = pointAt(u01(rng) * 1.2 * rMax, zAny);
            return {{p, u01(rng) < 0.5 ? n : -n}, "axial"};
        }
        case 2: {  // through the region near the axis (the torus hole of a bull-nose)
            const Vec3 p = pointAt(u01(rng) * 0.5 * rMax, u01(rng) * std::min(ref.length, 2 * rMax));
            return {{p, randomUnit(rng)}, "axis-region"};
        }
        case 3: {  // near-tangent: touch the surface at a boundary point, direction in its tangent plane
            const double z = std::max(1e-3, u01(rng) * ref.length * 0.999);
            const double r = ref.radius(z);
            const double h = 1e-5;
            const double slope = (ref.radius(std::min(z + h, ref.length)) - ref.radius(std::max(z - h, 0.0))) /
                                 (std::min(z + h, ref.length) - std::max(z - h, 0.0));
            // Normal in the (radial, axial) plane is (1, -slope); tangent directions are spanned by
            // the circumferential b2 and the meridian (slope, 1).
            const Vec3 meridian = glm::normalize(slope * b1 + n);
            const double t = u01(rng) * 2 * kPi;
            const Vec3 dir = glm::normalize(std::cos(t) * b2 + std::sin(t) * meridian);
            const double offset = (u01(rng) - 0.5) * 2e-3;
            return {{pointAt(r + offset, z), dir}, "near-tangent"};
        }
        case 4: {  // through a rim or joint circle
            const double z = ref.rims[std::size_t(u01(rng) * ref.rims.size()) % ref.rims.size()];
            const double r = ref.radius(std::min(z, ref.length));
            const Vec3 p = pointAt(r * (0.98 + 0.04 * u01(rng)), z + (u01(rng) - 0.5) * 1e-3);
            return {{p, randomUnit(rng)}, "rim"};
        }
        default: {  // perpendicular to the axis, sometimes just off a joint or face height (a line
                    // exactly in a face is a tie the oracle cannot decide; see the face test)
            const double side = (u01(rng) < 0.5 ? -1 : 1) * std::pow(10.0, -7 + 3 * u01(rng));
            const double z = u01(rng) < 0.3
                                 ? ref.rims[std::size_t(u01(rng) * ref.rims.size()) % ref.rims.size()] + side
                                 : zAny;
            const Vec3 p = pose.tip + z * n + (u01(rng) * 1.2 * rMax) * b1;
            return {{p, b2}, "perpendicular"};
        }
    }
}

}  // namespace

TEST_CASE("line versus tool agrees with the membership oracle", "[tool][oracle]") {
    const int kLinesPerTool = 10000;
    for (const Reference& ref : referenceTools()) {
        std::mt19937_64 rng(0x5eed + std::hash<std::string>{}(ref.name) % 1000);
        int hits = 0;
        for (int i = 0; i < kLinesPerTool; ++i) {
            ToolPose pose;
            pose.tip = Vec3(std::uniform_real_distribution<double>(-50, 50)(rng), 10.0, -20.0);
            pose.axis = (i % 4 == 0) ? Vec3(0, 0, 1) : randomUnit(rng);
            const LineCase lc = makeLine(ref, pose, rng, i);
            // Move the line's origin away along itself so the solver's re-centring is exercised.
            Line line = lc.line;
            line.origin -= 137.0 * line.dir;
            const std::vector<Interval> got = ref.tool.intersect(pose, line);
            const double span = ref.length + 2 * ref.tool.maxRadius();
            const std::vector<Interval> want = oracleRuns(ref, pose, line, span);
            INFO(ref.name << " line " << i << " (" << lc.kind << ")");
            // Every oracle run appears, with the same ends. The oracle cannot see a gap narrower
            // than its sampling step, so computed intervals closer than that are joined for this
            // comparison; the gaps themselves are checked by membership below.
            const double step = 2 * span / kOracleSamples;
            std::vector<Interval> joined;
            for (const Interval& g : got) {
                if (!joined.empty() && g.lo - joined.back().hi < step) joined.back().hi = g.hi;
                else joined.push_back(g);
            }
            for (const Interval& w : want) {
                auto matches = [&](const std::vector<Interval>& list) {
                    for (const Interval& g : list)
                        if (std::abs(g.lo - w.lo) <= kAgree && std::abs(g.hi - w.hi) <= kAgree) return true;
                    return false;
                };
                const bool found = matches(got) || matches(joined);
                std::ostringstream computed;
                computed.precision(12);
                for (const Interval& g : got) computed << " [" << g.lo << ", " << g.hi << "]";
                INFO("oracle run " << w.lo << " .. " << w.hi << "; computed" << computed.str());
                CHECK(found);
            }
            for (std::size_t k = 1; k < got.size(); ++k) {
                const double gap = got[k].lo - got[k - 1].hi;
                if (gap > 2 * kAgree) CHECK_FALSE(oracleInside(ref, pose, line.at(got[k].lo - 0.5 * gap)));
            }
            // Every computed interval is material inside and air just outside.
            for (const Interval& g : got) {
                INFO("computed " << g.lo << " .. " << g.hi);
                ++hits;
                if (g.length() > 4 * kAgree) {
                    CHECK(oracleInside(ref, pose, line.at(g.lo + kAgree)));
                    CHECK(oracleInside(ref, pose, line.at(g.hi - kAgree)));
                    CHECK(oracleInside(ref, pose, line.at(0.5 * (g.lo + g.hi))));
                }
                CHECK_FALSE(oracleInside(ref, pose, line.at(g.lo - kAgree)));
                CHECK_FALSE(oracleInside(ref, pose, line.at(g.hi + kAgree)));
            }
        }
        // The line families hit the tool often enough for the test to mean something.
        INFO(ref.name);
        CHECK(hits > kLinesPerTool / 3);
    }
}

TEST_CASE("a line lying in a face: the tool is closed, so the face's chord is inside", "[tool]") {
    const Tool flat = flatEndMill(10, {20, 40});
    const ToolPose pose{Vec3(1, 2, 3), Vec3(0, 0, 1)};
    // In the bottom face z = 3: the chord of the radius-5 disk 3 mm off the centre.
    auto bottom = flat.intersect(pose, Line{Vec3(-20, 5, 3), Vec3(1, 0, 0)});
    REQUIRE(bottom.size() == 1);
    CHECK(bottom[0].lo == Approx(21 - 4));
    CHECK(bottom[0].hi == Approx(21 + 4));
    // In the top face z = 43.
    auto top = flat.intersect(pose, Line{Vec3(1, -20, 43), Vec3(0, 1, 0)});
    REQUIRE(top.size() == 1);
    CHECK(top[0].length() == Approx(10));
    // Just outside either face: nothing.
    CHECK(flat.intersect(pose, Line{Vec3(-20, 5, 3 - 1e-9), Vec3(1, 0, 0)}).empty());
    CHECK(flat.intersect(pose, Line{Vec3(1, -20, 43 + 1e-9), Vec3(0, 1, 0)}).empty());
    // A line in the cylinder wall, parallel to the axis: the whole height.
    auto wall = flat.intersect(pose, Line{Vec3(6, 2, 0), Vec3(0, 0, 1)});
    REQUIRE(wall.size() == 1);
    CHECK(wall[0].lo == Approx(3));
    CHECK(wall[0].hi == Approx(43));
}

TEST_CASE("a torus piece meets a line parallel to its axis in closed form", "[tool]") {
    // Bull-nose fillet: rc = 3, zc = 2, rho = 2, heights [0, 2] (the lower quarter).
    const ProfilePiece fillet = ArcPiece{0.0, 2.0, 3.0, 2.0, 2.0};
    auto along = [](double rho) {  // a line parallel to the axis, rho from it, going up
        LocalLine l;
        l.z0 = 0.0, l.zv = 1.0, l.A = 0.0, l.B = 0.0, l.C = rho * rho;
        return l;
    };
    // rho = 4.6: 1.6 beyond the spine circle, so |z - 2| <= sqrt(4 - 2.56) = 1.2: z in [0.8, 2].
    const Interval mid = intersectPiece(fillet, along(4.6));
    CHECK(mid.lo == Approx(0.8).margin(1e-12));
    CHECK(mid.hi == Approx(2.0).margin(1e-12));
    // Inside the spine circle (rho < rc): the whole slab.
    const Interval core = intersectPiece(fillet, along(1.0));
    CHECK(core.lo == 0.0);
    CHECK(core.hi == 2.0);
    // Beyond the outer radius rc + rho = 5: nothing.
    CHECK(intersectPiece(fillet, along(5.0 + 1e-9)).isEmpty());
    // Going down the line: the same heights, so parameters [-2, -0.8].
    LocalLine down = along(4.6);
    down.zv = -1.0;
    const Interval rev = intersectPiece(fillet, down);
    CHECK(rev.lo == Approx(-2.0).margin(1e-12));
    CHECK(rev.hi == Approx(-0.8).margin(1e-12));
}

TEST_CASE("a torus piece's ends lie within the root tolerance of the torus, by bisection in long double",
          "[tool][oracle]") {
    // The bull nose's fillet (rc = 3, zc = 2, rho = 2, heights [0, 2]) against lines in random
    // directions through random points near it. The oracle: the slab solid's membership,
    // rho <= rc + sqrt(rho^2 - (z - zc)^2) with z in [0, 2], in long double, its ends bisected from
    // samples 6 um apart to 1e-16 mm. Where the line crosses the torus at an angle (the implicit
    // function's gradient at least a tenth along the line), the solver's end lies within its root
    // tolerance (1e-12) of the oracle's, plus rounding; near-tangent crossings, within 1e-6.
    const ArcPiece fillet{0.0, 2.0, 3.0, 2.0, 2.0};
    using L = long double;
    const auto inside = [&](const Line& line, L t) {
        const L x = L(line.origin.x) + t * L(line.dir.x), y = L(line.origin.y) + t * L(line.dir.y);
        const L z = L(line.origin.z) + t * L(line.dir.z);
        if (z < 0 || z > 2) return false;
        const L dz = z - 2;
        return std::sqrt(x * x + y * y) <= 3 + std::sqrt(std::max(L(0), 4 - dz * dz));
    };
    // The cosine of the angle between the line and the torus's normal at its point t.
    const auto crossing = [&](const Line& line, double t) {
        const Vec3 p = line.at(t);
        const double r = std::hypot(p.x, p.y);
        if (!(r > 0.0)) return 0.0;
        const Vec3 n = glm::normalize(Vec3((r - 3.0) * p.x / r, (r - 3.0) * p.y / r, p.z - 2.0));
        return std::abs(glm::dot(n, line.dir));
    };
    std::mt19937_64 rng(20261130);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int tight = 0, loose = 0;
    for (int i = 0; i < 4000; ++i) {
        const Vec3 dir = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        const Vec3 through(5.5 * u(rng), 5.5 * u(rng), 1.0 + 1.2 * u(rng));
        const Line line{through - 30.0 * dir, dir};
        // A piece's interval is in the local line's parameter, which starts where the line comes
        // nearest the tip: vShift from the line's own.
        const LocalLine local = LocalLine::make(ToolPose{}, line);
        Interval got = intersectPiece(fillet, local);
        if (!got.isEmpty()) got = {got.lo + local.vShift, got.hi + local.vShift};
        // The oracle's runs along t in [0, 60], which holds the slab's stretch of the line.
        std::vector<std::pair<L, L>> runs;
        const int n = 10000;
        bool prev = inside(line, 0);
        REQUIRE(!prev);
        L start = 0;
        for (int k = 1; k <= n; ++k) {
            const L t = L(60) * k / n;
            const bool now = inside(line, t);
            if (now != prev) {
                L a = L(60) * (k - 1) / n, b = t;
                while (b - a > L(1e-16)) {
                    const L m = 0.5L * (a + b);
                    (inside(line, m) == prev ? a : b) = m;
                }
                if (now) start = 0.5L * (a + b);
                else runs.push_back({start, 0.5L * (a + b)});
            }
            prev = now;
        }
        INFO("line " << i);
        if (runs.empty()) {
            // The oracle's samples, 6 um apart, may miss a graze the solver finds.
            CHECK(got.length() < 1e-3);
            continue;
        }
        REQUIRE(runs.size() == 1);
        REQUIRE(!got.isEmpty());
        for (const bool upper : {false, true}) {
            const double want = double(upper ? runs[0].second : runs[0].first), end = upper ? got.hi : got.lo;
            if (crossing(line, want) >= 0.1) {
                CHECK(std::abs(end - want) <= 1.1e-12);
                ++tight;
            } else {
                CHECK(std::abs(end - want) <= 1e-6);
                ++loose;
            }
        }
    }
    CHECK(tight > 2000);
    CHECK(loose > 50);
}

namespace {

/// A bull nose D10 r2's fillet grown by 1: rc = 3, zc = 2, rho = 3, heights [-1, 2].
const ArcPiece kGrownFillet{-1.0, 2.0, 3.0, 2.0, 3.0};

/// Whether the point at t on `line` lies in kGrownFillet's slab solid, in long double.
bool inGrownFillet(const Line& line, long double t) {
    using L = long double;
    const L x = L(line.origin.x) + t * L(line.dir.x), y = L(line.origin.y) + t * L(line.dir.y);
    const L z = L(line.origin.z) + t * L(line.dir.z);
    if (z < -1 || z > 2) return false;
    const L dz = z - 2;
    return std::sqrt(x * x + y * y) <= 3 + std::sqrt(std::max(L(0), 9 - dz * dz));
}

/// The oracle's run of `line` in kGrownFillet's slab solid about t = 10, a point inside: each end
/// stepped out to a point outside, then bisected in long double to 1e-15.
std::pair<long double, long double> grownFilletRun(const Line& line) {
    using L = long double;
    L lo = 10, hi = 10;
    for (const int side : {-1, 1}) {
        L in = 10, out = 10 + side * L(1e-3);
        while (inGrownFillet(line, out)) in = out, out = 10 + 2 * (out - 10);
        while (std::abs(out - in) > L(1e-15)) {
            const L m = 0.5L * (in + out);
            (inGrownFillet(line, m) ? in : out) = m;
        }
        (side < 0 ? lo : hi) = in;
    }
    return {lo, hi};
}

}  // namespace

TEST_CASE("an outer torus interval holds the torus's, for lines that only graze it", "[tool][oracle]") {
    // A bull nose D10 r2's fillet grown by 1 (rc = 3, zc = 2, rho = 3, heights [-1, 2]), as the
    // static search's settling test takes it, against lines that enter it less than 1 um deep
    // (chords up to 0.15 mm): through a point of the torus moved in along its normal, in a random
    // direction of the tangent plane there. With slacks of 0.01 and 0.1 mm and no hint,
    // the outer interval must hold the oracle's run (long-double bisection of the slab solid)
    // and end within the slack of it. The search for q's least, stopped at a bracket as wide as the
    // slack, once called such lines misses (70bc9fa).
    const ArcPiece& torus = kGrownFillet;
    std::mt19937_64 rng(20261130);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    int checked = 0;
    for (int i = 0; i < 3000; ++i) {
        // A point of the torus at normal angle psi (its lower quarter and a little of the upper)
        // and azimuth phi, its outward normal, and a tangent direction.
        const double psi = -0.5 * kPi + u01(rng) * 0.5 * kPi * 0.98, phi = 2.0 * kPi * u01(rng);
        const Vec3 radial(std::cos(phi), std::sin(phi), 0.0);
        const Vec3 normal = std::cos(psi) * radial + Vec3(0.0, 0.0, std::sin(psi));
        const Vec3 surface = 3.0 * radial + Vec3(0.0, 0.0, 2.0) + 3.0 * normal;
        const Vec3 side = glm::normalize(glm::cross(normal, Vec3(-radial.y, radial.x, 0.0)));
        const Vec3 around(-radial.y, radial.x, 0.0);
        const double turn = 2.0 * kPi * u01(rng);
        const Vec3 dir = std::cos(turn) * around + std::sin(turn) * side;
        const Vec3 through = surface - 1e-3 * u01(rng) * normal;
        const Line line{through - 10.0 * dir, dir};
        // The oracle's run about t = 10, where the line passes `through`, inside.
        if (!inGrownFillet(line, 10)) continue;
        const auto [lo, hi] = grownFilletRun(line);
        const LocalLine local = LocalLine::make(ToolPose{}, line);
        const Interval slab = detail::slabRange(local, torus.z0, torus.z1);
        for (const double slack : {0.01, 0.1}) {
            INFO("line " << i << ", slack " << slack << ", oracle [" << double(lo) << ", " << double(hi) << "]");
            Interval outer = detail::outerTorusInterval(torus, local, slab, slack);
            REQUIRE(!outer.isEmpty());
            outer = {outer.lo + local.vShift, outer.hi + local.vShift};
            CHECK(outer.lo <= double(lo) + 1e-9);
            CHECK(outer.hi >= double(hi) - 1e-9);
            CHECK(outer.lo >= double(lo) - slack - 1e-9);
            CHECK(outer.hi <= double(hi) + slack + 1e-9);
            ++checked;
        }
    }
    CHECK(checked > 4000);
}

TEST_CASE("an outer torus interval holds the torus's within the slack, whatever its hint", "[tool][oracle]") {
    // The grown fillet of the test above, against lines through a point inside it at depths from
    // 1 um to 2 mm in random directions, each asked with hints good and bad: the interval's own
    // ends moved in or out by up to three times the reach, one end only inside, both outside, a
    // hint beyond the interval, and one that is empty. Each answer must hold the oracle's run
    // (long-double bisection of the slab solid) and end within the slack of it, as without a hint.
    const ArcPiece& torus = kGrownFillet;
    std::mt19937_64 rng(20261201);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    int checked = 0, hinted = 0;
    for (int i = 0; i < 1500; ++i) {
        const double psi = -0.5 * kPi + u01(rng) * 0.5 * kPi * 0.98, phi = 2.0 * kPi * u01(rng);
        const Vec3 radial(std::cos(phi), std::sin(phi), 0.0);
        const Vec3 normal = std::cos(psi) * radial + Vec3(0.0, 0.0, std::sin(psi));
        const Vec3 surface = 3.0 * radial + Vec3(0.0, 0.0, 2.0) + 3.0 * normal;
        const double depth = std::pow(10.0, -3.0 + 3.3 * u01(rng));
        const double cz = 2.0 * u01(rng) - 1.0, az = 2.0 * kPi * u01(rng), sz = std::sqrt(1.0 - cz * cz);
        const Vec3 dir(sz * std::cos(az), sz * std::sin(az), cz);
        const Line line{surface - depth * normal - 10.0 * dir, dir};
        if (!inGrownFillet(line, 10)) continue;
        const auto [lo, hi] = grownFilletRun(line);
        const LocalLine local = LocalLine::make(ToolPose{}, line);
        const Interval slab = detail::slabRange(local, torus.z0, torus.z1);
        // The oracle's run in the local line's parameters.
        const double lLo = double(lo) - local.vShift, lHi = double(hi) - local.vShift;
        for (const double reach : {1e-6, 0.01, 1.0}) {
            std::vector<Interval> hints{{lLo - 4.0 * reach, lHi + 4.0 * reach},
                                        {lHi + 1.0, lHi + 2.0},
                                        {lLo + reach, lLo + reach},
                                        {lHi, lLo - 1.0},
                                        {lLo + reach, lHi + 4.0 * reach}};
            for (int k = 0; k < 3; ++k)
                hints.push_back({lLo + reach * (6.0 * u01(rng) - 3.0), lHi - reach * (6.0 * u01(rng) - 3.0)});
            for (const Interval& near : hints) {
                for (const double slack : {0.01, 0.1}) {
                    INFO("line " << i << ", depth " << depth << ", reach " << reach << ", slack " << slack
                                 << ", hint [" << near.lo << ", " << near.hi << "], oracle [" << lLo << ", " << lHi
                                 << "] (local)");
                    const Interval outer = detail::outerTorusInterval(torus, local, slab, slack, near, reach);
                    REQUIRE(!outer.isEmpty());
                    CHECK(outer.lo <= lLo + 1e-9);
                    CHECK(outer.hi >= lHi - 1e-9);
                    CHECK(outer.lo >= lLo - slack - 1e-9);
                    CHECK(outer.hi <= lHi + slack + 1e-9);
                    ++checked;
                    hinted += !near.isEmpty() && near.lo > lLo && near.lo < lHi;
                }
            }
        }
    }
    CHECK(checked > 30000);
    CHECK(hinted > 10000);
}

TEST_CASE("profile radius and membership follow the builders' shapes", "[tool]") {
    for (const Reference& ref : referenceTools()) {
        INFO(ref.name);
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> z01(0.0, 1.0);
        for (int i = 0; i < 2000; ++i) {
            const double z = z01(rng) * ref.length;
            if (ref.name == "stepped" && (std::abs(z - 5) < 1e-9 || std::abs(z - 15) < 1e-9)) continue;
            CHECK(ref.tool.radiusAt(z) == Approx(ref.radius(z)).margin(1e-9));
            const double rho = z01(rng) * 1.2 * ref.tool.maxRadius();
            if (std::abs(rho - ref.radius(z)) > 1e-9) CHECK(ref.tool.containsLocal(rho, z) == (rho <= ref.radius(z)));
        }
        CHECK(ref.tool.radiusAt(-0.1) < 0);
        CHECK(ref.tool.radiusAt(ref.length + 0.1) < 0);
        CHECK(ref.tool.totalLength() == Approx(ref.length));
    }
}

TEST_CASE("convex parts: one for common cutters, split at steps and concave joints", "[tool]") {
    CHECK(flatEndMill(6).isConvex());
    CHECK(ballEndMill(6).isConvex());
    CHECK(bullNoseEndMill(10, 2).isConvex());
    CHECK(taperBallMill(3, deg(5)).isConvex());
    CHECK(drill(6, deg(118)).isConvex());
    CHECK(aptCutter(12, 0, 6, 4.5, deg(45), 0, 73).isConvex());
    const Tool stepped("stepped", {ConePiece{0, 5, 3, 3}, ConePiece{5, 15, 2, 2}, ConePiece{15, 30, 4, 4}}, 15);
    REQUIRE(stepped.convexParts().size() == 3);
    CHECK(stepped.convexParts()[1].z0 == 5);
    CHECK(stepped.convexParts()[1].z1 == 15);
    // A dovetail-like profile: widening cone, then a narrower cylinder: the joint is concave.
    const Tool dovetail("dovetail", {ConePiece{0, 4, 6, 3}, ConePiece{4, 20, 3, 3}}, 20);
    CHECK(dovetail.convexParts().size() == 2);
}

TEST_CASE("tool lengths and the shank region", "[tool]") {
    const Tool t = flatEndMill(6, {20, 50});
    CHECK(t.cuttingLength() == 20);
    CHECK(t.totalLength() == 50);
    CHECK(t.cuttingRadius() == 3);
    const Tool shank = t.region(t.cuttingLength(), t.totalLength());
    CHECK(shank.bottom() == 20);
    CHECK(shank.totalLength() == 50);
    CHECK_FALSE(shank.containsLocal(1.0, 10.0));
    CHECK(shank.containsLocal(1.0, 30.0));
    // Defaults: 3 diameters of flute, 2 more of stick-out.
    const Tool d = ballEndMill(6);
    CHECK(d.cuttingLength() == 18);
    CHECK(d.totalLength() == 30);
    const Tool taper = taperEndMill(2, deg(10), {10, 40});
    CHECK(taper.cuttingRadius() == Approx(1 + 10 * std::tan(deg(10))));
}

namespace {
/// The message of the Error `f` throws.
template <class F>
std::string errorOf(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "<no error>";
}
}  // namespace

TEST_CASE("impossible tool parameters name the parameter and the value", "[tool][errors]") {
    using Catch::Matchers::Contains;
    CHECK_THAT(errorOf([] { flatEndMill(0); }), Contains("diameter d") && Contains("0"));
    CHECK_THAT(errorOf([] { ballEndMill(-3); }), Contains("diameter d") && Contains("-3"));
    CHECK_THAT(errorOf([] { bullNoseEndMill(10, 6); }), Contains("corner radius r = 6") && Contains("d/2 = 5"));
    CHECK_THAT(errorOf([] { bullNoseEndMill(10, 0); }), Contains("corner radius r") && Contains("0"));
    CHECK_THAT(errorOf([] { taperEndMill(2, deg(-5)); }), Contains("half angle") && Contains("-5"));
    CHECK_THAT(errorOf([] { taperEndMill(-1, deg(5)); }), Contains("tip diameter") && Contains("-1"));
    CHECK_THAT(errorOf([] { chamferMill(0, deg(90), 10); }), Contains("half angle") && Contains("90"));
    CHECK_THAT(errorOf([] { chamferMill(12, deg(45), 10); }), Contains("diameter d = 10"));
    CHECK_THAT(errorOf([] { drill(6, deg(180)); }), Contains("point angle") && Contains("180"));
    CHECK_THAT(errorOf([] { flatEndMill(6, {30, 20}); }), Contains("total length 20") && Contains("30"));
    CHECK_THAT(errorOf([] { flatEndMill(6, {-1, 20}); }), Contains("cutting length") && Contains("-1"));
    CHECK_THAT(errorOf([] { ballEndMill(10, {2, 4}); }), Contains("total length 4"));
    CHECK_THAT(errorOf([] { aptCutter(10, 6, 0, 6, 0, 0, 50); }), Contains("r = 6") && Contains("d/2 = 5"));
    CHECK_THAT(errorOf([] { aptCutter(10, 0, 5, 0, deg(-10), 0, 50); }), Contains("alpha") && Contains("-10"));
    CHECK_THAT(errorOf([] { aptCutter(10, 2, 3, 3, 0, 0, 50); }), Contains("f must equal r"));
    CHECK_THAT(errorOf([] { aptCutter(10, 0, 4, 0, 0, 0, 50); }),
               Contains("d = 10 is not the diameter its corner makes, 2 (e + r cos(beta)) = 8"));
    CHECK_THAT(errorOf([] { aptCutter(10, 0, 5, 0, 0, 0, 0); }), Contains("h must be positive"));
    CHECK_THAT(errorOf([] { aptCutter(10, 0, 5, 20, deg(30), 0, 50); }), Contains("meets the axis"));
    CHECK_THAT(errorOf([] { Tool("gap", {ConePiece{0, 5, 3, 3}, ConePiece{6, 9, 3, 3}}, 9); }),
               Contains("starts at z = 6"));
    CHECK_THAT(errorOf([] { Tool("neg", {ConePiece{0, 5, 3, -1}}, 5); }), Contains("negative radius"));
    CHECK_THAT(errorOf([] { Tool("none", {}, 5); }), Contains("no pieces"));
    CHECK_THAT(errorOf([] { Tool("flat", {ConePiece{0, 5, 3, 3}}, 6); }), Contains("cutting length 6"));
}

TEST_CASE("APT relations hold within the rounding of printed values, and messages tell the values apart", "[tool]") {
    using Catch::Matchers::Contains;
    // d/2 = 50.05 against e + r = 50: beyond six digits of each (5e-4 mm all told), refused.
    CHECK_THAT(errorOf([] { aptCutter(100.1, 2, 48, 2, 0, 0, 50); }),
               Contains("d = 100.1 is not the diameter its corner makes, 2 (e + r cos(beta)) = 100"));
    // r = d/2 + 5e-6 (1.984375 printed 1.98438) is within them: the profile is the one r, e, f give.
    const Tool ball = aptCutter(3.96875, 1.98438, 0, 1.98438, 0, 0, 50);
    CHECK(ball.radiusAt(0.0) == 0.0);
    CHECK(ball.cuttingRadius() == 1.98438);
    // Four decimals of an inch: 0.0001 inch = 2.54e-3 mm off in d/2, within 3 times 1.27e-3 mm.
    CHECK(aptCutter(6.35, 0.0313 * 25.4, 0.0938 * 25.4, 0.0313 * 25.4, 0, 0, 50, 0.0, 25.4).cuttingRadius() ==
          Approx(0.1251 * 25.4));
    CHECK_THAT(errorOf([] { aptCutter(6.35, 0.0313 * 25.4, 0.0938 * 25.4, 0.0313 * 25.4, 0, 0, 50); }),
               Contains("is not the diameter its corner makes"));
    // A named bull nose takes exact values: 1e-7 over d/2 is not rounding, and the message shows it.
    CHECK_THAT(errorOf([] { bullNoseEndMill(6, 3.0000001); }), Contains("corner radius r = 3.0000001 exceeds d/2 = 3"));
}

TEST_CASE("a total length given alone caps the default cutting length, and must clear the tool's end", "[tool]") {
    using Catch::Matchers::Contains;
    // 3 d = 18 mm of flute would not fit a 15 mm tool: the flute is the whole of it.
    const Tool ball = ballEndMill(6, {0, 15});
    CHECK(ball.cuttingLength() == 15);
    CHECK(ball.totalLength() == 15);
    const Tool drill2 = drill(6, deg(118), {0, 2});
    CHECK(drill2.cuttingLength() == 2);
    CHECK(drill2.totalLength() == 2);
    // A D6 118 deg point is 3 / tan(59 deg) = 1.80258 mm tall: 1 mm of tool does not clear it.
    CHECK_THAT(errorOf([] { drill(6, deg(118), {0, 1}); }), Contains("total length 1 mm does not clear the 1.80258 mm point"));
    CHECK_THAT(errorOf([] { ballEndMill(6, {0, 2}); }), Contains("total length 2 mm does not clear the 3 mm ball"));
    // Both given, the user's cutting length stands, and the message compares the two.
    CHECK_THAT(errorOf([] { ballEndMill(6, {20, 15}); }), Contains("total length 15 mm is shorter than the cutting length 20 mm"));
    // A short flute under a tall cone: the default total clears the cone, 6 / tan(0.5 deg) = 687.526 mm,
    // by 2 d, as it would clear the flute.
    const Tool vbit = chamferMill(0, deg(0.5), 12, {5, 0});
    CHECK(vbit.cuttingLength() == 5);
    CHECK(vbit.totalLength() == Approx(6 / std::tan(deg(0.5)) + 24));
}

TEST_CASE("a tool's sizes, given or derived, stop at kMaxToolSizeMm, named with the cap", "[tool][errors]") {
    using Catch::Matchers::Contains;
    const std::string beyond = " mm is beyond the 10000 mm a tool may measure";
    // Given sizes name their parameter (the square of 1e155 overflows a double).
    CHECK_THAT(errorOf([] { flatEndMill(1e155); }), Contains("diameter d = 1e+155" + beyond));
    CHECK_THAT(errorOf([] { ballEndMill(6, {0, 1e300}); }), Contains("total length = 1e+300" + beyond));
    CHECK_THAT(errorOf([] { ballEndMill(6, {2e4, 0}); }), Contains("cutting length = 20000" + beyond));
    CHECK_THAT(errorOf([] { bullNoseEndMill(10, 1e155); }), Contains("corner radius r = 1e+155" + beyond));
    CHECK_THAT(errorOf([] { chamferMill(2e4, deg(45), 3e4); }), Contains("tip diameter = 20000" + beyond));
    CHECK_THAT(errorOf([] { taperBallMill(3e4, deg(5)); }), Contains("ball diameter = 30000" + beyond));
    CHECK_THAT(errorOf([] { aptCutter(1e155, 0, 5e154, 0, 0, 0, 50); }), Contains("d = 1e+155" + beyond));
    CHECK_THAT(errorOf([] { aptCutter(10, 0, 5, 0, 0, 0, 1e300); }), Contains("h = 1e+300" + beyond));
    // Just past the cap the message still tells the two numbers apart.
    const double past = std::nextafter(kMaxToolSizeMm, 2 * kMaxToolSizeMm);
    CHECK_THAT(errorOf([past] { flatEndMill(past); }), Contains("diameter d = 10000.000000000002" + beyond));
    // At the cap a tool is built, and its default lengths (3 d of flute, 2 d more) stop there.
    const Tool widest = flatEndMill(kMaxToolSizeMm);
    CHECK(widest.cuttingRadius() == 5000);
    CHECK(widest.cuttingLength() == 10000);
    CHECK(widest.totalLength() == 10000);
    // Derived sizes. A V-bit D12 at a half angle of 1e-9 deg has a cone 6 / tan(1e-9 deg) =
    // 3.43775e11 mm tall; a taper D2 at 89.99 deg widens over its 10 mm of flute to
    // 2 (1 + 10 tan(89.99 deg)) = 114594 mm; an APT cutter's flank at beta = 89.99 deg to
    // 2 (5 + 50 tan(89.99 deg)) = 572968 mm at h = 50.
    CHECK_THAT(errorOf([] { chamferMill(0, deg(1e-9), 12); }), Contains("height = 3.43775e+11" + beyond));
    CHECK_THAT(errorOf([] { taperEndMill(2, deg(89.99)); }), Contains("its largest diameter, 114594 mm, is beyond the 10000 mm"));
    CHECK_THAT(errorOf([] { aptCutter(10, 0, 5, 0, 0, deg(89.99), 50); }),
               Contains("its largest diameter, 572968 mm, is beyond the 10000 mm"));
}
