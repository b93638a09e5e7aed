// The random cases of the sweep's oracle tests (sweep_oracle_test.cpp, sweep_normals_test.cpp): a
// family per degenerate case of method.md section 5, each drawing a random tool of every kind
// (tool_models.h), a move and a line.
#pragma once

#include <iomanip>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "dexelmill/tool/tool.h"
#include "oracle.h"
#include "tool_models.h"

namespace cases {

using dexelmill::ArcPiece;
using dexelmill::ConePiece;
using dexelmill::Line;
using dexelmill::ProfilePiece;
using dexelmill::Tool;
using dexelmill::Vec3;

enum class Family {
    General,         ///< any tool axis, any feed, any dexel direction
    ThreeAxis,       ///< axis +z, dexels along x, y, z (the tri-dexel stock's case)
    Horizontal,      ///< n . f = 0
    Plunge,          ///< f parallel to n, both senses
    ZeroLength,      ///< f = 0 (and |f| below the zero-move tolerance)
    DexelAlongMove,  ///< w x f = 0
    DexelAlongAxis,  ///< w parallel to the tool axis
    NearDegenerate,  ///< within 1e-14 .. 1e-3 rad of each of the above; tiny moves
    TinyAcross,      ///< 1e-4 .. 1e-3 mm long, 1e-12 .. 1e-10 rad off horizontal, lines by a rim
    DexelInFace,     ///< horizontal move, the line lying in the bottom or top face's plane
    Regions,         ///< the cutting part [0, Lc] and the shank [Lc, L] swept separately
    SymmetryPlane    ///< axis z, a move along x or y, the line in the plane of the axis and feed
};

inline Vec3 randomUnit(std::mt19937_64& rng) {
    std::normal_distribution<double> g;
    Vec3 v;
    do v = Vec3(g(rng), g(rng), g(rng));
    while (glm::length(v) < 1e-3);
    return glm::normalize(v);
}

/// A unit vector perpendicular to n.
inline Vec3 randomPerpendicular(std::mt19937_64& rng, const Vec3& n) {
    Vec3 v;
    do {
        v = randomUnit(rng);
        v -= glm::dot(v, n) * n;
    } while (glm::length(v) < 1e-3);
    return glm::normalize(v);
}

inline double uniform(std::mt19937_64& rng, double a, double b) { return models::uniform(rng, a, b); }

inline std::string str(const Vec3& v) {
    std::ostringstream s;
    s << std::setprecision(17) << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return s.str();
}

inline std::string str(const Tool& tool) {
    std::ostringstream s;
    s << std::setprecision(17) << "Tool(\"" << tool.description() << "\", {";
    for (const ProfilePiece& p : tool.pieces()) {
        if (const auto* c = std::get_if<ConePiece>(&p))
            s << "ConePiece{" << c->z0 << ", " << c->z1 << ", " << c->r0 << ", " << c->r1 << "}, ";
        else if (const auto* a = std::get_if<ArcPiece>(&p))
            s << "ArcPiece{" << a->z0 << ", " << a->z1 << ", " << a->rc << ", " << a->zc << ", " << a->rho << "}, ";
    }
    s << "}, " << tool.cuttingLength() << ")";
    return s.str();
}

inline std::string str(const std::vector<dexelmill::Interval>& ivs) {
    std::ostringstream s;
    s << std::setprecision(17) << "{";
    for (const dexelmill::Interval& i : ivs) s << " [" << i.lo << ", " << i.hi << "]";
    return s.str() + " }";
}

/// One random case of a family: a tool (or a region of it) with the oracle's parts of the same
/// solid, a move (tip from ps to ps + f, axis n) and a line.
struct Case {
    models::Kind kind = models::Kind::Flat;
    std::optional<models::Model> model;
    std::optional<Tool> region;
    std::vector<oracle::Part> parts;
    Vec3 ps{0.0}, f{0.0}, n{0.0};
    Line line;

    const Tool& tool() const { return region ? *region : model->tool; }
};

inline Case makeCase(Family family, std::mt19937_64& rng) {
    Case c;
    c.kind = models::Kind(rng() % int(models::Kind::Count));
    if (family == Family::DexelInFace && c.kind == models::Kind::NonConvex) c.kind = models::Kind::Flat;
    c.model.emplace(models::make(c.kind, rng));
    const models::Model& model = *c.model;
    std::vector<oracle::Part>& parts = c.parts;
    parts = model.parts;
    if (family == Family::Regions) {
        const double lc = model.tool.cuttingLength(), total = model.tool.totalLength();
        const bool shank = lc < total - 1e-6 && rng() % 2;
        const double z0 = shank ? lc : 0.0, z1 = shank ? total : lc;
        c.region.emplace(model.tool.region(z0, z1));
        parts = models::clip(model.parts, z0, z1);
    }
    const double length = parts.back().zb;
    double rBound = 0.0;
    for (const oracle::Part& p : parts) rBound = std::max(rBound, p.rBound);

    // The move.
    Vec3 &n = c.n, &ps = c.ps, &f = c.f;
    n = (family == Family::ThreeAxis || family == Family::DexelInFace || family == Family::SymmetryPlane ||
         rng() % 4 == 0)
            ? Vec3(0, 0, 1)
            : randomUnit(rng);
    ps = Vec3(uniform(rng, -10, 10), uniform(rng, -10, 10), uniform(rng, -10, 10));
    double len = rng() % 10 == 0 ? uniform(rng, 1e-3, 0.5) : uniform(rng, 0.5, 40.0);
    f = len * randomUnit(rng);
    Vec3 w = randomUnit(rng);
    switch (family) {
    case Family::General:
    case Family::Regions:
        break;
    case Family::ThreeAxis: {
        const int m = int(rng() % 6);
        if (m == 0) f = Vec3(0, 0, rng() % 2 ? len : -len);
        else if (m <= 2) f.z = 0.0;
        w = Vec3(0.0);
        w[int(rng() % 3)] = 1.0;
        break;
    }
    case Family::Horizontal:
        f = len * randomPerpendicular(rng, n);
        if (n == Vec3(0, 0, 1)) f.z = 0.0;
        break;
    case Family::Plunge:
        f = (rng() % 2 ? len : -len) * n;
        break;
    case Family::ZeroLength:
        f = rng() % 2 ? Vec3(0.0) : 1e-10 * randomUnit(rng);
        break;
    case Family::DexelAlongMove:
        w = (rng() % 2 ? 1.0 : -1.0) * glm::normalize(f);
        break;
    case Family::DexelAlongAxis:
        w = rng() % 2 ? n : -n;
        break;
    case Family::NearDegenerate: {
        // Angles from 1e-14 to 1e-3 rad straddle the solver's switches (horizontal below 1e-12,
        // parallel to the feed below 1e-9); one move in four is 1e-9 to 1e-3 mm long, across
        // the zero-length switch.
        const double eps = std::pow(10.0, uniform(rng, -14.0, -3.0));
        if (rng() % 4 == 0) f = std::pow(10.0, uniform(rng, -9.0, -3.0)) * glm::normalize(f);
        const Vec3 perp = randomPerpendicular(rng, n);
        switch (rng() % 4) {
        case 0:  // nearly horizontal
            f = len * glm::normalize(perp + (rng() % 2 ? eps : -eps) * n);
            break;
        case 1:  // nearly a plunge
            f = (rng() % 2 ? len : -len) * glm::normalize(n + eps * perp);
            break;
        case 2:  // dexel nearly along the move
            w = glm::normalize(glm::normalize(f) + eps * randomPerpendicular(rng, glm::normalize(f)));
            break;
        default:  // dexel nearly along the axis
            w = glm::normalize(n + eps * perp);
            break;
        }
        break;
    }
    case Family::TinyAcross: {
        // The moves a turning sweep's pure rotation makes of its nodes (turning.cpp, note h): a
        // tip stepping across the axis by a micrometre or less, its axial part near rounding (a
        // rim's feed parameter is its height over that part). The line, within 30 degrees of
        // the axis, crosses the bottom or top face's plane within two move lengths of its rim.
        const double eps = std::pow(10.0, uniform(rng, -12.0, -10.0));
        f = std::pow(10.0, uniform(rng, -4.0, -3.0)) *
            glm::normalize(randomPerpendicular(rng, n) + (rng() % 2 ? eps : -eps) * n);
        w = glm::normalize((rng() % 2 ? 1.0 : -1.0) * n + uniform(rng, 0.0, 0.58) * randomPerpendicular(rng, n));
        break;
    }
    case Family::SymmetryPlane: {
        // Exact coordinates, so that the line lies exactly in the move's plane of symmetry.
        const int along = int(rng() % 2);
        f = Vec3(0.0);
        f[along] = std::round(uniform(rng, -30, 30));
        f.z = rng() % 3 == 0 ? 0.0 : std::round(uniform(rng, -10, 10));
        if (f == Vec3(0.0)) f.z = 1.0;
        w = Vec3(0.0);
        const double a = uniform(rng, 0.0, 2 * models::kPi);
        w[along] = std::cos(a), w.z = std::sin(a);
        if (rng() % 3 == 0) w = Vec3(0, 0, 1);
        break;
    }
    case Family::DexelInFace:
        // The tip at height 0 so that the face heights below are exact sums.
        ps = Vec3(std::round(ps.x), std::round(ps.y), 0.0);
        f.z = 0.0;
        w = rng() % 2 ? Vec3(double(rng() % 2), 0.0, 0.0) : randomUnit(rng);
        w.z = 0.0;
        if (glm::length(w) < 1e-3) w = Vec3(0, 1, 0);
        w = glm::normalize(w);
        break;
    }

    // The line: through a random point near the sweep, its origin well away from it.
    const Vec3 radial = randomPerpendicular(rng, n);
    const double z = length * std::pow(uniform(rng, 0.0, 1.0), 2.0) * 1.1 - 0.05 * length;
    const Vec3 anchor = ps + uniform(rng, -0.15, 1.15) * f + z * n + uniform(rng, 0.0, 1.3 * rBound) * radial;
    Line& line = c.line;
    line = Line{anchor - uniform(rng, 5.0, 60.0) * w, w};
    if (family == Family::DexelInFace) {
        line.origin.z = rng() % 2 ? ps.z + parts.front().za : ps.z + parts.back().zb;
    }
    if (family == Family::TinyAcross) {
        const double face = rng() % 2 ? parts.front().za : parts.back().zb;
        const double rim = parts.front().za == face ? parts.front().radius(face) : parts.back().radius(face);
        const Vec3 near = ps + face * n + (rim + uniform(rng, -2.0, 2.0) * glm::length(f)) * radial;
        line = Line{near - uniform(rng, 5.0, 60.0) * w, w};
    }
    if (family == Family::SymmetryPlane) {
        const int across = f.x != 0.0 ? 1 : 0;  // the coordinate the plane fixes
        line.origin[across] = ps[across];
    }
    return c;
}

/// The case in words, with the numbers to rebuild it.
inline std::string describe(const Case& c) {
    std::ostringstream s;
    s << c.tool().description() << " (" << models::name(c.kind) << ") start " << str(c.ps) << " feed " << str(c.f)
      << " axis " << str(c.n) << "\n   " << str(c.tool()) << "\n   line " << str(c.line.origin) << " dir "
      << str(c.line.dir);
    return s.str();
}

}  // namespace cases
