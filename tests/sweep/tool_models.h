// Random tools for the sweep tests, each as a pair: the dexelmill::Tool the solver sweeps, and the
// oracle's own description of the same solid (oracle.h), written from the builder parameters with
// radius functions of its own, not from Tool::radiusAt or the profile pieces.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "dexelmill/tool/builders.h"
#include "dexelmill/tool/tool.h"
#include "oracle.h"

namespace models {

using dexelmill::Tool;
using dexelmill::ToolLengths;

constexpr double kPi = 3.14159265358979323846;

struct Model {
    Tool tool;
    std::vector<oracle::Part> parts;  ///< convex parts of the whole tool, bottom to top
};

inline double uniform(std::mt19937_64& rng, double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
}

/// sqrt(2 r z - z^2): the radius at height z of a sphere of radius r resting on z = 0.
inline double capRadius(double r, double z) { return std::sqrt(std::max(0.0, z * (2.0 * r - z))); }

/// Random cutting and total lengths above a shaped end of height `minimum`.
inline ToolLengths lengths(std::mt19937_64& rng, double minimum) {
    ToolLengths l;
    l.cutting = minimum + uniform(rng, 1.0, 20.0);
    l.total = (rng() % 4 == 0) ? l.cutting : l.cutting + uniform(rng, 1.0, 15.0);
    return l;
}

inline oracle::Part part(double za, double zb, std::function<double(double)> r, double rBound) {
    return oracle::Part{za, zb, std::move(r), rBound};
}

enum class Kind { Flat, Ball, Bull, Taper, Chamfer, VBit, TaperBall, Drill, Apt, NonConvex, Count };

inline const char* name(Kind k) {
    static const char* names[] = {"flat", "ball", "bull-nose", "taper", "chamfer", "V-bit",
                                  "taper-ball", "drill", "APT", "non-convex"};
    return names[int(k)];
}

/// A random tool of the given kind.
inline Model make(Kind kind, std::mt19937_64& rng) {
    switch (kind) {
    case Kind::Flat: {
        const double d = uniform(rng, 1.0, 20.0);
        const ToolLengths l = lengths(rng, 0.0);
        return {dexelmill::flatEndMill(d, l), {part(0, l.total, [d](double) { return d / 2; }, d / 2)}};
    }
    case Kind::Ball: {
        const double d = uniform(rng, 1.0, 20.0), r = d / 2;
        const ToolLengths l = lengths(rng, r);
        return {dexelmill::ballEndMill(d, l),
                {part(0, l.total, [r](double z) { return z < r ? capRadius(r, z) : r; }, r)}};
    }
    case Kind::Bull: {
        const double d = uniform(rng, 2.0, 20.0), r = uniform(rng, 0.1, 0.5) * d;
        const ToolLengths l = lengths(rng, r);
        const double inner = d / 2 - r;
        return {dexelmill::bullNoseEndMill(d, r, l),
                {part(0, l.total, [=](double z) { return z < r ? inner + capRadius(r, z) : d / 2; }, d / 2)}};
    }
    case Kind::Taper: {
        const double tipD = uniform(rng, 0.5, 10.0), a = uniform(rng, 1.0, 20.0) * kPi / 180;
        const ToolLengths l = lengths(rng, 0.0);
        const double lc = l.cutting, top = tipD / 2 + lc * std::tan(a);
        return {dexelmill::taperEndMill(tipD, a, l),
                {part(0, l.total, [=](double z) { return tipD / 2 + std::min(z, lc) * std::tan(a); }, top)}};
    }
    case Kind::Chamfer:
    case Kind::VBit: {
        const double tipD = kind == Kind::VBit ? 0.0 : uniform(rng, 0.5, 6.0);
        const double d = tipD + uniform(rng, 1.0, 16.0), a = uniform(rng, 15.0, 75.0) * kPi / 180;
        const ToolLengths l = lengths(rng, (d - tipD) / 2 / std::tan(a));
        return {dexelmill::chamferMill(tipD, a, d, l),
                {part(0, l.total, [=](double z) { return std::min(tipD / 2 + z * std::tan(a), d / 2); }, d / 2)}};
    }
    case Kind::TaperBall: {
        const double bd = uniform(rng, 1.0, 12.0), a = uniform(rng, 0.0, 15.0) * kPi / 180, rb = bd / 2;
        const ToolLengths l = lengths(rng, rb);
        const double lc = l.cutting;
        // The flank is tangent to the ball where the ball's normal is perpendicular to it: at
        // angle a below the ball's equator.
        const double zt = rb - rb * std::sin(a), rt = rb * std::cos(a);
        auto r = [=](double z) {
            return z <= zt ? capRadius(rb, z) : rt + (std::min(z, lc) - zt) * std::tan(a);
        };
        return {dexelmill::taperBallMill(bd, a, l), {part(0, l.total, r, r(lc) + rb)}};
    }
    case Kind::Drill: {
        const double d = uniform(rng, 1.0, 16.0), p = uniform(rng, 90.0, 140.0) * kPi / 180;
        const ToolLengths l = lengths(rng, d / 2 / std::tan(p / 2));
        return {dexelmill::drill(d, p, l),
                {part(0, l.total, [=](double z) { return std::min(z * std::tan(p / 2), d / 2); }, d / 2)}};
    }
    case Kind::Apt: {
        // CUTTER/d, r, e, f, alpha, beta, h: corner circle (e, f) of radius r, bottom flank at
        // alpha above the horizontal, side flank at beta from the vertical.
        const double r = (rng() % 4 == 0) ? 0.0 : uniform(rng, 0.2, 4.0);
        const double alpha = (rng() % 3 == 0) ? 0.0 : uniform(rng, 2.0, 30.0) * kPi / 180;
        double beta = uniform(rng, -5.0, 15.0) * kPi / 180;
        const double e = uniform(rng, 0.5, 6.0);
        // Lowest tangent point T1 = (e + r sin alpha, f - r cos alpha); a flat bottom (alpha = 0)
        // puts it on z = 0; otherwise choose its height, keeping the tip radius non-negative.
        const double r1 = e + r * std::sin(alpha);
        const double z1 = alpha == 0.0 ? 0.0 : uniform(rng, 0.0, 0.9) * r1 * std::tan(alpha);
        const double f = z1 + r * std::cos(alpha);
        const double hAbove = uniform(rng, 3.0, 25.0);
        // A narrowing side flank must not reach the axis below the top.
        if (e + (hAbove + 2 * r) * std::tan(beta) < 0.2) beta = 0.0;
        const double r2 = e + r * std::cos(beta), z2 = f - r * std::sin(beta);
        const double h = std::max(z1, z2) + hAbove;
        const double lc = (rng() % 2) ? h : uniform(rng, std::max(z1, z2) + 0.5, h);
        const double rTip = alpha == 0.0 ? r1 : r1 - z1 / std::tan(alpha);
        auto R = [=](double z) {
            if (z < z1) return rTip + (r1 - rTip) * (z / z1);               // bottom flank
            if (z <= z2) return e + std::sqrt(std::max(0.0, r * r - (z - f) * (z - f)));  // corner
            return r2 + (z - z2) * std::tan(beta);                         // side flank
        };
        const double bound = std::max({r1, r2, R(h), e + r});
        return {dexelmill::aptCutter(2 * r2, r, e, f, alpha, beta, h, lc), {part(0, h, R, bound)}};
    }
    case Kind::NonConvex:
    default: {
        // Three shapes, randomly scaled: a stepped shank, an hourglass, a ball with a neck.
        const double s = uniform(rng, 0.5, 2.0);
        using dexelmill::ArcPiece;
        using dexelmill::ConePiece;
        switch (rng() % 3) {
        case 0:
            return {Tool("stepped", {ConePiece{0, 4 * s, 3 * s, 3 * s}, ConePiece{4 * s, 12 * s, 1.5 * s, 1.5 * s},
                                     ConePiece{12 * s, 20 * s, 4 * s, 4 * s}},
                         20 * s),
                    {part(0, 4 * s, [s](double) { return 3 * s; }, 3 * s),
                     part(4 * s, 12 * s, [s](double) { return 1.5 * s; }, 1.5 * s),
                     part(12 * s, 20 * s, [s](double) { return 4 * s; }, 4 * s)}};
        case 1:
            return {Tool("hourglass", {ConePiece{0, 5 * s, 4 * s, 2 * s}, ConePiece{5 * s, 12 * s, 2 * s, 5 * s}}, 12 * s),
                    {part(0, 5 * s, [s](double z) { return 4 * s - 0.4 * z; }, 4 * s),
                     part(5 * s, 12 * s, [s](double z) { return 2 * s + (z - 5 * s) * 3.0 / 7.0; }, 5 * s)}};
        default:
            return {Tool("necked ball", {ArcPiece{0, 3 * s, 0, 3 * s, 3 * s}, ConePiece{3 * s, 6 * s, 3 * s, 3 * s},
                                         ConePiece{6 * s, 9 * s, 3 * s, 1.5 * s}, ConePiece{9 * s, 25 * s, 1.5 * s, 1.5 * s}},
                         15 * s),
                    {part(0, 9 * s,
                          [s](double z) {
                              if (z < 3 * s) return capRadius(3 * s, z);
                              return z < 6 * s ? 3 * s : 3 * s - 0.5 * (z - 6 * s);
                          },
                          3 * s),
                     part(9 * s, 25 * s, [s](double) { return 1.5 * s; }, 1.5 * s)}};
        }
    }
    }
}

/// The oracle parts of the tool restricted to heights [z0, z1] (Tool::region).
inline std::vector<oracle::Part> clip(const std::vector<oracle::Part>& parts, double z0, double z1) {
    std::vector<oracle::Part> out;
    for (const oracle::Part& p : parts) {
        const double a = std::max(p.za, z0), b = std::min(p.zb, z1);
        if (b > a) out.push_back({a, b, p.radius, p.rBound});
    }
    return out;
}

}  // namespace models
