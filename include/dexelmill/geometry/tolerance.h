/// @file tolerance.h
/// @brief Named tolerances. Lengths are in mm. Every comparison that is not exact names one of
/// these, so a reader can see what is being decided and at which scale.
#pragma once

namespace dexelmill::tol {

/// Two lengths closer than this are the same length (mm). Far below any machining tolerance and
/// far above double rounding for parts up to a few metres.
constexpr double kLength = 1e-9;

/// Directions whose unit vectors' cross product is shorter than this are parallel
/// (sine of the angle between them).
constexpr double kParallel = 1e-12;

/// A move shorter than this is a zero-length move (mm): the tool just sits.
constexpr double kZeroMove = 1e-9;

/// Profile chains: consecutive pieces must meet within this distance (mm).
constexpr double kProfileJoint = 1e-7;

/// Profile slopes dR/dz that differ by less than this count as equal when deciding whether a
/// joint between two pieces is convex (dimensionless).
constexpr double kSlope = 1e-9;

/// Root finders stop when the bracket is this narrow relative to the problem scale (mm).
constexpr double kRoot = 1e-12;

/// A triangle whose doubled area |(b-a) x (c-a)| is at most this times its longest squared edge
/// is degenerate (a sliver with all three vertices on one line, or a point).
constexpr double kDegenerateTriangle = 1e-12;

}  // namespace dexelmill::tol
