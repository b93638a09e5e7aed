/// @file mesh_distance.h
/// @brief Exact distance from a point to a triangle mesh: a bounding-volume hierarchy over the
/// triangles, searched nearest box first and pruned by box distance, with the closest point on
/// each candidate triangle found in closed form. No sampling and no field: the answer is the
/// distance to the nearest triangle, to double rounding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief The closest point of triangle (a, b, c) to p: a corner whose edges both lead away from
/// p, else p's foot on the plane where it lies within every edge, else the nearest point of the
/// edges p is beyond. Within about eps |p - a| L / h of the exact point for a triangle L long and
/// h high (eps the rounding unit): 1e-9 mm 100 mm out with h / L = 1e-5. A degenerate triangle (a segment or a point) gives the closest point of that segment
/// or point.
Vec3 closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// @brief A mesh prepared for distance queries. Queries are const and may run on many threads.
class MeshDistance {
public:
    /// @brief Builds the hierarchy (O(n log n)); the mesh may be freed afterwards. With `orient`
    /// false the mesh's orientation is not checked (a pass over its edges and a ray per shell):
    /// orientation() is then 0 and signedDistance lets rays decide every sign, which is as exact
    /// and slower, for callers that sign no points or few.
    /// @throw Error for more than 2^32 / 3 triangles.
    explicit MeshDistance(const Mesh& mesh, bool orient = true);

    /// @brief What a query found.
    struct Nearest {
        double distance = 0.0;     ///< mm; infinity for an empty mesh
        Vec3 point{0.0};           ///< the closest point on the mesh
        std::uint32_t triangle = 0;
    };

    /// @brief The nearest point of the mesh to p. `hint`, when given, names a triangle likely
    /// near p (the previous query's, for points that follow each other): the search starts from
    /// its distance, which speeds it and does not change the answer. It receives the nearest.
    Nearest nearest(const Vec3& p, std::uint32_t* hint = nullptr) const;
    /// @brief The distance from p to the mesh (mm).
    double distance(const Vec3& p) const { return nearest(p).distance; }

    /// @brief Whether p lies inside the closed mesh: the parity of the triangles a ray from p
    /// crosses. A ray that meets a triangle within a relative 1e-9 of its edges or its plane, or
    /// starts on a triangle, is ambiguous and another direction is tried, so the answer is exact for
    /// a closed mesh and independent of the triangles' orientation, like the dexel cast. A point on
    /// the surface (no direction decides) counts as outside.
    bool inside(const Vec3& p) const;
    /// @brief The distance from p to the mesh, negative inside it (mm); `hint` as for nearest.
    /// When the mesh is a closed, consistently oriented 2-manifold and p's nearest point lies
    /// inside a face, p is inside exactly when it lies behind that face (the segment from the
    /// nearest point to p meets no other part of the surface); otherwise inside() decides.
    double signedDistance(const Vec3& p, std::uint32_t* hint = nullptr) const;

    /// @brief For many queries in one small region: the triangles (by their internal slots) whose
    /// distance from c is at most `radius`, into `out`. Every point within r of c has its nearest
    /// triangle among those within distance(c) + 2 r of c, so signedDistanceAmong with them is
    /// then exact for all such points.
    /// @return false, with `out` incomplete, when there are more than `limit`.
    bool slotsNear(const Vec3& c, double radius, std::size_t limit, std::vector<std::uint32_t>& out) const;
    /// @brief signedDistance, when p's nearest triangle is among `slots` (from slotsNear);
    /// infinity for no slots.
    double signedDistanceAmong(const Vec3& p, const std::vector<std::uint32_t>& slots) const;

    /// @brief The distance from p to one triangle of the mesh (by its index in the mesh given).
    double distanceTo(const Vec3& p, std::uint32_t triangle) const;

    std::size_t triangleCount() const { return original_.size(); }
    /// @brief +1 for a closed, consistently oriented 2-manifold all of whose shells face out of
    /// the solid, -1 when all face in, 0 for anything else (an open or non-manifold mesh, shells
    /// facing both ways).
    int orientation() const { return orientation_; }

private:
    /// The nearest triangle's slot, the squared distance, the nearest point and whether it lies
    /// inside the triangle's face; `found` is false while no slot has been tested.
    struct Found {
        std::uint32_t slot = 0;
        double d2 = 0.0;
        Vec3 point{0.0};
        bool onFace = false;
        bool found = false;
    };
    Found search(const Vec3& p, const std::uint32_t* hint) const;
    /// The found distance with its sign (see signedDistance).
    double withSign(const Vec3& p, const Found& f) const;
    /// What orientation() reports, for the mesh the index was built from.
    int orientationOf(const Mesh& mesh) const;

    struct Node {
        Box box;
        std::uint32_t first = 0;  ///< a leaf's first triangle slot, or an inner node's left child
        std::uint32_t count = 0;  ///< triangles in a leaf; 0 for an inner node (right = left + 1)
    };
    std::vector<Node> nodes_;
    /// Corner k of the triangle slots (three a slot, in hierarchy order), exactly as the mesh has it.
    Vec3 corner(std::size_t k) const { return single_.empty() ? corners_[k] : Vec3(single_[k]); }
    /// The corners, in single precision when every one of them is a float (an STL's always are),
    /// which halves the index and the memory its queries read; otherwise in double.
    std::vector<glm::vec3, NoZeroAllocator<glm::vec3>> single_;
    std::vector<Vec3, NoZeroAllocator<Vec3>> corners_;
    std::vector<std::uint32_t> original_;  ///< each slot's index in the input mesh
    std::vector<std::uint32_t> slot_;      ///< each input triangle's slot
    int orientation_ = 0;
};

}  // namespace dexelmill
