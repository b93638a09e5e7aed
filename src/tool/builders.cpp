#include "dexelmill/tool/builders.h"

#include <cmath>
#include <sstream>

#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// CL files print CUTTER values with about six significant digits, so an APT profile that should
/// meet the axis or a corner exactly may miss it by this much relative to the diameter.
constexpr double kAptDigits = 1e-6;

std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

std::string deg(double radians) { return num(radians * 180.0 / kPi) + " deg"; }

[[noreturn]] void bad(const std::string& tool, const std::string& what) {
    throw Error(tool + ": " + what);
}

/// Refuses a length beyond kMaxToolSizeMm.
void requireWithinSize(const std::string& tool, const char* name, double v) {
    if (v <= kMaxToolSizeMm) return;
    const auto [value, cap] = decimalsApart(v, kMaxToolSizeMm);
    bad(tool, std::string(name) + " = " + value + " mm is beyond the " + cap + " mm a tool may measure");
}

/// A length that must be positive and within kMaxToolSizeMm.
void requirePositiveLength(const std::string& tool, const char* name, double v) {
    if (!(v > 0.0)) bad(tool, std::string(name) + " must be positive, got " + num(v));
    requireWithinSize(tool, name, v);
}

/// A length that must not be negative and be within kMaxToolSizeMm.
void requireLength(const std::string& tool, const char* name, double v) {
    if (!(v >= 0.0)) bad(tool, std::string(name) + " must not be negative, got " + num(v));
    requireWithinSize(tool, name, v);
}

/// An angle in [0, 90 deg) (or (0, 90) when `open` is set), e.g. a flank angle.
void requireAngle(const std::string& tool, const char* name, double a, bool positive) {
    if (!std::isfinite(a) || a < 0.0 || (positive && a == 0.0) || a >= 0.5 * kPi)
        bad(tool, std::string(name) + " must lie in " + (positive ? "(0" : "[0") + ", 90) deg, got " + deg(a));
}

/// The end a profile shapes below its cylinder (a ball, a drill's point): its height, which the
/// total length must clear, and what it is, for messages. None for a flat or taper end.
struct ShapedEnd {
    double height = 0.0;
    const char* what = nullptr;
};

/// Resolves default lengths: cutting length 3 diameters (at least 10 mm and the shaped end),
/// total length 2 diameters more than the cutting length or the shaped end, whichever is longer,
/// neither beyond kMaxToolSizeMm. A total length given alone caps the default cutting length: the
/// tool asked for is no longer.
ToolLengths resolve(const std::string& tool, ToolLengths l, double diameter, ShapedEnd end = {}) {
    requireLength(tool, "cutting length", l.cutting);
    requireLength(tool, "total length", l.total);
    if (end.what) requireWithinSize(tool, (std::string("the ") + end.what + "'s height").c_str(), end.height);
    if (l.cutting == 0.0) {
        l.cutting = std::min(std::max({3.0 * diameter, 10.0, end.height}), kMaxToolSizeMm);
        if (l.total != 0.0) l.cutting = std::min(l.cutting, l.total);
    }
    if (l.total == 0.0) l.total = std::min(std::max(l.cutting, end.height) + 2.0 * diameter, kMaxToolSizeMm);
    if (end.what && l.total <= end.height + tol::kLength) {
        const auto [total, height] = decimalsApart(l.total, end.height);
        bad(tool, "total length " + total + " mm does not clear the " + height + " mm " + end.what);
    }
    if (l.total < l.cutting) {
        const auto [total, cutting] = decimalsApart(l.total, l.cutting);
        bad(tool, "total length " + total + " mm is shorter than the cutting length " + cutting + " mm");
    }
    return l;
}

std::string name(const std::string& kind, const ToolLengths& l) {
    return kind + " L" + num(l.cutting) + "/" + num(l.total);
}

/// Appends a cylinder of radius r from the last piece's top to height z1.
void addShank(std::vector<ProfilePiece>& pieces, double z0, double z1, double r) {
    if (z1 > z0 + tol::kLength) pieces.push_back(ConePiece{z0, z1, r, r});
}

}  // namespace

Tool flatEndMill(double d, ToolLengths lengths) {
    const std::string who = "flat end mill";
    requirePositiveLength(who, "diameter d", d);
    const ToolLengths l = resolve(who, lengths, d);
    return Tool(name("flat D" + num(d), l), {ConePiece{0.0, l.total, d / 2, d / 2}}, l.cutting);
}

Tool ballEndMill(double d, ToolLengths lengths) {
    const std::string who = "ball end mill";
    requirePositiveLength(who, "diameter d", d);
    const double r = d / 2;
    const ToolLengths l = resolve(who, lengths, d, {r, "ball"});
    return Tool(name("ball D" + num(d), l), {ArcPiece{0.0, r, 0.0, r, r}, ConePiece{r, l.total, r, r}},
                l.cutting);
}

Tool bullNoseEndMill(double d, double r, ToolLengths lengths) {
    const std::string who = "bull-nose end mill";
    requirePositiveLength(who, "diameter d", d);
    requirePositiveLength(who, "corner radius r", r);
    if (r > d / 2 + tol::kLength) bad(who, "corner radius r = " + num(r) + " exceeds d/2 = " + num(d / 2));
    r = std::min(r, d / 2);
    const ToolLengths l = resolve(who, lengths, d, {r, "corner"});
    return Tool(name("bull D" + num(d) + " R" + num(r), l),
                {ArcPiece{0.0, r, d / 2 - r, r, r}, ConePiece{r, l.total, d / 2, d / 2}}, l.cutting);
}

Tool taperEndMill(double tipD, double halfAngle, ToolLengths lengths) {
    const std::string who = "taper end mill";
    requireLength(who, "tip diameter", tipD);
    requireAngle(who, "half angle", halfAngle, true);
    const ToolLengths l = resolve(who, lengths, std::max(tipD, 1.0));
    const double rTop = tipD / 2 + l.cutting * std::tan(halfAngle);
    std::vector<ProfilePiece> pieces{ConePiece{0.0, l.cutting, tipD / 2, rTop}};
    addShank(pieces, l.cutting, l.total, rTop);
    return Tool(name("taper D" + num(tipD) + " A" + deg(halfAngle), l), std::move(pieces), l.cutting);
}

Tool chamferMill(double tipD, double halfAngle, double d, ToolLengths lengths) {
    const std::string who = "chamfer mill";
    requireLength(who, "tip diameter", tipD);
    requirePositiveLength(who, "diameter d", d);
    requireAngle(who, "half angle", halfAngle, true);
    if (!(d > tipD)) bad(who, "diameter d = " + num(d) + " must exceed the tip diameter " + num(tipD));
    const double hCone = (d - tipD) / 2 / std::tan(halfAngle);
    const ToolLengths l = resolve(who, lengths, d, {hCone, "cone"});
    std::vector<ProfilePiece> pieces{ConePiece{0.0, hCone, tipD / 2, d / 2}};
    addShank(pieces, hCone, l.total, d / 2);
    return Tool(name("chamfer D" + num(d) + " tip " + num(tipD) + " A" + deg(halfAngle), l), std::move(pieces),
                l.cutting);
}

Tool taperBallMill(double ballD, double halfAngle, ToolLengths lengths) {
    const std::string who = "tapered ball mill";
    requirePositiveLength(who, "ball diameter", ballD);
    requireAngle(who, "half angle", halfAngle, false);
    const double rb = ballD / 2;
    // The flank touches the sphere where the sphere's normal is perpendicular to it.
    const double zT = rb * (1.0 - std::sin(halfAngle));
    const double rT = rb * std::cos(halfAngle);
    const ToolLengths l = resolve(who, lengths, ballD, {rb, "ball"});
    const double rTop = rT + (l.cutting - zT) * std::tan(halfAngle);
    std::vector<ProfilePiece> pieces{ArcPiece{0.0, zT, 0.0, rb, rb}};
    if (halfAngle == 0.0) {
        pieces.push_back(ConePiece{zT, l.total, rb, rb});
    } else {
        pieces.push_back(ConePiece{zT, l.cutting, rT, rTop});
        addShank(pieces, l.cutting, l.total, rTop);
    }
    return Tool(name("taper-ball D" + num(ballD) + " A" + deg(halfAngle), l), std::move(pieces), l.cutting);
}

Tool drill(double d, double pointAngle, ToolLengths lengths) {
    const std::string who = "drill";
    requirePositiveLength(who, "diameter d", d);
    if (!std::isfinite(pointAngle) || !(pointAngle > 0.0) || !(pointAngle < kPi))
        bad(who, "point angle must lie in (0, 180) deg, got " + deg(pointAngle));
    const double hTip = d / 2 / std::tan(pointAngle / 2);
    const ToolLengths l = resolve(who, lengths, d, {hTip, "point"});
    std::vector<ProfilePiece> pieces{ConePiece{0.0, hTip, 0.0, d / 2}};
    addShank(pieces, hTip, l.total, d / 2);
    return Tool(name("drill D" + num(d) + " P" + deg(pointAngle), l), std::move(pieces), l.cutting);
}

Tool aptCutter(double d, double r, double e, double f, double alpha, double beta, double h,
               double cuttingLength) {
    const std::string who = "CUTTER/" + num(d) + "," + num(r) + "," + num(e) + "," + num(f) + "," +
                            deg(alpha) + "," + deg(beta) + "," + num(h);
    requirePositiveLength(who, "d", d);
    requireLength(who, "r", r);
    requireLength(who, "e", e);
    requireLength(who, "f", f);
    requirePositiveLength(who, "h", h);
    requireAngle(who, "alpha", alpha, false);
    if (!std::isfinite(beta) || std::abs(beta) >= 0.5 * kPi)
        bad(who, "beta must lie in (-90, 90) deg, got " + deg(beta));
    if (r > d / 2 + tol::kLength) bad(who, "r = " + num(r) + " exceeds d/2 = " + num(d / 2));
    // The side flank touches the corner at T2; its radius there is the nominal d/2.
    const double r2 = e + r * std::cos(beta), z2 = f - r * std::sin(beta);
    const double dTol = 1e-3 * std::max(1.0, d);
    if (std::abs(r2 - d / 2) > dTol)
        bad(who, "d/2 = " + num(d / 2) + " does not match the corner, e + r cos(beta) = " + num(r2));
    // The bottom flank at alpha touches the corner at T1 (the corner point itself when r = 0).
    const double r1 = e + r * std::sin(alpha), z1 = f - r * std::cos(alpha);
    if (z1 < -kAptDigits * std::max(1.0, d)) bad(who, "the corner reaches below the tip: f - r cos(alpha) = " + num(z1));
    double rTip = r1;
    if (alpha > 0.0) rTip = r1 - z1 / std::tan(alpha);
    else if (z1 > kAptDigits * std::max(1.0, d))
        bad(who, "with alpha = 0 the bottom is flat, so f must equal r, got f = " + num(f) + ", r = " + num(r));
    if (rTip < -kAptDigits * std::max(1.0, d))
        bad(who, "the bottom flank meets the axis " + num(-rTip * std::tan(alpha)) + " mm above the tip");
    rTip = std::max(rTip, 0.0);
    if (!(h > std::max(z1, z2) + tol::kLength)) bad(who, "h = " + num(h) + " does not clear the corner");
    const double rTop = r2 + (h - z2) * std::tan(beta);
    if (rTop < 0.0) bad(who, "the side flank at beta = " + deg(beta) + " reaches the axis below h");

    std::vector<ProfilePiece> pieces;
    if (z1 > tol::kProfileJoint) pieces.push_back(ConePiece{0.0, z1, rTip, r1});
    if (r > 0.0 && z2 > std::max(z1, 0.0) + tol::kLength)
        pieces.push_back(ArcPiece{std::max(z1, 0.0), z2, e, f, r});
    pieces.push_back(ConePiece{pieces.empty() ? 0.0 : pieceZ1(pieces.back()), h, r2, rTop});
    if (cuttingLength == 0.0) cuttingLength = h;
    if (!(cuttingLength > 0.0) || cuttingLength > h + tol::kLength)
        bad(who, "cutting length " + num(cuttingLength) + " must lie in (0, h]");
    return Tool(who, std::move(pieces), cuttingLength);
}

}  // namespace dexelmill
