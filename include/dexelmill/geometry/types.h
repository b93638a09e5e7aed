/// @file types.h
/// @brief Plain geometric value types in double precision: vectors, lines, intervals, boxes.
/// Lengths are in mm.
#pragma once

#include <algorithm>
#include <limits>

#include <glm/vec3.hpp>
#include <glm/geometric.hpp>

namespace dexelmill {

using Vec3 = glm::dvec3;

/// @brief A closed interval [lo, hi] of a line parameter or coordinate. Empty when lo > hi
/// (or either end is NaN); the default is empty.
struct Interval {
    double lo = std::numeric_limits<double>::infinity();
    double hi = -std::numeric_limits<double>::infinity();

    static Interval empty() { return {}; }
    static Interval all() {
        return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    }
    bool isEmpty() const { return !(lo <= hi); }
    double length() const { return isEmpty() ? 0.0 : hi - lo; }
    bool contains(double v) const { return lo <= v && v <= hi; }
    /// @brief The smallest interval holding both.
    Interval hull(const Interval& o) const {
        if (o.isEmpty()) return *this;
        if (isEmpty()) return o;
        return {std::min(lo, o.lo), std::max(hi, o.hi)};
    }
    Interval intersect(const Interval& o) const {
        return {std::max(lo, o.lo), std::min(hi, o.hi)};
    }
};

/// @brief The line I(v) = origin + v dir (the paper's Eq. 22). `dir` is a unit vector where the
/// caller says so; the parameter v is then a length in mm.
struct Line {
    Vec3 origin{0.0};
    Vec3 dir{0.0, 0.0, 1.0};

    Vec3 at(double v) const { return origin + v * dir; }
};

/// @brief The stretch of a line inside a solid with the solid's Hermite data at its ends: the
/// interval of line parameters, and the solid's outward unit normal where the line enters (lo) and
/// leaves (hi). An end on an edge or corner of the solid, where it has no single normal, is marked
/// sharp, and its normal is then one from the edge's normal cone. An end whose normal is unknown
/// has the zero vector. Empty when the range is.
struct LineHit {
    Interval range;
    Vec3 normalLo{0.0};
    Vec3 normalHi{0.0};
    bool sharpLo = false;
    bool sharpHi = false;

    bool isEmpty() const { return range.isEmpty(); }
};

/// @brief An axis-aligned box. Empty when any lo > hi; the default is empty.
struct Box {
    Vec3 lo{std::numeric_limits<double>::infinity()};
    Vec3 hi{-std::numeric_limits<double>::infinity()};

    static Box empty() { return {}; }
    bool isEmpty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
    Vec3 size() const { return isEmpty() ? Vec3(0.0) : hi - lo; }
    Vec3 center() const { return 0.5 * (lo + hi); }
    double volume() const {
        const Vec3 s = size();
        return s.x * s.y * s.z;
    }
    void expand(const Vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void expand(const Box& b) {
        if (b.isEmpty()) return;
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
    /// @brief Grows the box by `margin` on every side.
    Box padded(double margin) const { return isEmpty() ? *this : Box{lo - margin, hi + margin}; }
    bool contains(const Vec3& p) const {
        return lo.x <= p.x && p.x <= hi.x && lo.y <= p.y && p.y <= hi.y && lo.z <= p.z &&
               p.z <= hi.z;
    }
    bool overlaps(const Box& b) const {
        return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y &&
               lo.z <= b.hi.z && b.lo.z <= hi.z;
    }
};

}  // namespace dexelmill
