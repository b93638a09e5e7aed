/// @file mesh.h
/// @brief A plain indexed triangle mesh, free of OpenVDB, and the checks every mesh the library
/// produces must pass: a closed, consistently oriented 2-manifold without degenerate triangles.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <new>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "dexelmill/geometry/tolerance.h"
#include "dexelmill/geometry/types.h"

namespace dexelmill {

namespace detail {
/// @brief Memory for a list's elements (NoZeroAllocator): from operator new, or for a large list
/// (1 MiB and more) where the kernel gives transparent huge pages on advice, a mapping of its own,
/// aligned to 2 MiB and advised for them (memory/pages.cpp).
void* allocateList(std::size_t bytes);
/// @brief Returns memory allocateList gave for the same number of bytes.
void deallocateList(void* p, std::size_t bytes) noexcept;
}  // namespace detail

/// @brief The allocator of a mesh's lists and of the library's other large lists.
///  - `resize` leaves new elements of a trivial type as the memory holds them rather than writing
///    zeros, because the meshers size their lists once and then write every element (zeroing the
///    hood's 760 MB took a third of a second for nothing).
///  - A large list's memory comes in whole huge pages (detail::allocateList): on the virtual
///    machines this project is measured on, the first write to each fresh 4 KiB page costs about
///    14 us (64 MB page by page in 0.23 s), to a 2 MiB page 0.1 to 3 ms (64 MB in 4 to 98 ms). A
///    list from std::allocator is a mapping at an arbitrary 4 KiB boundary, of which advice
///    reaches only the whole 2 MiB runs inside it.
/// Anything else behaves as std::allocator.
template <class T>
struct NoZeroAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = NoZeroAllocator<U>;
    };
    NoZeroAllocator() = default;
    template <class U>
    NoZeroAllocator(const NoZeroAllocator<U>&) noexcept {}
    T* allocate(std::size_t n) {
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        return static_cast<T*>(detail::allocateList(n * sizeof(T)));
    }
    void deallocate(T* p, std::size_t n) noexcept { detail::deallocateList(p, n * sizeof(T)); }
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

/// @brief An indexed triangle mesh in world coordinates (mm). Triangles are counter-clockwise
/// seen from outside the solid, so the outward normal is (b - a) x (c - a).
struct Mesh {
    using Triangle = std::array<std::uint32_t, 3>;

    std::vector<Vec3, NoZeroAllocator<Vec3>> vertices;
    std::vector<Triangle, NoZeroAllocator<Triangle>> triangles;

    bool empty() const { return triangles.empty(); }
    /// @brief The bounding box of the vertices (empty for an empty mesh).
    Box bounds() const;
    /// @brief Twice the area vector of triangle t: (b - a) x (c - a).
    Vec3 areaVector(std::size_t t) const;
};

/// @brief What checkMesh found. A mesh is a closed 2-manifold when every undirected edge is
/// shared by exactly two triangles that traverse it in opposite directions.
struct MeshCheck {
    std::size_t vertexCount = 0;
    std::size_t triangleCount = 0;
    std::size_t edgeCount = 0;            ///< distinct undirected edges
    std::size_t boundaryEdges = 0;        ///< edges used by one triangle
    std::size_t nonManifoldEdges = 0;     ///< edges used by three or more triangles
    std::size_t misorientedEdges = 0;     ///< edges used twice in the same direction
    std::size_t degenerateTriangles = 0;  ///< repeated index or (numerically) zero area
    std::size_t invalidIndices = 0;       ///< triangles with an index past the vertex list
    std::size_t unusedVertices = 0;       ///< vertices no triangle uses (allowed, reported)
    /// Triangles facing against their own vertices: (b - a) x (c - a) has a negative dot product
    /// with the sum of the three vertex normals, each the mean direction of the triangles around
    /// the vertex, of unit length, both when they are weighted by their areas and when by their
    /// angles at the vertex (on a ridge sharper than a right angle the two disagree). A fold
    /// shows as a dark crease in a picture and turns the surface inside out locally.
    std::size_t foldedTriangles = 0;
    /// Triangles facing against their vertices' area-weighted normals alone: the repair's test,
    /// which holds every folded triangle and those only a ridge's larger side turns over.
    std::size_t facingAgainstTriangles = 0;
    double signedVolume = 0.0;            ///< mm^3, positive for outward-facing triangles
    double area = 0.0;                    ///< mm^2

    /// @brief Closed, oriented 2-manifold: no boundary, non-manifold or misoriented edges.
    bool closedManifold() const {
        return boundaryEdges == 0 && nonManifoldEdges == 0 && misorientedEdges == 0 &&
               invalidIndices == 0 && triangleCount > 0;
    }
    /// @brief closedManifold(), no degenerate and no folded triangles.
    bool ok() const { return closedManifold() && degenerateTriangles == 0 && foldedTriangles == 0; }
    /// @brief Why the mesh is not closed, for a message: "12 edges on one triangle, 2 on three or
    /// more", naming each count closedManifold() needs to be 0; empty when it is closed.
    std::string openness() const;
};

/// @brief Checks a mesh: edge manifoldness and orientation, degenerate and folded triangles,
/// volume, area.
/// A triangle is degenerate when two of its indices are equal or when |(b-a) x (c-a)| is at most
/// tol::kDegenerateTriangle times its longest squared edge (a needle or a sliver of zero area).
/// `folded`, when given, receives the triangles to repair (in increasing order): the degenerate
/// ones and those facing against their vertices' area-weighted normals, every folded one among
/// them.
MeshCheck checkMesh(const Mesh& mesh, std::vector<std::uint32_t>* folded = nullptr);

/// @brief checkMesh's `folded` list kept up to date while vertices move and the triangles stay.
/// A triangle's test depends on its corners' normals, each from the triangles around it, so a
/// moved vertex can change the test of the triangles around it and around its neighbours: only
/// those are tested again. The answers are checkMesh's, bit for bit (the same sums in the same
/// order); an update costs in proportion to the triangles it touches, not to the mesh.
class FoldWatch {
public:
    /// @brief Watches `mesh`, which must outlive the watch, keep its triangles, and have valid
    /// indices (checkMesh's invalidIndices zero).
    explicit FoldWatch(const Mesh& mesh);
    ~FoldWatch();
    FoldWatch(const FoldWatch&) = delete;
    FoldWatch& operator=(const FoldWatch&) = delete;

    /// @brief Takes into account that these vertices have moved since the watch was made or last
    /// told (any order; repeats allowed).
    void moved(const std::vector<std::uint32_t>& vertices);
    /// @brief The triangles to repair, in increasing order: what checkMesh's `folded` would
    /// receive now.
    std::vector<std::uint32_t> folded() const;

private:
    struct State;
    std::unique_ptr<State> s_;
};

/// @brief How repairAndCheckMesh repairs folds.
struct FoldRepair {
    /// Triangles facing their vertices' normals at a cosine below this are repaired too, as are
    /// degenerate ones: a margin against rounding.
    double minCosine = 0.0;
    /// The most rounds of pulls.
    int rounds = 8;
    /// Called for every vertex of every triangle to repair, round after round, with the vertices
    /// joined to it by an edge: may move the position, and returns whether it did. Only the
    /// triangles around moved vertices and their neighbours are tested again.
    std::function<bool(std::uint32_t vertex, int round, Vec3& position, const std::vector<std::uint32_t>& neighbours)>
        pull;
    /// May be empty. Called after the last round for every vertex of a triangle still to repair,
    /// with its neighbours: appends positions to try. The vertex goes to the one (or stays where it
    /// is) that leaves the fewest triangles to repair around it and its neighbours.
    std::function<void(std::uint32_t vertex, const std::vector<std::uint32_t>& neighbours, std::vector<Vec3>& positions)>
        candidates;
};

/// @brief checkMesh, repairing on the way: the triangles that fold, nearly fold or have no area
/// have their vertices moved by `repair.pull` until none is left or the rounds run out. The
/// topology does not change. `moved` receives the number of vertices moved, and `unrepaired` the
/// triangles that still fold, nearly fold or have no area after the last round.
MeshCheck repairAndCheckMesh(Mesh& mesh, const FoldRepair& repair, std::size_t* moved = nullptr,
                             std::vector<std::uint32_t>* unrepaired = nullptr);

/// @brief The signed volume enclosed by the mesh (divergence theorem), mm^3.
double meshVolume(const Mesh& mesh);

}  // namespace dexelmill
