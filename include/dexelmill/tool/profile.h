/// @file profile.h
/// @brief Cutter profiles as chains of canal-surface pieces (method.md section 2, the paper's
/// Eqs. 3-12) in the (radial, axial) half-plane of the tool frame.
///
/// A tool is the solid of revolution { 0 <= z <= L, rho <= R(z) } around its axis, where z is the
/// height above the tip (the cutter-location point) and rho the distance from the axis. R(z) is
/// given piecewise by the chain. The bottom face (R(0) > 0), the top cap at z = L and any step
/// where R jumps between pieces are flat annular disks; they are implied by the chain and need no
/// piece of their own.
#pragma once

#include <variant>
#include <vector>

namespace dexelmill {

/// @brief A cone frustum on [z0, z1]: R linear from r0 to r1. A cylinder when r0 == r1.
/// Its spine is the axis and its sphere radius is linear in z (a canal surface with a linear
/// spine).
struct ConePiece {
    double z0 = 0.0, z1 = 0.0;
    double r0 = 0.0, r1 = 0.0;
};

/// @brief The outer half of a circle (centre (rc, zc), radius rho) revolved about the axis, on
/// [z0, z1] within [zc - rho, zc + rho]: R(z) = rc + sqrt(rho^2 - (z - zc)^2).
/// A sphere when rc == 0, a torus (the fillet of a bull-nose cutter) when rc > 0: a pipe surface
/// whose spine is the circle of radius rc at height zc.
struct ArcPiece {
    double z0 = 0.0, z1 = 0.0;
    double rc = 0.0, zc = 0.0, rho = 0.0;
};

using ProfilePiece = std::variant<ConePiece, ArcPiece>;

/// @brief The lowest height of a piece.
double pieceZ0(const ProfilePiece& piece);
/// @brief The highest height of a piece.
double pieceZ1(const ProfilePiece& piece);
/// @brief R(z) of a piece; z is clamped to the piece's range.
double pieceRadius(const ProfilePiece& piece, double z);
/// @brief dR/dz of a piece at z (one-sided at the ends; +-infinity where an arc is vertical).
double pieceSlope(const ProfilePiece& piece, double z);

/// @brief The pieces [first, last) of a chain cut to the heights [z0, z1]: each piece that
/// reaches more than tol::kLength into them, its ends moved to z0 and z1 where it passes them (a
/// cone's radii interpolated, an arc keeping its circle). A piece cut to a sliver is left out, so
/// a caller that needs the whole range keeps z0 and z1 off the chain's joints.
std::vector<ProfilePiece> clipChain(const std::vector<ProfilePiece>& pieces, std::size_t first, std::size_t last,
                                    double z0, double z1);

}  // namespace dexelmill
