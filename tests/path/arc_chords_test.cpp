// Arcs cut into chords (G2/G3, APT CIRCLE) against an oracle that samples each arc densely from
// its centre and radius and measures each sample's distance to the chords by brute force: every
// chord stays within the chord tolerance, whatever the tolerance, and the program's arcSag is the
// distance the samples find.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "dexelmill/path/apt.h"
#include "dexelmill/path/gcode.h"

using namespace dexelmill;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Samples the oracle takes on an arc: the largest distance it finds falls short of the true one
/// by at most r (1 - cos(pi / kSamples)) for a full circle of radius r, 1.2e-6 r.
constexpr int kSamples = 2000;

/// The rounding the chord ends' and the samples' coordinates may carry, relative to the radius.
constexpr double kRounding = 1e-12;

double segmentDistance(const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 m = b - a;
    const double mm = glm::dot(m, m);
    const double s = mm > 0.0 ? std::clamp(glm::dot(p - a, m) / mm, 0.0, 1.0) : 0.0;
    return glm::length(p - (a + s * m));
}

/// The largest distance from the samples of the circle about `centre` (radius r, in the xy plane),
/// from angle a0 turning by `sweep`, to the feed moves of `p` made by source line `line`.
double farthestSample(const Program& p, int line, const Vec3& centre, double r, double a0, double sweep) {
    double farthest = 0.0;
    for (int i = 0; i <= kSamples; ++i) {
        const double a = a0 + sweep * i / kSamples;
        const Vec3 q = centre + r * Vec3(std::cos(a), std::sin(a), 0.0);
        double nearest = INFINITY;
        for (const Move& m : p.path.moves)
            if (m.source.line == line) nearest = std::min(nearest, segmentDistance(q, m.start, m.end));
        farthest = std::max(farthest, nearest);
    }
    return farthest;
}

}  // namespace

TEST_CASE("arcs: chords stay within the chord tolerance, even one as large as the radius or larger",
          "[path][gcode][degenerate]") {
    std::mt19937 rng(20261202);
    std::uniform_real_distribution<double> radius(0.1, 50.0), share(0.001, 3.0), turn(0.05, 2 * kPi);
    for (int trial = 0; trial < 60; ++trial) {
        const double r = radius(rng);
        // Tolerances from a thousandth of the radius to three times it: a full circle's one chord
        // (no length at all) lies 2r from its far side.
        const double tol = r * share(rng);
        const bool full = trial % 3 == 0;
        const double sweep = full ? 2 * kPi : turn(rng);
        GcodeOptions o;
        o.startPosition = Vec3(0.0);
        o.chordTolerance = tol;
        // Counter-clockwise about the origin from (r, 0).
        char text[200];
        std::snprintf(text, sizeof text, "G0 X%.15f Y0 Z0\nG3 X%.15f Y%.15f I%.15f J0\n", r, r * std::cos(sweep),
                      r * std::sin(sweep), -r);
        const Program p = parseGcode(text, "arc.ngc", o);
        INFO("r " << r << ", tolerance " << tol << ", sweep " << sweep);
        const double found = farthestSample(p, 2, Vec3(0.0), r, 0.0, sweep);
        CHECK(found <= tol + kRounding * r);
        // arcSag is the chords' farthest distance, which the samples find to within their spacing.
        CHECK(p.arcSag >= found - kRounding * r);
        CHECK(p.arcSag <= found + r * (1.0 - std::cos(kPi / kSamples)) + kRounding * r);
        CHECK(p.arcSagSource.line == 2);
    }
}

TEST_CASE("arcs: an APT CIRCLE's chords stay within the tolerance, and its sag is recorded", "[path][apt]") {
    for (double tol : {0.01, 4.0, 6.0, 25.0}) {
        AptOptions o;
        o.chordTolerance = tol;
        // A full circle of radius 5 about the origin, from (5, 0, 0) back to it.
        const Program p = parseApt("CUTTER/2\nFROM/5,0,0\nCIRCLE/0,0,0,0,0,1,5\nGOTO/5,0,0\n", "c.apt", o);
        INFO("tolerance " << tol);
        const double found = farthestSample(p, 4, Vec3(0.0), 5.0, 0.0, 2 * kPi);
        CHECK(found <= tol + kRounding * 5.0);
        CHECK(found > 0.0);
        CHECK(p.arcSag >= found - kRounding * 5.0);
        CHECK(p.arcSag <= found + 5.0 * (1.0 - std::cos(kPi / kSamples)) + kRounding * 5.0);
    }
}

TEST_CASE("arcs: a program without arcs has no sag, and appending keeps the larger with its file",
          "[path][gcode]") {
    GcodeOptions o;
    o.startPosition = Vec3(0.0);
    o.chordTolerance = 0.5;
    Program a = parseGcode("G1 X10\nG1 Y10\n", "lines.ngc", o);
    CHECK(a.arcSag == 0.0);
    a.append(parseGcode("G1 X10\nG2 X0 Y0 I-5 J0\n", "arc.ngc", o));
    CHECK(a.arcSag > 0.0);
    CHECK(a.arcSag <= 0.5);
    CHECK(a.path.where(a.arcSagSource).file == "arc.ngc");
    CHECK(a.arcSagSource.line == 2);
}
