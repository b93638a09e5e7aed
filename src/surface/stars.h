/// @file stars.h
/// @brief Vertex stars of a triangle mesh, for its check and repair (mesh.cpp): the triangle
/// corners at each vertex, as 3 t + k for corner k of triangle t, in increasing order, so that
/// sums over a star come out the same for any thread count and any way of building it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "dexelmill/surface/mesh.h"

namespace dexelmill::detail {

/// The stars of the vertices first .. first + offset.size() - 2.
struct Stars {
    std::uint32_t first = 0;
    std::vector<std::uint32_t, NoZeroAllocator<std::uint32_t>> offset;  ///< per vertex from `first`, into corners; one more at the end
    std::vector<std::uint32_t, NoZeroAllocator<std::uint32_t>> corners;

    const std::uint32_t* begin(std::uint32_t v) const { return corners.data() + offset[v - first]; }
    const std::uint32_t* end(std::uint32_t v) const { return corners.data() + offset[v - first + 1]; }
};

/// The stars of all vertices, built in parallel.
Stars buildStars(const Mesh& mesh);

/// @brief The stars of a large mesh in chunks of consecutive vertices, each made from the
/// triangles that reach it, when those come from a short stretch of the triangle list (as a
/// contoured mesh's do: it is made block by block); otherwise, and for smaller meshes, all at
/// once.
///
/// Why: a whole-mesh star list is as large as the triangles, and it set the run's peak memory:
/// on the hood at 1 mm, 408 MB of 1.89 GB. A chunk's stars are small and reused. Chunks cost
/// about as much time as they save there (more scans of the triangles, fewer pages to fault
/// in); on a mesh whose list fits in cache (bear, 9.5 MB) they cost a tenth more, hence the
/// threshold.
class StarChunks {
public:
    /// Vertices per chunk, for a pass over all of them.
    static constexpr std::uint32_t kChunk = 1u << 16;
    /// Vertices per piece, for the stars of a few: a piece's stretch of triangles is shorter.
    static constexpr std::uint32_t kPiece = 1u << 10;
    /// Chunks are used from this size of the whole-mesh star list on.
    static constexpr std::size_t kChunkedBytes = std::size_t(64) << 20;
    /// Chunks are used while their triangle stretches add up to at most this many times the
    /// triangle count (a contoured mesh: 2 to 4; a mesh in arbitrary order: up to the chunk count).
    static constexpr double kMaxScans = 6.0;

    /// Chunks from a whole-mesh star list of `chunkedBytes` on (a smaller value for tests).
    explicit StarChunks(const Mesh& mesh, std::size_t chunkedBytes = kChunkedBytes);

    /// Whether the stars come in chunks; if not, whole() holds them all.
    bool chunked() const { return !whole_; }
    const Stars& whole() const { return *whole_; }
    std::size_t chunkCount() const { return lo_.size(); }
    /// Builds chunk c's stars into `out`, reusing its buffers and `scratch`'s.
    void build(std::size_t c, Stars& out, std::vector<std::uint64_t>& scratch) const;

    /// The star of vertex v: from whole(), or from its piece, built on first use and kept (not
    /// for concurrent use).
    const std::uint32_t* begin(std::uint32_t v) const { return stars(v).begin(v); }
    const std::uint32_t* end(std::uint32_t v) const { return stars(v).end(v); }

private:
    const Stars& stars(std::uint32_t v) const;

    const Mesh& mesh_;
    std::unique_ptr<Stars> whole_;
    /// Per chunk and per piece: the first triangle and one past the last with a corner in it.
    std::vector<std::uint32_t> lo_, hi_, pieceLo_, pieceHi_;
    mutable std::unordered_map<std::size_t, Stars> cache_;
    mutable std::vector<std::uint64_t> scratch_;
};

}  // namespace dexelmill::detail
