/// @file offset.h
/// @brief A convex part of a tool grown by a distance r: the set of points within r of it, as a
/// chain of profile pieces in the same tool frame. The sweep of a turning tool (turning.h) bounds
/// the poses between two it has solved by such offsets.
///
/// The offset of a solid of revolution is a solid of revolution, and its meridian section is the
/// section grown by a disk of radius r. For a convex section the boundary of the grown section is
/// the boundary moved out by r along its outward normals, with a circular arc of radius r round
/// every corner where the normal jumps:
///  - a cone piece (normal constant along it) moves by r times its normal: a cone of the same
///    height;
///  - an arc piece of radius rho keeps its centre and gets radius rho + r;
///  - the bottom face (normal -z) moves down by r and the top face (normal +z) up by r; they need
///    no piece (the chain's slab solids hold them);
///  - a corner between normals at angles psi_a < psi_b (psi = atan2(nz, nr), in [-pi/2, pi/2] and
///    increasing up a convex chain) becomes the arc piece of radius r centred on the corner,
///    heights zc + r sin(psi_a) to zc + r sin(psi_b). The bottom face meets the lowest piece at
///    (R(z0), z0), a corner even when R(z0) = 0 (a drill's or V-bit's apex); a ball's tip, whose
///    normal is already -z, has none.
/// The chain's heights start r below the part and end r above it, so they can be negative.
#pragma once

#include <vector>

#include "dexelmill/tool/line_query.h"
#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// @brief The pieces of `part` of `tool` grown by r >= 0, bottom to top (see the file comment).
std::vector<ProfilePiece> offsetPart(const Tool& tool, const ConvexPart& part, double r);

/// @brief A superset of `part` of `tool` grown by r >= 0 whose corners are polygons: each corner's
/// arc (offsetPart) is replaced by the tangents to it at steps of at most a quarter turn, which
/// meet at most r (sqrt 2 - 1) outside the arc; everything else is offsetPart's. A flat or
/// conical tool stays cones and faces, which sweep in closed form (MoveSweep), where offsetPart's
/// rims would be tori. Built from the part's own normal angles, not from the grown arcs' heights,
/// so it stays exact to rounding for r of any size against the part's.
std::vector<ProfilePiece> mitredOffsetPart(const Tool& tool, const ConvexPart& part, double r);
/// @brief As mitredOffsetPart, for a convex chain of pieces given on its own (bottom to top; its
/// solid closed by flat faces at its lowest and highest heights). Where slack > 0, each of the
/// chain's tori (an arc off the axis), grown, is also replaced by the chain of cones tangent to it
/// at evenly spaced normal angles (as OuterPart's), where at most maxCones keep that chain within
/// `slack` of the grown arc: a superset still, whose sweep along a move is in closed form where a
/// torus's needs its grazing curve solved per line (MoveSweep).
std::vector<ProfilePiece> mitredOffsetChain(const std::vector<ProfilePiece>& chain, double r, double slack = 0.0,
                                            int maxCones = 0);

/// @brief A part grown by r, for tests that need only a superset of a line's interval in it:
/// offsetPart's pieces, with each torus piece (an arc off the axis) also as the chain of cones
/// tangent to it at evenly spaced points, where at most kMaxTangentCones keep the chain within
/// `slack` of the arc. A torus without a chain has its interval's ends found to within `slack`
/// along the line, each taken from the outer side of its bracket (detail::outerTorusInterval).
///
/// The chain round an arc of radius a from normal angle psiA to psiB in n steps of d: the
/// tangents at psiA + i d meet at distance a / cos(d / 2) from the arc's centre, so the chain
/// holds the arc's slab solid and lies within a (1 / cos(d / 2) - 1) of it.
struct OuterPart {
    std::vector<ProfilePiece> pieces;
    /// Per piece: its tangent cones, bottom to top, or none (a cone, a sphere, or a torus whose
    /// chain would need too many).
    std::vector<std::vector<ConePiece>> chains;
    /// How far the part was grown.
    double growth = 0.0;
    /// How far beyond the grown part a torus's interval may reach.
    double slack = 0.0;
};

/// @brief `part` of `tool` grown by r >= 0, with tangent chains within slack > 0 of its tori.
OuterPart outerOffsetPart(const Tool& tool, const ConvexPart& part, double r, double slack);

/// Most cones that replace one torus piece in outerOffsetPart.
constexpr int kMaxTangentCones = 6;

namespace detail {

/// outerPieceInterval for piece i of `outer`, a torus, given the line's range in its slab (not
/// empty) and a hint for the root finding (outerTorusInterval).
inline Interval chainedTorusInterval(const OuterPart& outer, std::size_t i, const LocalLine& line,
                                     const Interval& slab, const Interval& near) {
    const ArcPiece& a = std::get<ArcPiece>(outer.pieces[i]);
    const std::vector<ConePiece>& chain = outer.chains[i];
    if (chain.empty()) return outerTorusInterval(a, line, slab, outer.slack, near, outer.growth);
    Interval iv;
    if (torusClosedForm(a, line, slab, iv)) return iv;
    for (const ConePiece& c : chain) iv = iv.hull(intersectCone(c, line));
    return iv;
}

}  // namespace detail

/// @brief An interval that holds the line's interval in piece i of the grown part, in the line's
/// local parameters: exact, except for a torus where it would need root finding (the line crosses
/// its surface): there the chain's interval, or without a chain the root finding's to within
/// the slack. So it lies within r + slack of the part. Inline: the turning sweep's settling test
/// calls it per piece.
inline Interval outerPieceInterval(const OuterPart& outer, std::size_t i, const LocalLine& line) {
    const auto* a = std::get_if<ArcPiece>(&outer.pieces[i]);
    if (!a || a->rc == 0.0) return intersectPiece(outer.pieces[i], line);
    const Interval slab = detail::slabRange(line, a->z0, a->z1);
    return slab.isEmpty() ? slab : detail::chainedTorusInterval(outer, i, line, slab, Interval::empty());
}

/// @brief An interval of `line` that holds its interval in the grown part: the hull of
/// outerPieceInterval over the pieces, in the line's own parameters (LocalLine::vShift added back).
Interval intersectOuter(const OuterPart& outer, const LocalLine& line);

/// @brief Whether `held` accepts, for each piece of the grown part, an interval that holds the
/// line's interval in that piece (line parameters, LocalLine::vShift added back; possibly empty).
/// The line's interval in a convex part is the union of its pieces' (the slab solids tile it along
/// the axis), so this is the test "does `held` accept the whole interval" for any `held` that
/// accepts an interval whenever it accepts a larger one; made piece by piece it can stop early.
/// A torus piece is first offered its slab within the outer cylinder (one square root), then
/// outerPieceInterval. `inside` (possibly empty; line parameters) is a hint for a torus's root
/// finding: the line's interval in the part before it was grown, whose ends lie about the growth
/// inside the grown part's. The answer does not depend on it.
template <class Held>
bool allPiecesHeld(const OuterPart& outer, const LocalLine& line, Held&& held,
                   const Interval& inside = Interval::empty()) {
    const auto shifted = [&](const Interval& iv) {
        return iv.isEmpty() ? iv : Interval{iv.lo + line.vShift, iv.hi + line.vShift};
    };
    const Interval near = inside.isEmpty() ? inside : Interval{inside.lo - line.vShift, inside.hi - line.vShift};
    for (std::size_t i = 0; i < outer.pieces.size(); ++i) {
        const auto* a = std::get_if<ArcPiece>(&outer.pieces[i]);
        if (!a || a->rc == 0.0) {
            if (!held(shifted(intersectPiece(outer.pieces[i], line)))) return false;
            continue;
        }
        const Interval slab = detail::slabRange(line, a->z0, a->z1);
        if (slab.isEmpty() || held(shifted(slab.intersect(detail::cylinderRange(line, a->rc + a->rho))))) continue;
        if (!held(shifted(detail::chainedTorusInterval(outer, i, line, slab, near)))) return false;
    }
    return true;
}

/// @brief The interval of `line` inside the convex solid that `pieces` describe (the hull of the
/// pieces' slab solids), in the line's own parameters (LocalLine::vShift added back).
Interval intersectPieces(const std::vector<ProfilePiece>& pieces, const LocalLine& line);

}  // namespace dexelmill
