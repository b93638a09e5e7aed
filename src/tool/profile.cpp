#include "dexelmill/tool/profile.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {
template <class... F>
struct Overloaded : F... {
    using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;
}  // namespace

double pieceZ0(const ProfilePiece& piece) {
    return std::visit([](const auto& p) { return p.z0; }, piece);
}

double pieceZ1(const ProfilePiece& piece) {
    return std::visit([](const auto& p) { return p.z1; }, piece);
}

double pieceRadius(const ProfilePiece& piece, double z) {
    return std::visit(Overloaded{[z](const ConePiece& c) {
                                     const double t = std::clamp((z - c.z0) / (c.z1 - c.z0), 0.0, 1.0);
                                     return c.r0 + t * (c.r1 - c.r0);
                                 },
                                 [z](const ArcPiece& a) {
                                     const double dz = std::clamp(z, a.z0, a.z1) - a.zc;
                                     return a.rc + std::sqrt(std::max(0.0, a.rho * a.rho - dz * dz));
                                 }},
                      piece);
}

double pieceSlope(const ProfilePiece& piece, double z) {
    return std::visit(Overloaded{[](const ConePiece& c) { return (c.r1 - c.r0) / (c.z1 - c.z0); },
                                 [z](const ArcPiece& a) {
                                     const double dz = std::clamp(z, a.z0, a.z1) - a.zc;
                                     const double s = std::sqrt(std::max(0.0, a.rho * a.rho - dz * dz));
                                     if (s == 0.0)
                                         return dz > 0 ? -std::numeric_limits<double>::infinity()
                                                       : std::numeric_limits<double>::infinity();
                                     return -dz / s;
                                 }},
                      piece);
}

std::vector<ProfilePiece> clipChain(const std::vector<ProfilePiece>& pieces, std::size_t first, std::size_t last,
                                    double z0, double z1) {
    std::vector<ProfilePiece> out;
    for (std::size_t i = first; i < last; ++i) {
        const double lo = std::max(pieceZ0(pieces[i]), z0), hi = std::min(pieceZ1(pieces[i]), z1);
        if (!(hi > lo + tol::kLength)) continue;
        if (const auto* c = std::get_if<ConePiece>(&pieces[i])) {
            out.push_back(ConePiece{lo, hi, pieceRadius(*c, lo), pieceRadius(*c, hi)});
        } else {
            ArcPiece a = std::get<ArcPiece>(pieces[i]);
            a.z0 = lo, a.z1 = hi;
            out.push_back(a);
        }
    }
    return out;
}

}  // namespace dexelmill
