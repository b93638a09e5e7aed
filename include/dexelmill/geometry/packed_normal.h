/// @file packed_normal.h
/// @brief A unit surface normal in 32 bits, for the Hermite data kept at every dexel segment end:
/// the octahedral encoding (Meyer et al. 2010, "On floating-point normal vectors"; Cigolle et al.
/// 2014, "A survey of efficient representations for independent unit vectors").
///
/// The unit sphere is mapped onto the octahedron |x| + |y| + |z| = 1, whose lower half is folded
/// over the upper one onto the square [-1, 1]^2. Each coordinate of the square is stored in 15
/// bits. Bit 30 marks a sharp end (the surface has no single normal there: an edge or corner of
/// the solid; the stored normal is then one from its normal cone), and bit 31 is set for every
/// stored normal, so that the all-zero word means "no normal known".
///
/// Error bound: a grid step of the square is 2 / 32766 = 6.1e-5, so rounding moves a point of the
/// square by at most (sqrt(2) / 2) 6.1e-5 = 4.3e-5. The map from the square to the sphere stretches
/// lengths by at most 3: at the centre of an octahedron face, which lies 1/sqrt(3) from the origin,
/// a step along the square's diagonal moves the point sqrt(3) times as far on the face, and the
/// projection onto the sphere multiplies that by sqrt(3). So the decoded direction is within
/// 3 * 4.3e-5 = 1.3e-4 rad of the packed one (measured over a million random directions in the
/// tests: 1.29e-4 at worst).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "dexelmill/geometry/types.h"

namespace dexelmill {

/// @brief A unit normal packed in 32 bits (see the file comment). Zero: no normal known.
struct PackedNormal {
    std::uint32_t bits = 0;

    static constexpr std::uint32_t kComponentBits = 15;
    /// Each coordinate of the square is stored as round((c + 1) / 2 * kComponentMax): an even
    /// number of steps, so that 0 (and with it every axis direction) is represented exactly.
    static constexpr std::uint32_t kComponentMax = (1u << kComponentBits) - 2;
    static constexpr std::uint32_t kComponentMask = (1u << kComponentBits) - 1;
    static constexpr std::uint32_t kSharpBit = 1u << 30;
    static constexpr std::uint32_t kPresentBit = 1u << 31;
    /// Largest angle between a unit vector and its decoded packing (radians): see the file comment.
    static constexpr double kMaxAngleError = 1.3e-4;

    /// @brief Packs a vector (any non-zero length; it is normalised). A zero or non-finite vector
    /// packs as "no normal".
    static PackedNormal pack(const Vec3& n, bool sharp = false) {
        const double l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
        if (!(l1 > 0.0) || !(l1 < std::numeric_limits<double>::infinity())) return {};
        const double u = n.x / l1, v = n.y / l1;
        // The lower half folded over the diagonals (selected without a branch: the sign of n.z is
        // as often one as the other).
        const double fu = std::copysign(1.0 - std::abs(v), u), fv = std::copysign(1.0 - std::abs(u), v);
        const bool lower = n.z < 0.0;
        const double su = lower ? fu : u, sv = lower ? fv : v;
        // (c + 1) / 2 * kComponentMax lies in [0, kComponentMax]: adding 0.5 and truncating rounds
        // it to nearest.
        auto quantise = [](double c) { return std::uint32_t((c + 1.0) * (0.5 * kComponentMax) + 0.5); };
        return {kPresentBit | (sharp ? kSharpBit : 0u) | quantise(su) | (quantise(sv) << kComponentBits)};
    }

    /// @brief Whether a normal is stored.
    bool present() const { return (bits & kPresentBit) != 0; }
    /// @brief Whether the end is marked sharp.
    bool sharp() const { return (bits & kSharpBit) != 0; }
    /// @brief The same normal with the sharp mark set or cleared.
    PackedNormal withSharp(bool s) const {
        return {s ? (bits | kSharpBit) : (bits & ~kSharpBit)};
    }

    /// @brief The unit normal, or the zero vector when none is stored.
    Vec3 unpack() const {
        if (!present()) return Vec3(0.0);
        const double u = double(bits & kComponentMask) * (2.0 / kComponentMax) - 1.0;
        const double v = double((bits >> kComponentBits) & kComponentMask) * (2.0 / kComponentMax) - 1.0;
        Vec3 n(u, v, 1.0 - std::abs(u) - std::abs(v));
        if (n.z < 0.0) {
            const double fu = (1.0 - std::abs(v)) * (u >= 0.0 ? 1.0 : -1.0);
            const double fv = (1.0 - std::abs(u)) * (v >= 0.0 ? 1.0 : -1.0);
            n.x = fu;
            n.y = fv;
        }
        return glm::normalize(n);
    }

    /// @brief The opposite normal (same sharp mark); "no normal" stays so.
    PackedNormal flipped() const {
        if (!present()) return {};
        return pack(-unpack(), sharp());
    }

    friend bool operator==(PackedNormal a, PackedNormal b) { return a.bits == b.bits; }
    friend bool operator!=(PackedNormal a, PackedNormal b) { return a.bits != b.bits; }
};

}  // namespace dexelmill
