// The per-cell patch tables: every configuration's loops, and closed meshes from random sign
// fields whatever the face rule picks, as long as neighbours see the same faces.
#include <catch2/catch.hpp>

#include <array>
#include <map>
#include <random>

#include "dexelmill/surface/mesh.h"
#include "surface/detail/cell_table.h"

using namespace dexelmill;
using namespace dexelmill::detail;

TEST_CASE("cell tables: each crossing edge lies on exactly one loop, once", "[surface][contour]") {
    for (int m = 0; m < 256; ++m) {
        for (int j = 0; j < 64; ++j) {
            const CellPatches& p = cellPatches(std::uint8_t(m), std::uint8_t(j));
            int seen[kCellEdges] = {};
            int total = 0;
            for (int k = 0; k < p.count; ++k) {
                CHECK(p.size[k] >= 3);
                total += p.size[k];
            }
            for (int i = 0; i < total; ++i) ++seen[p.edges[i]];
            for (int e = 0; e < kCellEdges; ++e) {
                const bool crosses = ((m >> edgeCorner(e, 0)) & 1) != ((m >> edgeCorner(e, 1)) & 1);
                INFO("config " << m << " rule " << j << " edge " << e);
                CHECK(seen[e] == (crosses ? 1 : 0));
                CHECK((p.patchOf[e] != 0xff) == crosses);
            }
        }
    }
}

TEST_CASE("cell tables: random sign fields give closed oriented manifolds", "[surface][contour]") {
    std::mt19937_64 rng(11);
    for (int trial = 0; trial < 200; ++trial) {
        constexpr int n = 7;  // lattice points per axis; the border is outside
        const double density = 0.2 + 0.6 * double(trial % 5) / 4.0;
        std::bernoulli_distribution coin(density);
        std::vector<bool> in(n * n * n);
        std::vector<float> value(n * n * n);
        std::uniform_real_distribution<float> mag(0.1f, 1.0f);
        auto at = [&](int x, int y, int z) { return (z * n + y) * n + x; };
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const bool border = x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1;
                    const bool inside = !border && coin(rng);
                    in[at(x, y, z)] = inside;
                    value[at(x, y, z)] = inside ? -mag(rng) : mag(rng);
                }
        Mesh mesh;
        std::map<std::tuple<int, int, int, int>, std::uint32_t> edgeVertex;
        for (int z = 0; z + 1 < n; ++z)
            for (int y = 0; y + 1 < n; ++y)
                for (int x = 0; x + 1 < n; ++x) {
                    std::uint8_t mask = 0;
                    float f[8];
                    for (int k = 0; k < 8; ++k) {
                        const int i = at(x + (k & 1), y + ((k >> 1) & 1), z + ((k >> 2) & 1));
                        f[k] = value[i];
                        if (in[i]) mask |= std::uint8_t(1u << k);
                    }
                    if (mask == 0 || mask == 0xff) continue;
                    std::uint8_t joined = 0;
                    for (int face = 0; face < kCellFaces; ++face) {
                        const auto k = faceCorners(face);
                        if (insideJoinedAcrossFace(f[k[0]], f[k[1]], f[k[2]], f[k[3]])) joined |= std::uint8_t(1u << face);
                    }
                    const CellPatches& p = cellPatches(mask, joined);
                    std::uint32_t vert[kCellEdges];
                    for (int e = 0; e < kCellEdges; ++e) {
                        if (p.patchOf[e] == 0xff) continue;
                        const int c0 = edgeCorner(e, 0), a = edgeAxis(e);
                        const auto key = std::make_tuple(x + (c0 & 1), y + ((c0 >> 1) & 1), z + ((c0 >> 2) & 1), a);
                        auto it = edgeVertex.find(key);
                        if (it == edgeVertex.end()) {
                            Vec3 v(std::get<0>(key), std::get<1>(key), std::get<2>(key));
                            v[a] += 0.5;
                            it = edgeVertex.emplace(key, std::uint32_t(mesh.vertices.size())).first;
                            mesh.vertices.push_back(v);
                        }
                        vert[e] = it->second;
                    }
                    int off = 0;
                    for (int k = 0; k < p.count; ++k) {
                        Vec3 c(0.0);
                        for (int i = 0; i < p.size[k]; ++i) c += mesh.vertices[vert[p.edges[off + i]]];
                        c /= double(p.size[k]);
                        const std::uint32_t ci = std::uint32_t(mesh.vertices.size());
                        mesh.vertices.push_back(c);
                        for (int i = 0; i < p.size[k]; ++i)
                            mesh.triangles.push_back({ci, vert[p.edges[off + i]], vert[p.edges[off + (i + 1) % p.size[k]]]});
                        off += p.size[k];
                    }
                }
        const MeshCheck check = checkMesh(mesh);
        INFO("trial " << trial << " density " << density);
        REQUIRE(check.closedManifold());
        // Outward: the enclosed volume is positive when anything is inside.
        if (!mesh.empty()) CHECK(check.signedVolume > 0.0);
    }
}

TEST_CASE("cell tables: the edge tables agree with the numbering the header states", "[surface][contour]") {
    // The header's numbering, read afresh: edge 4 a + j starts at offset 0 on axis a, j & 1 on
    // (a + 1) % 3 and j >> 1 on (a + 2) % 3, and runs one step along a; face 2 a + s is where
    // coordinate a is s.
    const auto ends = [](int e) {
        const int a = e / 4, j = e % 4;
        std::array<int, 3> p{0, 0, 0};
        p[std::size_t((a + 1) % 3)] = j & 1;
        p[std::size_t((a + 2) % 3)] = j >> 1;
        std::array<int, 3> q = p;
        ++q[std::size_t(a)];
        return std::array<std::array<int, 3>, 2>{p, q};
    };
    const auto onFace = [&](int e, int f) {
        for (const auto& p : ends(e))
            if (p[std::size_t(f / 2)] != f % 2) return false;
        return true;
    };
    const EdgeTables& t = edgeTables();
    for (int i = 0; i < kCellEdges; ++i) {
        INFO("edge " << i);
        const EdgeStart& s = edgeStarts()[std::size_t(i)];
        CHECK(std::array<int, 3>{s.dx, s.dy, s.dz} == ends(i)[0]);
        CHECK(s.axis == i / 4);
        for (int j = 0; j < kCellEdges; ++j) {
            INFO("with edge " << j);
            int holding = -1;
            for (int f = 0; f < kCellFaces; ++f)
                if (i != j && onFace(i, f) && onFace(j, f)) holding = f;
            CHECK(int(t.face[i][j]) == holding);
        }
        for (int f = 0; f < kCellFaces; ++f) {
            if (!onFace(i, f)) continue;
            INFO("across face " << f);
            // In the neighbour's cell the same lattice edge lies one step back along the face's axis.
            auto shifted = ends(i);
            for (auto& p : shifted) p[std::size_t(f / 2)] -= 2 * (f % 2) - 1;
            int same = -1;
            for (int k = 0; k < kCellEdges; ++k)
                if (ends(k) == shifted) same = k;
            CHECK(same >= 0);
            CHECK(int(t.across[i][f]) == same);
        }
    }
}
