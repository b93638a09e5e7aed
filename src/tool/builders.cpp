#include "dexelmill/tool/builders.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

constexpr double kPi = 3.14159265358979323846;

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
    if (r > d / 2 + tol::kLength) {
        const auto [rText, halfD] = decimalsApart(r, d / 2);
        bad(who, "corner radius r = " + rText + " exceeds d/2 = " + halfD);
    }
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

Tool withHolder(const Tool& tool, double d, double length) {
    const std::string who = "holder of " + tool.description();
    requirePositiveLength(who, "diameter", d);
    requirePositiveLength(who, "length", length);
    const double top = tool.totalLength(), rTop = tool.radiusAt(top);
    if (d / 2 < rTop - tol::kLength) {
        const auto [dText, topText] = decimalsApart(d, 2 * rTop);
        bad(who, "diameter " + dText + " mm is narrower than the tool it holds, " + topText + " mm at its top");
    }
    std::vector<ProfilePiece> pieces = tool.pieces();
    pieces.push_back(ConePiece{top, top + length, d / 2, d / 2});
    Tool held(tool.description() + " holder D" + num(d) + " L" + num(length), std::move(pieces), tool.cuttingLength());
    held.holderBottom_ = top;
    return held;
}

double cutterRounding(double value, double unit) {
    // Half a unit in the sixth significant digit is at most this fraction of the value (1.00000
    // to 9.99999: 5e-6 to 5e-7).
    constexpr double kSixDigits = 5e-6;
    // Half a unit in the fourth decimal place.
    constexpr double kFourDecimals = 5e-5;
    return std::max(kSixDigits * std::abs(value), kFourDecimals * unit);
}

Tool aptCutter(double d, double r, double e, double f, double alpha, double beta, double h,
               double cuttingLength, double lengthUnit) {
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
    // Each relation among the values holds within what their printing may have moved it: the
    // rounding of each value times the relation's slope in it (angles in radians).
    const auto printed = [lengthUnit](double length) { return cutterRounding(length, lengthUnit); };
    const auto printedAngle = [](double angle) { return cutterRounding(angle / kPi * 180.0, 1.0) * kPi / 180.0; };
    if (r - d / 2 > printed(r) + printed(d) / 2) {
        const auto [rText, halfD] = decimalsApart(r, d / 2);
        bad(who, "r = " + rText + " exceeds d/2 = " + halfD);
    }
    // The side flank touches the corner at T2; its radius there is the nominal d/2.
    const double r2 = e + r * std::cos(beta), z2 = f - r * std::sin(beta);
    if (std::abs(r2 - d / 2) > printed(d) / 2 + printed(e) + printed(r) + r * printedAngle(beta)) {
        const auto [dText, cornerD] = decimalsApart(d, 2 * r2);
        bad(who, "d = " + dText + " is not the diameter its corner makes, 2 (e + r cos(beta)) = " + cornerD);
    }
    // The bottom flank at alpha touches the corner at T1 (the corner point itself when r = 0).
    const double r1 = e + r * std::sin(alpha), z1 = f - r * std::cos(alpha);
    const double z1Printed = printed(f) + printed(r) + r * printedAngle(alpha);
    if (z1 < -z1Printed) bad(who, "the corner reaches below the tip: f - r cos(alpha) = " + num(z1));
    double rTip = r1;
    if (alpha > 0.0) {
        rTip = r1 - z1 / std::tan(alpha);
        // d rTip / d(e, r, f, alpha) = (1, 1 / sin(alpha), -1 / tan(alpha), z1 / sin(alpha)^2).
        const double sinA = std::sin(alpha);
        const double rTipPrinted = printed(e) + printed(r) / sinA + printed(f) / std::tan(alpha) +
                                   std::abs(z1) * printedAngle(alpha) / (sinA * sinA);
        if (rTip < -rTipPrinted)
            bad(who, "the bottom flank meets the axis " + num(-rTip * std::tan(alpha)) + " mm above the tip");
    } else if (z1 > z1Printed) {
        const auto [fText, rText] = decimalsApart(f, r);
        bad(who, "with alpha = 0 the bottom is flat, so f must equal r, got f = " + fText + ", r = " + rText);
    }
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
