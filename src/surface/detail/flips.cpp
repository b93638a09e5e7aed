#include "surface/detail/flips.h"

#include <algorithm>
#include <memory>
#include <utility>

namespace dexelmill::detail {

namespace {

/// A flip's new triangles must face within acos(this) (87 degrees) of the pair they replace. Across
/// a crease each lies in one face, whose normal is half the crease's turn from the pair's: this
/// admits creases up to 174 degrees sharp.
constexpr double kFlipFacing = 0.05;

/// The flip pass over one block (flipChords).
class ChordFlips {
  public:
    explicit ChordFlips(const FlipInputs& in) : in_(in), mesh_(*in.mesh) {}

    /// Flips the fan chords of the block's feature patches that run across a crease (flipChord).
    /// Each of the two cells sharing a chord decides alike and turns its own triangle.
    std::size_t block(const Block& b) {
        const EdgeTables& tables = edgeTables();
        std::size_t flipped = 0;
        std::uint32_t loop[kCellEdges];
        std::uint32_t tri = b.triangleBase;
        std::uint32_t patch = b.patchBase;
        std::unique_ptr<BlockIndex::Around> near;  // made for the first feature patch of the block
        b.forEachTableCell([&](int off, const CellPatches& patches) {
            if (b.isPlain(off)) {
                tri += 2;
                return;
            }
            int start = 0;
            for (int k = 0; k < patches.count; ++k, ++patch) {
                const int len = patches.size[k];
                const std::uint8_t* edges = &patches.edges[start];
                start += len;
                // A flip joins two patch vertices through the cells' insides, where a cell's only
                // surface is the patch's own. A cell holding another patch, the other side of a fin
                // thinner than the cell, has it within a fraction of h of that join: between two
                // ball plunges of radius 5 h whose walls pass 0.0095 h apart, the join of (8.50,
                // 8.44, 1.00) with (8.37, 8.50, 1.57) across the face z = 1.5 passed through the
                // fan of the fin's other side in the lower cell (11 of 16 pairs of triangles that
                // met). The chords of such cells, and those they share with one, keep their fans.
                if (patches.count > 1 || !isFeature(patch)) {
                    tri += std::uint32_t(len);
                    continue;
                }
                if (!near) near = std::make_unique<BlockIndex::Around>(in_.index->around(b));
                const Coord p = b.origin.offsetBy(off >> 6, (off >> 3) & 7, off & 7);
                in_.loop(*near, p, patches, k, loop);
                for (int i = 0; i < len; ++i, ++tri) {
                    const int j = i + 1 == len ? 0 : i + 1;
                    // The chord loop[i]-loop[j] lies on the face shared with the neighbour
                    // whose patch holds the same two crossings.
                    const int face = tables.face[edges[i]][edges[j]];
                    Coord np = p;
                    np[face >> 1] += (face & 1) ? 1 : -1;
                    const CellPatches* other = nullptr;
                    std::uint32_t otherFirst = 0;
                    // A plain neighbour has no vertex to join, and no crease.
                    if (!in_.cell(*near, np, other, otherFirst)) continue;
                    const int ok = other->patchOf[tables.across[edges[i]][face]];
                    const std::uint32_t partner = otherFirst + std::uint32_t(ok);
                    if (other->count == 1 && isFeature(partner) &&
                        flipChord(edges, len, i, *other, ok, face, patch, partner, loop)) {
                        mesh_.triangles[tri] = {patch, loop[i], partner};
                        flipped += patch < partner;
                    }
                }
            }
        });
        return flipped;
    }

  private:
    /// Twice the area vector of a triangle.
    Vec3 area(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
        return glm::cross(mesh_.vertices[b] - mesh_.vertices[a],
                          mesh_.vertices[c] - mesh_.vertices[a]);
    }

    /// How well a triangle agrees with the Hermite data: the least cosine between its normal and
    /// the normals of its crossings (1 when none has a known normal; -1 when it has no area).
    double fit(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
        const Vec3 n = glm::cross(mesh_.vertices[b] - mesh_.vertices[a],
                                  mesh_.vertices[c] - mesh_.vertices[a]);
        const double len = glm::length(n);
        if (!(len > 0.0)) return -1.0;
        double worst = 1.0;
        for (std::uint32_t i : {a, b, c}) {
            if (i >= in_.patchVertexBase || !in_.crossingNormal[i].present()) continue;
            worst = std::min(worst, glm::dot(n, in_.crossingNormal[i].unpack()) / len);
        }
        return worst;
    }

    bool isFeature(std::uint32_t patchVertex) const {
        return in_.feature[patchVertex - in_.patchVertexBase] != 0;
    }

    /// Whether the chord loop[i]-loop[i+1] of this cell's patch (vertex `patch`) is flipped to
    /// join `patch` with the neighbour's patch `partner` across `face`. Both cells ask the same
    /// question of the same data and get the same answer: flip when the two new triangles agree
    /// better with the normals at their crossings (across a crease each new triangle lies in the
    /// plane of its one crossing), and when this chord is the first, in the order of the lattice
    /// edges, of the chords the two patches share on the face (two flips would join the two
    /// vertices twice), and when neither new triangle faces against the pair it replaces.
    bool flipChord(const std::uint8_t* edges, int len, int i, const CellPatches& otherPatches,
                   int ok, int face, std::uint32_t patch, std::uint32_t partner,
                   const std::uint32_t* loop) const {
        const int j = (i + 1) % len;
        const std::uint32_t xi = loop[i], xj = loop[j];
        // Before: (patch, xi, xj) and (partner, xj, xi). After: (patch, xi, partner) and
        // (partner, xj, patch).
        const double before = std::min(fit(patch, xi, xj), fit(partner, xj, xi));
        const double after = std::min(fit(patch, xi, partner), fit(partner, xj, patch));
        if (!(after > before)) return false;
        // The new pair must face the way the old pair does, by more than a sliver's margin: a flip
        // never turns a triangle over, nor makes one that stands edge-on to the surface there.
        const Vec3 quad = area(patch, xi, xj) + area(partner, xj, xi);
        for (const Vec3& n : {area(patch, xi, partner), area(partner, xj, patch)})
            if (!(glm::dot(n, quad) > kFlipFacing * glm::length(n) * glm::length(quad)))
                return false;
        // Other chords of this patch on the same face that reach the same partner.
        const EdgeTables& tables = edgeTables();
        const std::uint64_t mine = std::min<std::uint64_t>(xi, xj);
        for (int m = 0; m < len; ++m) {
            if (m == i) continue;
            const int n = (m + 1) % len;
            if (tables.face[edges[m]][edges[n]] != face) continue;
            const int oe = tables.across[edges[m]][face];
            if (otherPatches.patchOf[oe] != ok) continue;
            if (std::min<std::uint64_t>(loop[m], loop[n]) < mine) return false;
        }
        return true;
    }

    const FlipInputs& in_;
    Mesh& mesh_;
};

}  // namespace

std::size_t flipChords(const FlipInputs& in, const Block& b) {
    return ChordFlips(in).block(b);
}

std::size_t unflip(Mesh& mesh, std::uint32_t patchVertexBase,
                   const std::vector<std::uint32_t>& triangles) {
    auto isFlip = [&](const Mesh::Triangle& t) {
        return t[0] >= patchVertexBase && t[2] >= patchVertexBase;
    };
    // Each flipped triangle's partner triangle is the one that runs the other way along the
    // join of the two patch vertices.
    std::vector<std::pair<std::uint64_t, std::uint32_t>> wanted;
    for (std::uint32_t t : triangles) {
        const Mesh::Triangle& tri = mesh.triangles[t];
        if (isFlip(tri)) wanted.push_back({std::uint64_t(tri[2]) << 32 | tri[0], t});
    }
    if (wanted.empty()) return 0;
    std::sort(wanted.begin(), wanted.end());
    wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        const Mesh::Triangle& tri = mesh.triangles[t];
        if (!isFlip(tri)) continue;
        const std::uint64_t key = std::uint64_t(tri[0]) << 32 | tri[2];
        auto it =
            std::lower_bound(wanted.begin(), wanted.end(), std::make_pair(key, std::uint32_t(0)));
        if (it != wanted.end() && it->first == key)
            pairs.push_back({std::min(it->second, t), std::max(it->second, t)});
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    for (const auto& [a, b] : pairs) {
        Mesh::Triangle& t1 = mesh.triangles[a];
        Mesh::Triangle& t2 = mesh.triangles[b];
        const std::uint32_t xi = t1[1], xj = t2[1];
        t1[2] = xj;
        t2[2] = xi;
    }
    return pairs.size();
}

}  // namespace dexelmill::detail
