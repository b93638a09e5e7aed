// The general cell loops (cell_loops.h): the cell table's loops where every edge holds at most one
// crossing, and closed oriented manifolds from lattices whose edges hold several.
#include <catch2/catch.hpp>

#include <algorithm>
#include <map>
#include <random>
#include <tuple>

#include "dexelmill/surface/mesh.h"
#include "surface/detail/cell_loops.h"
#include "surface/detail/cell_table.h"

using namespace dexelmill;
using namespace dexelmill::detail;

namespace {

/// A loop turned to start at its least id, so that equal cycles compare equal.
std::vector<std::uint32_t> canonical(std::vector<std::uint32_t> loop) {
    std::rotate(loop.begin(), std::min_element(loop.begin(), loop.end()), loop.end());
    return loop;
}

using EdgeKey = std::tuple<int, int, int, int>;  // lower lattice point and axis

/// A small lattice: signs (and level set values for the decider) at its points, and on chosen
/// edges the offsets of their crossings; other edges cross once, at the middle, where their ends
/// differ.
struct TestLattice {
    int n = 0;
    std::vector<char> in;
    std::vector<float> value;
    std::map<EdgeKey, std::vector<double>> crossings;

    explicit TestLattice(int size) : n(size), in(std::size_t(size * size * size), 0), value(in.size(), 1.0f) {}
    int at(int x, int y, int z) const { return (z * n + y) * n + x; }
    void set(int x, int y, int z, bool inside, float magnitude = 1.0f) {
        in[std::size_t(at(x, y, z))] = inside;
        value[std::size_t(at(x, y, z))] = inside ? -magnitude : magnitude;
    }
};

struct Built {
    Mesh mesh;
    std::size_t loops = 0, faceVertices = 0;
    std::vector<std::size_t> loopSizes;
};

/// The mesh of every cell's loops, each fanned from its mass point.
Built build(const TestLattice& L) {
    Built out;
    std::map<std::tuple<int, int, int, int, int>, std::uint32_t> edgeVertex;  // edge, index
    std::map<std::tuple<int, int, int, int, std::uint32_t, std::uint32_t>, std::uint32_t> faceVertex;
    for (int z = 0; z + 1 < L.n; ++z)
        for (int y = 0; y + 1 < L.n; ++y)
            for (int x = 0; x + 1 < L.n; ++x) {
                const int cell[3] = {x, y, z};
                CellCrossings c;
                float f[8];
                for (int k = 0; k < 8; ++k) {
                    const int i = L.at(x + (k & 1), y + ((k >> 1) & 1), z + ((k >> 2) & 1));
                    f[k] = L.value[std::size_t(i)];
                    if (L.in[std::size_t(i)]) c.inside |= std::uint8_t(1u << k);
                }
                for (int face = 0; face < kCellFaces; ++face) {
                    const auto k = faceCorners(face);
                    if (insideJoinedAcrossFace(f[k[0]], f[k[1]], f[k[2]], f[k[3]])) c.joined |= std::uint8_t(1u << face);
                }
                bool any = false;
                for (int e = 0; e < kCellEdges; ++e) {
                    const int c0 = edgeCorner(e, 0), a = edgeAxis(e);
                    const EdgeKey key{x + (c0 & 1), y + ((c0 >> 1) & 1), z + ((c0 >> 2) & 1), a};
                    std::vector<double> at;
                    const auto it = L.crossings.find(key);
                    if (it != L.crossings.end()) at = it->second;
                    else if (((c.inside >> c0) & 1) != ((c.inside >> edgeCorner(e, 1)) & 1)) at = {0.5};
                    for (std::size_t j = 0; j < at.size(); ++j) {
                        const auto vk = std::make_tuple(std::get<0>(key), std::get<1>(key), std::get<2>(key), a, int(j));
                        auto v = edgeVertex.find(vk);
                        if (v == edgeVertex.end()) {
                            Vec3 p(std::get<0>(key), std::get<1>(key), std::get<2>(key));
                            p[a] += at[j];
                            v = edgeVertex.emplace(vk, std::uint32_t(out.mesh.vertices.size())).first;
                            out.mesh.vertices.push_back(p);
                        }
                        c.edges[std::size_t(e)].ids.push_back(v->second);
                        c.edges[std::size_t(e)].at.push_back(at[j]);
                        any = true;
                    }
                }
                if (!any) continue;
                const auto vertexOnFace = [&](int face, std::uint32_t from, std::uint32_t to, double u, double v) {
                    const int a = face >> 1;
                    int lo[3] = {cell[0], cell[1], cell[2]};
                    lo[a] += face & 1;
                    const auto key = std::make_tuple(lo[0], lo[1], lo[2], a, std::min(from, to), std::max(from, to));
                    auto it = faceVertex.find(key);
                    if (it == faceVertex.end()) {
                        Vec3 p(lo[0], lo[1], lo[2]);
                        p[(a + 1) % 3] += u;
                        p[(a + 2) % 3] += v;
                        it = faceVertex.emplace(key, std::uint32_t(out.mesh.vertices.size())).first;
                        out.mesh.vertices.push_back(p);
                        ++out.faceVertices;
                    }
                    return it->second;
                };
                for (const auto& loop : cellLoops(c, vertexOnFace)) {
                    Vec3 m(0.0);
                    for (std::uint32_t i : loop) m += out.mesh.vertices[i];
                    const std::uint32_t centre = std::uint32_t(out.mesh.vertices.size());
                    out.mesh.vertices.push_back(m / double(loop.size()));
                    for (std::size_t i = 0; i < loop.size(); ++i)
                        out.mesh.triangles.push_back({centre, loop[i], loop[(i + 1) % loop.size()]});
                    ++out.loops;
                    out.loopSizes.push_back(loop.size());
                }
            }
    return out;
}

}  // namespace

TEST_CASE("cell loops: one crossing per edge gives the cell table's loops", "[surface][contour]") {
    for (int m = 0; m < 256; ++m)
        for (int j = 0; j < 64; ++j) {
            CellCrossings c;
            c.inside = std::uint8_t(m);
            c.joined = std::uint8_t(j);
            for (int e = 0; e < kCellEdges; ++e)
                if (((m >> edgeCorner(e, 0)) & 1) != ((m >> edgeCorner(e, 1)) & 1)) {
                    c.edges[std::size_t(e)].ids = {std::uint32_t(e)};
                    c.edges[std::size_t(e)].at = {0.5};
                }
            bool askedForFaceVertex = false;
            const auto loops = cellLoops(c, [&](int, std::uint32_t, std::uint32_t, double, double) {
                askedForFaceVertex = true;
                return std::uint32_t(100);
            });
            const CellPatches& p = cellPatches(std::uint8_t(m), std::uint8_t(j));
            std::vector<std::vector<std::uint32_t>> expected;
            int off = 0;
            for (int k = 0; k < p.count; ++k) {
                expected.emplace_back(p.edges.begin() + off, p.edges.begin() + off + p.size[k]);
                off += p.size[k];
            }
            std::vector<std::vector<std::uint32_t>> got;
            for (const auto& l : loops) got.push_back(canonical(l));
            for (auto& l : expected) l = canonical(l);
            std::sort(got.begin(), got.end());
            std::sort(expected.begin(), expected.end());
            INFO("config " << m << " joined " << j);
            CHECK_FALSE(askedForFaceVertex);
            CHECK(got == expected);
        }
}

TEST_CASE("cell loops: a stretch of material on an edge between empty points is a closed lens", "[surface][contour]") {
    TestLattice L(4);
    L.crossings[{1, 1, 1, 0}] = {0.3, 0.6};
    const Built b = build(L);
    const MeshCheck check = checkMesh(b.mesh);
    CHECK(check.closedManifold());
    CHECK(check.signedVolume > 0.0);
    // The four cells round the edge hold one loop each: the two ends and a vertex on each face.
    CHECK(b.loops == 4);
    CHECK(b.faceVertices == 4);
    for (std::size_t s : b.loopSizes) CHECK(s == 4);
}

TEST_CASE("cell loops: a gap on an edge between points in material is a closed hole", "[surface][contour]") {
    TestLattice L(5);
    for (int z = 1; z < 4; ++z)
        for (int y = 1; y < 4; ++y)
            for (int x = 1; x < 4; ++x) L.set(x, y, z, true);
    const double solid = checkMesh(build(L).mesh).signedVolume;
    L.crossings[{1, 2, 2, 0}] = {0.4, 0.45};
    const Built b = build(L);
    const MeshCheck check = checkMesh(b.mesh);
    CHECK(check.closedManifold());
    // The same block less a lens-shaped hole round the gap.
    CHECK(check.signedVolume > 0.0);
    CHECK(check.signedVolume < solid);
    CHECK(b.faceVertices == 4);
}

TEST_CASE("cell loops: stretches on parallel edges that overlap are one wall", "[surface][contour]") {
    TestLattice L(4);
    // A wall across x, between the lattice planes x = 1 and x = 2, crossing the edges along x at
    // y = 1, 2 and z = 1, 2: each cell round it holds one band of the wall, no face vertex.
    for (int y = 1; y <= 2; ++y)
        for (int z = 1; z <= 2; ++z) L.crossings[{1, y, z, 0}] = {0.4, 0.5 + 0.02 * y};
    const Built b = build(L);
    const MeshCheck check = checkMesh(b.mesh);
    CHECK(check.closedManifold());
    CHECK(check.signedVolume > 0.0);
    // The face between the four edges joins them; the outer faces close the wall's edges.
    std::size_t fourOrMore = 0;
    for (std::size_t s : b.loopSizes) fourOrMore += s >= 4;
    CHECK(fourOrMore == b.loops);
    CHECK(b.faceVertices == 8);
}

TEST_CASE("cell loops: stretches on parallel edges that do not overlap stay apart", "[surface][contour]") {
    TestLattice L(4);
    L.crossings[{1, 1, 1, 0}] = {0.1, 0.2};
    L.crossings[{1, 2, 1, 0}] = {0.7, 0.8};
    const Built b = build(L);
    const MeshCheck check = checkMesh(b.mesh);
    CHECK(check.closedManifold());
    CHECK(check.signedVolume > 0.0);
    // Two lenses: each of its four cells holds one loop of two ends and two face vertices.
    CHECK(b.loops == 8);
    CHECK(b.faceVertices == 8);
}

TEST_CASE("cell loops: a lens's face vertex follows its ends' tangents", "[surface][contour]") {
    // One cell, a stretch of material on edge 0 (along x at y = z = 0) from 0.3 to 0.7, bulging
    // into face 4 (across z at 0: u = x, v = y). Its ends' outward normals, in that face, turn 60
    // degrees from the edge: (-sin 60, cos 60) and (sin 60, cos 60).
    //  - As they are, 120 degrees apart (a sharp edge), the face vertex is the wedge's tip, where
    //    the tangent lines meet: 0.2 tan 60 = 0.346 into the face.
    //  - Leaning mostly out of the face (their part in it a fifth), 19 degrees apart (smooth), it
    //    lies on the circular arc that turns 120 degrees over the chord of 0.4: 0.2 tan 30 = 0.115.
    const double s60 = std::sqrt(3.0) / 2.0, lean = 0.2, out = -std::sqrt(1.0 - lean * lean);
    struct Case {
        Vec3 n1, n2;
        double depth;
    };
    for (const Case& k : {Case{Vec3(-s60, 0.5, 0.0), Vec3(s60, 0.5, 0.0), 0.2 * std::sqrt(3.0)},
                          Case{Vec3(-lean * s60, lean * 0.5, out), Vec3(lean * s60, lean * 0.5, out), 0.2 / std::sqrt(3.0)}}) {
        CellCrossings c;
        c.edges[0].ids = {0, 1};
        c.edges[0].at = {0.3, 0.7};
        c.edges[0].normals = {k.n1, k.n2};
        double u = -1.0, v = -1.0;
        cellLoops(c, [&](int face, std::uint32_t, std::uint32_t, double fu, double fv) {
            if (face == 4) u = fu, v = fv;
            return std::uint32_t(10 + face);
        });
        INFO("normals " << k.n1.x << ", " << k.n1.y << ", " << k.n1.z << ": face vertex at (" << u << ", " << v << ")");
        CHECK(u == Approx(0.5).margin(1e-9));
        CHECK(v == Approx(k.depth).margin(1e-9));
    }
}

TEST_CASE("cell loops: a fin's two sides whose tangents meet past the face close it inside the face",
          "[surface][contour]") {
    // A fin 0.1 thick on edge 0 (along x at y = z = 0), from 0.45 to 0.55, its sides turned 0.02
    // rad toward each other into face 4 (u = x, v = y): normals (-cos 0.02, sin 0.02, 0) and
    // (cos 0.02, sin 0.02, 0), 0.04 rad from opposite, well within the feature angle. Their tangent
    // lines meet 0.05 / tan 0.02 = 2.5 into the face, past its far edge; taken for a wedge's tip,
    // the face vertex went to that edge (0.999 in). A fin's sides run alike, and nothing on the
    // face's edges says where its stub ends: the lens stays within the near half of the face.
    const double a = 0.02;
    CellCrossings c;
    c.edges[0].ids = {0, 1};
    c.edges[0].at = {0.45, 0.55};
    c.edges[0].normals = {Vec3(-std::cos(a), std::sin(a), 0.0), Vec3(std::cos(a), std::sin(a), 0.0)};
    REQUIRE(glm::dot(c.edges[0].normals[0], c.edges[0].normals[1]) < -c.creaseCosine);  // a fin
    double u = -1.0, v = -1.0;
    cellLoops(c, [&](int face, std::uint32_t, std::uint32_t, double fu, double fv) {
        if (face == 4) u = fu, v = fv;
        return std::uint32_t(10 + face);
    });
    INFO("face vertex at (" << u << ", " << v << ")");
    CHECK(u == Approx(0.5).margin(1e-9));
    CHECK(v > 0.0);
    CHECK(v <= 0.5);
}

TEST_CASE("cell loops: a wedge whose side lies nearly in the face gets its face vertex near the tip",
          "[surface][contour]") {
    // Material inside two balls: A, centred 0.6 below the face z = 0 at (0.5, 0), whose slice is
    // the circle of radius 0.2 round (0.5, 0), and B, centred in the face at (0.2, -0.3) with
    // radius 0.5. On edge 0 their common part runs from 0.3 (A's side) to 0.6 (B's); in face 4 it
    // ends where the two circles meet. At 0.3, A's normal lies mostly out of the face (its part in
    // the face 0.32), and the slice turns at once round the small circle: the tangent lines meet
    // at (0.3, 0.4), 0.25 from the tip.
    const Vec3 ca(0.5, 0.0, -0.6), cb(0.2, -0.3, 0.0);
    const double ra = std::sqrt(0.6 * 0.6 + 0.2 * 0.2), rb = 0.5;
    const double x1 = 0.3, x2 = 0.2 + std::sqrt(rb * rb - 0.3 * 0.3);
    // The circles' meeting point above the edge: x + y = 0.55 from their difference, then A's.
    const double ty = (0.1 + std::sqrt(0.01 + 8.0 * (0.04 - 0.05 * 0.05))) / 4.0, tx = 0.55 - ty;
    REQUIRE(std::abs(std::hypot(tx - 0.5, ty) - 0.2) < 1e-12);
    REQUIRE(std::abs(std::hypot(tx - 0.2, ty + 0.3) - rb) < 1e-12);
    CellCrossings c;
    c.edges[0].ids = {0, 1};
    c.edges[0].at = {x1, x2};
    c.edges[0].normals = {(Vec3(x1, 0.0, 0.0) - ca) / ra, (Vec3(x2, 0.0, 0.0) - cb) / rb};
    REQUIRE(glm::dot(c.edges[0].normals[0], c.edges[0].normals[1]) < c.creaseCosine);  // a sharp edge
    double u = -1.0, v = -1.0;
    cellLoops(c, [&](int face, std::uint32_t, std::uint32_t, double fu, double fv) {
        if (face == 4) u = fu, v = fv;
        return std::uint32_t(10 + face);
    });
    INFO("face vertex at (" << u << ", " << v << "), the tip at (" << tx << ", " << ty << ")");
    CHECK(std::hypot(u - tx, v - ty) < 0.1);
    CHECK(v > 0.0);
    CHECK(v < 0.4);  // short of the tangents' meeting point
}

TEST_CASE("cell loops: random lattices with several crossings on edges give closed oriented manifolds",
          "[surface][contour]") {
    for (std::uint64_t seed : {3u, 17u, 29u}) {
        std::mt19937_64 rng(seed);
        for (int trial = 0; trial < 60; ++trial) {
            const int n = 6;  // the border is outside
            TestLattice L(n);
            const double density = 0.2 + 0.6 * double(trial % 4) / 3.0;
            std::bernoulli_distribution coin(density), several(0.25);
            std::uniform_real_distribution<float> mag(0.1f, 1.0f);
            std::uniform_real_distribution<double> offset(0.01, 0.99);
            for (int z = 1; z < n - 1; ++z)
                for (int y = 1; y < n - 1; ++y)
                    for (int x = 1; x < n - 1; ++x) L.set(x, y, z, coin(rng), mag(rng));
            // Inner edges: some get extra pairs of crossings.
            for (int z = 1; z < n - 1; ++z)
                for (int y = 1; y < n - 1; ++y)
                    for (int x = 1; x < n - 1; ++x)
                        for (int a = 0; a < 3; ++a) {
                            int q[3] = {x, y, z};
                            ++q[a];
                            if (q[a] >= n - 1 || !several(rng)) continue;
                            const bool differ = L.in[std::size_t(L.at(x, y, z))] != L.in[std::size_t(L.at(q[0], q[1], q[2]))];
                            const int count = (differ ? 1 : 0) + 2 * (1 + int(rng() % 2));
                            std::vector<double> at;
                            while (int(at.size()) < count) {
                                const double t = offset(rng);
                                if (std::none_of(at.begin(), at.end(), [&](double s) { return std::abs(s - t) < 1e-3; }))
                                    at.push_back(t);
                            }
                            std::sort(at.begin(), at.end());
                            L.crossings[{x, y, z, a}] = at;
                        }
            const Built b = build(L);
            const MeshCheck check = checkMesh(b.mesh);
            INFO("seed " << seed << " trial " << trial);
            REQUIRE(check.closedManifold());
            if (!b.mesh.empty()) CHECK(check.signedVolume > 0.0);
        }
    }
}

TEST_CASE("cell loops: lenses on two edges near their corner do not cross in the face", "[surface][contour]") {
    // From tort.ngc at h = 0.5 mm, the cell below the lattice plane z = -2.442 at (3.94, -5.06),
    // all of its corners empty. Edge 0 (along x at y = z = 0) holds material from 0.774 to 0.979,
    // and edge 6 (along y at x = 1, z = 0) from 0.0088 to 0.0753: two thin wedges that come
    // within 0.021 of corner (1, 0, 0). Their face vertices in face 4 (u = x, v = y), placed each
    // on its own, were 0.197 and 0.124 into the face, and the second wedge's path through its
    // vertex crossed the first's: the fan triangles over them passed through each other. The
    // paths must not cross, and each face vertex stays inside the face.
    REQUIRE(edgeAxis(0) == 0);
    REQUIRE(edgeCorner(0, 0) == 0);
    REQUIRE(edgeAxis(6) == 1);
    REQUIRE(edgeCorner(6, 0) == 1);
    CellCrossings c;
    c.edges[0].ids = {0, 1};
    c.edges[0].at = {0.77420806884765625, 0.97872161865234375};
    c.edges[0].normals = {Vec3(-0.22498124282009768, 0.77636969858410754, 0.58875591844120456),
                          Vec3(0.38263822493471256, -0.92389825674627846, 0.0)};
    c.edges[6].ids = {2, 3};
    c.edges[6].at = {0.00881195068359375, 0.07526397705078125};
    c.edges[6].normals = {Vec3(0.38263822493471256, -0.92389825674627846, 0.0),
                          Vec3(-0.25196998128860199, 0.66651400073986511, 0.70161970849396793)};
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::array<double, 2>> vertex;
    cellLoops(c, [&](int face, std::uint32_t from, std::uint32_t to, double u, double v) {
        if (face == 4) vertex[{std::min(from, to), std::max(from, to)}] = {u, v};
        return std::uint32_t(10 + face * 16 + std::min(from, to));
    });
    REQUIRE(vertex.size() == 2);
    const std::array<double, 2> a = vertex.at({0, 1}), b = vertex.at({2, 3});
    INFO("face vertices (" << a[0] << ", " << a[1] << ") and (" << b[0] << ", " << b[1] << ")");
    CHECK(a[1] > 0.0);
    CHECK(b[0] < 1.0);
    using P = std::array<double, 2>;
    const auto orient = [](const P& p, const P& q, const P& r) {
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
    };
    const auto cross = [&](const P& p, const P& q, const P& r, const P& s) {
        return orient(p, q, r) * orient(p, q, s) < 0.0 && orient(r, s, p) * orient(r, s, q) < 0.0;
    };
    const std::array<P, 3> first{P{c.edges[0].at[0], 0.0}, a, P{c.edges[0].at[1], 0.0}};
    const std::array<P, 3> second{P{1.0, c.edges[6].at[0]}, b, P{1.0, c.edges[6].at[1]}};
    for (std::size_t i = 0; i < 2; ++i)
        for (std::size_t j = 0; j < 2; ++j) CHECK_FALSE(cross(first[i], first[i + 1], second[j], second[j + 1]));
}

TEST_CASE("cell loops: a slab that cuts a corner of the cell closer than its lenses reach runs across it",
          "[surface][contour]") {
    // From the contour tests' fin 0.004 h from a lattice point (contour_test.cpp): the cell from
    // (9.5, 8.5) to (10.5, 9.5) in x and y, all of its corners empty. The upright fin cuts the
    // corner of its z faces at x = y = 1: its near side crosses the x edges at y = 1 (1 and 3)
    // 0.0042 h from x = 1 and the y edges at x = 1 (6 and 7) 0.0081 h from y = 1, its far side
    // 0.071 h and 0.178 h from that corner. Each side crosses the cell as one sheet through four
    // crossings, and on the z faces its path runs from the x edge to the y edge. The face rule's
    // samples missed the slab across the corner and read two stubs, whose lenses, a fifth of their
    // chords deep at least (0.013 and 0.034 h), reached past each other's near end and crossed.
    REQUIRE(edgeAxis(1) == 0);
    REQUIRE(edgeCorner(1, 0) == 2);  // x edge at y = 1, z = 0
    REQUIRE(edgeCorner(3, 0) == 6);  // x edge at y = 1, z = 1
    REQUIRE(edgeAxis(6) == 1);
    REQUIRE(edgeCorner(6, 0) == 1);  // y edge at x = 1, z = 0
    REQUIRE(edgeCorner(7, 0) == 5);  // y edge at x = 1, z = 1
    CellCrossings c;
    for (const int e : {1, 3}) {
        const std::uint32_t id = e == 1 ? 0 : 2;
        c.edges[std::size_t(e)].ids = {id, id + 1};
        c.edges[std::size_t(e)].at = {0.92933750152587891, 0.99576425552368164};
        c.edges[std::size_t(e)].normals = {Vec3(-0.92700603109977653, -0.37504642153290857, 0.0),
                                           Vec3(0.88689440657284835, 0.46197219785371829, 0.0)};
    }
    for (const int e : {6, 7}) {
        const std::uint32_t id = e == 6 ? 4 : 6;
        c.edges[std::size_t(e)].ids = {id, id + 1};
        c.edges[std::size_t(e)].at = {0.8220820426940918, 0.99187421798706055};
        c.edges[std::size_t(e)].normals = {Vec3(-0.93171661499612679, -0.36318610840746535, 0.0),
                                           Vec3(0.88658631452194903, 0.46256319233418047, 0.0)};
    }
    int zFaceVertices = 0;
    const auto loops = cellLoops(c, [&](int face, std::uint32_t from, std::uint32_t to, double, double) {
        zFaceVertices += face >= 4;
        return std::uint32_t(10 + face * 16 + std::min(from, to));
    });
    CHECK(zFaceVertices == 0);
    std::vector<std::vector<std::uint32_t>> sorted;
    for (auto loop : loops) {
        std::sort(loop.begin(), loop.end());
        sorted.push_back(loop);
    }
    std::sort(sorted.begin(), sorted.end());
    // The far side through crossings 0, 2, 4 and 6, the near side through 1, 3, 5 and 7.
    const std::vector<std::vector<std::uint32_t>> want{{0, 2, 4, 6}, {1, 3, 5, 7}};
    CHECK(sorted == want);
}

TEST_CASE("cell loops: a notch through a sheet thinner than its lens's least depth opens the sheet",
          "[surface][contour]") {
    // From boat-xyzac.ngc at h = 0.25 mm: the material of the cell lies below a sheet's face at
    // y = 0.0256 (corners with y = 0 in, edges 4 to 7 along y crossed there), and a notch cuts
    // through that thin sheet on edge 9 (along z at x = 1, y = 0) from z = 0.468 to 0.804. On the
    // face x = 1 (face 1) the notch's lens is at least a fifth of its chord deep (0.067), past the
    // sheet's path at 0.026, and the two paths of the one region crossed: the notch's loop and
    // the sheet's were two, and their fans passed through each other. The region is split there:
    // the sheet's path runs into the notch from either side, with no face vertex on face 1, and
    // one loop goes round the sheet's face and the notch.
    REQUIRE(edgeAxis(9) == 2);
    REQUIRE(edgeCorner(9, 0) == 1);  // z edge at x = 1, y = 0
    for (const int e : {4, 5, 6, 7}) REQUIRE(edgeAxis(e) == 1);
    CellCrossings c;
    c.inside = 0x33;  // corners 0, 1, 4 and 5: y = 0
    c.joined = 4;
    for (const int e : {4, 5, 6, 7}) {
        c.edges[std::size_t(e)].ids = {std::uint32_t(e)};
        c.edges[std::size_t(e)].at = {0.025604248046875};
        c.edges[std::size_t(e)].normals = {Vec3(0.0, 1.0, 0.0)};
    }
    c.edges[9].ids = {0, 1};
    c.edges[9].at = {0.46807098388671875, 0.80362319946289062};
    c.edges[9].normals = {Vec3(0.15225046246208002, -0.20929374376772381, 0.96592749494968477),
                          Vec3(0.57388480258685037, -0.77696987140161133, -0.25879345489021821)};
    int face1Vertices = 0;
    const auto loops = cellLoops(c, [&](int face, std::uint32_t from, std::uint32_t to, double, double) {
        face1Vertices += face == 1;
        return std::uint32_t(10 + face * 16 + std::min(from, to));
    });
    CHECK(face1Vertices == 0);
    REQUIRE(loops.size() == 1);
    std::vector<std::uint32_t> crossings;
    for (std::uint32_t id : loops[0])
        if (id < 10) crossings.push_back(id);
    std::sort(crossings.begin(), crossings.end());
    CHECK(crossings == std::vector<std::uint32_t>{0, 1, 4, 5, 6, 7});
}

TEST_CASE("cell loops: a notch whose lens reaches past a crease's corner opens the crease",
          "[surface][contour]") {
    // From boat-xyzac.ngc at h = 0.25 mm, the cell from (0.7943, 12.3186, -4.2875): a pocket's
    // floor (edges 8 and 9, along z at y = 0, crossed at z = 0.51 and 0.47, normals up) meets its
    // wall (edges 5 and 7, along y at z = 1, crossed at y = 0.97 and 0.98, normals along -y) in a
    // crease whose tangent lines meet at y = 0.92, z = 0.43 on the faces x = 0 and 1. A notch cuts
    // the corners' material at y = 1 (edges 10 and 11) from z = 0.40 to 0.88, and its lens on those
    // faces, a wedge whose sides' tangents meet at y = 0.85, holds that corner: the notch opens
    // into the pocket. The chord from the floor's crossing to the wall's missed the lens, so the
    // face rule kept one region, and the pocket's loop and the notch's were two, the crease's
    // vertex inside the notch: their fans passed through each other (42 of the boat's 88 pairs of
    // crossing triangles, in ten such cells along x). The region is split there: the floor runs
    // into the notch's lower side and the wall into its upper side, with no face vertex on x = 0
    // or x = 1.
    REQUIRE(edgeAxis(5) == 1);
    REQUIRE(edgeCorner(5, 0) == 4);  // y edge at x = 0, z = 1
    REQUIRE(edgeCorner(7, 0) == 5);  // y edge at x = 1, z = 1
    REQUIRE(edgeAxis(8) == 2);
    REQUIRE(edgeCorner(8, 0) == 0);   // z edge at x = 0, y = 0
    REQUIRE(edgeCorner(9, 0) == 1);   // z edge at x = 1, y = 0
    REQUIRE(edgeCorner(10, 0) == 2);  // z edge at x = 0, y = 1
    REQUIRE(edgeCorner(11, 0) == 3);  // z edge at x = 1, y = 1
    CellCrossings c;
    c.inside = 0xcf;  // all but corners 4 and 5 (y = 0, z = 1)
    const auto set = [&](int e, std::vector<std::uint32_t> ids, std::vector<double> at, std::vector<Vec3> normals) {
        c.edges[std::size_t(e)].ids = std::move(ids);
        c.edges[std::size_t(e)].at = std::move(at);
        c.edges[std::size_t(e)].normals = std::move(normals);
    };
    set(5, {0}, {0.9729156494140625}, {Vec3(-0.0043828313740830373, -0.99616444610030452, 0.087391001337777593)});
    set(7, {1}, {0.977996826171875}, {Vec3(-0.10468685966349131, -0.99032610880836591, 0.091076119956204682)});
    set(8, {2}, {0.51436233520507812}, {Vec3(0.041791827970313687, 0.087152087885547361, 0.99531801786770113)});
    set(9, {3}, {0.47240447998046875}, {Vec3(0.041791827970313687, 0.087152087885547361, 0.99531801786770113)});
    set(10, {4, 5}, {0.3959503173828125, 0.87920761108398438},
        {Vec3(0.039748950055823622, 0.32598937711778103, 0.94453742486776082),
         Vec3(-0.010168291480337949, 0.94533823716434529, -0.32593285075821832)});
    set(11, {6, 7}, {0.35362625122070312, 0.84596633911132812},
        {Vec3(0.040161379647410768, 0.3260111993290824, 0.94451244644887011),
         Vec3(-0.010404218962383189, 0.94537583579249551, -0.32581633066410792)});
    int xFaceVertices = 0;
    const auto loops = cellLoops(c, [&](int face, std::uint32_t from, std::uint32_t to, double, double) {
        xFaceVertices += face < 2;
        return std::uint32_t(10 + face * 16 + std::min(from, to));
    });
    CHECK(xFaceVertices == 0);
    std::vector<std::vector<std::uint32_t>> sorted;
    for (auto loop : loops) {
        std::sort(loop.begin(), loop.end());
        sorted.push_back(loop);
    }
    std::sort(sorted.begin(), sorted.end());
    // The wall and the notch's upper side through 0, 1, 5 and 7; the floor and its lower side
    // through 2, 3, 4 and 6.
    const std::vector<std::vector<std::uint32_t>> want{{0, 1, 5, 7}, {2, 3, 4, 6}};
    CHECK(sorted == want);
}
