// The stars behind checkMesh, whole or in chunks, against lists made the plain way: every corner
// appended to its vertex's list, triangle by triangle.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "surface/stars.h"

using namespace dexelmill;
using detail::StarChunks;

namespace {

/// A closed UV sphere built ring by ring, so that its triangles reach each run of vertices from a
/// short stretch of the list, as a contoured mesh's do.
Mesh ringSphere(int rings, int sectors) {
    Mesh m;
    m.vertices.push_back(Vec3(0, 0, 1));
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < sectors; ++j) {
            const double th = M_PI * i / rings, ph = 2 * M_PI * j / sectors;
            m.vertices.push_back(Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
        }
    m.vertices.push_back(Vec3(0, 0, -1));
    const auto at = [&](int i, int j) { return std::uint32_t(1 + (i - 1) * sectors + (j % sectors)); };
    const auto south = std::uint32_t(m.vertices.size() - 1);
    for (int j = 0; j < sectors; ++j) m.triangles.push_back({0, at(1, j), at(1, j + 1)});
    for (int i = 1; i + 1 < rings; ++i)
        for (int j = 0; j < sectors; ++j) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    for (int j = 0; j < sectors; ++j) m.triangles.push_back({at(rings - 1, j), south, at(rings - 1, j + 1)});
    return m;
}

std::vector<std::vector<std::uint32_t>> plainStars(const Mesh& m) {
    std::vector<std::vector<std::uint32_t>> s(m.vertices.size());
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) s[m.triangles[t][std::size_t(k)]].push_back(std::uint32_t(3 * t + std::size_t(k)));
    return s;
}

template <class S>
bool sameStar(const S& stars, std::uint32_t v, const std::vector<std::uint32_t>& want) {
    return std::equal(stars.begin(v), stars.end(v), want.begin(), want.end());
}

}  // namespace

TEST_CASE("stars: whole, by chunk and by piece, as the plain lists", "[surface][mesh]") {
    // 420,002 vertices: seven chunks, 411 pieces.
    Mesh m = ringSphere(601, 700);
    m.vertices.push_back(Vec3(5.0));  // unused: an empty star
    const auto want = plainStars(m);
    const auto nv = std::uint32_t(m.vertices.size());

    const detail::Stars whole = detail::buildStars(m);
    for (std::uint32_t v = 0; v < nv; ++v) REQUIRE(sameStar(whole, v, want[v]));

    const StarChunks chunks(m, 0);
    REQUIRE(chunks.chunked());
    REQUIRE(chunks.chunkCount() == (nv + StarChunks::kChunk - 1) / StarChunks::kChunk);
    detail::Stars chunk;
    std::vector<std::uint64_t> scratch;
    std::uint32_t covered = 0;
    for (std::size_t c = 0; c < chunks.chunkCount(); ++c) {
        chunks.build(c, chunk, scratch);
        REQUIRE(chunk.first == covered);
        for (std::uint32_t v = chunk.first; v + 1 < chunk.first + chunk.offset.size(); ++v, ++covered)
            REQUIRE(sameStar(chunk, v, want[v]));
    }
    CHECK(covered == nv);
    // A few vertices' stars, piece by piece, in any order.
    std::mt19937 rng(7);
    for (int i = 0; i < 2000; ++i) {
        const std::uint32_t v = rng() % nv;
        REQUIRE(sameStar(chunks, v, want[v]));
    }

    // Small meshes keep the whole list.
    CHECK_FALSE(StarChunks(m).chunked());
}

TEST_CASE("stars: a mesh in scattered order keeps the whole list", "[surface][mesh]") {
    Mesh m = ringSphere(601, 700);
    std::mt19937 rng(11);
    std::shuffle(m.triangles.begin(), m.triangles.end(), rng);
    const StarChunks stars(m, 0);
    // Every chunk is reached from almost the whole list: seven scans, more than the limit.
    CHECK_FALSE(stars.chunked());
    const auto want = plainStars(m);
    for (std::uint32_t v = 0; v < m.vertices.size(); ++v) REQUIRE(sameStar(stars, v, want[v]));
}

TEST_CASE("checkMesh: a mesh large enough for chunked stars, closed, then damaged", "[surface][mesh]") {
    // 5.8 million triangles: a whole star list of 69 MB, past the threshold.
    Mesh m = ringSphere(1700, 1700);
    REQUIRE(StarChunks(m).chunked());
    const std::size_t nt = m.triangles.size();
    MeshCheck c = checkMesh(m);
    CHECK(c.ok());
    CHECK(c.vertexCount == m.vertices.size());
    CHECK(c.edgeCount == 3 * nt / 2);
    CHECK(c.foldedTriangles == 0);
    // An inscribed polyhedron: its volume a little under the unit ball's.
    CHECK(c.signedVolume < 4.0 * M_PI / 3.0);
    CHECK(c.signedVolume > 0.9999 * 4.0 * M_PI / 3.0);

    // Damage in three chunks far apart: one triangle turned over (its three edges each run twice
    // one way, and it faces against its vertices' normals), one removed (three boundary edges),
    // one repeated (three edges used three times).
    std::swap(m.triangles[nt / 5][0], m.triangles[nt / 5][1]);
    m.triangles.push_back(m.triangles[4 * nt / 5]);
    m.triangles.erase(m.triangles.begin() + std::ptrdiff_t(nt / 2));
    REQUIRE(StarChunks(m).chunked());
    c = checkMesh(m);
    CHECK(c.misorientedEdges == 3);
    CHECK(c.boundaryEdges == 3);
    CHECK(c.nonManifoldEdges == 3);
    CHECK(c.foldedTriangles == 1);
    CHECK(c.degenerateTriangles == 0);
    CHECK(c.unusedVertices == 0);
}
