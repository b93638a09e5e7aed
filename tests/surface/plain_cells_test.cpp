// The dexel mesher's plain cells: a cell the surface crosses as one flat square across a lattice
// axis (a face of the stock box, a pocket's floor or wall) takes two triangles and no patch
// vertex. The cells that should be plain are counted from the exact part alone, by an oracle that
// shares no code with the mesher: each cell's corners classified by exact membership, each of its
// four crossings bisected along its edge, and the surface's normal there taken from the analytic
// shape that bounds the part at that point.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <random>
#include <sstream>

#include "dexelmill/surface/contour.h"
#include "dexelmill/surface/levelset.h"
#include "support/analytic_parts.h"
#include "support/face_deviation.h"

using namespace dexelmill;
using dexelmill::testing::CarvedPart;
using dexelmill::testing::Cutter;

namespace {

/// Two crossings at the same height differ by less than this (mm): the carving bisects each dexel
/// end to 1e-12 mm, and the lattice is a few tens of mm across.
constexpr double kSameHeight = 1e-9;
/// Points sampled along each edge of a cell that may be plain: the features the tests cut are
/// at least a twentieth of a cell thick.
constexpr int kEdgeSamples = 256;

/// The outward normal of the part at x, a point of its surface: the stock box's face, or the
/// reversed normal of the cutter whose boundary passes through x (the one whose membership
/// changes across x along axis a).
Vec3 outwardNormal(const CarvedPart& part, const Vec3& x, int a) {
    Vec3 step(0.0);
    step[a] = 1e-7;
    for (const Cutter& c : part.cuts)
        if (c.inside(x - step) != c.inside(x + step)) return -c.normal(x);
    Vec3 n(0.0);
    n[a] = std::abs(x[a] - part.box.lo[a]) < std::abs(x[a] - part.box.hi[a]) ? -1.0 : 1.0;
    return n;
}

/// Lattice points per axis of a box at spacing h: ceil(size / h).
std::array<int, 3> pointsPerAxis(const Box& box, double h) {
    std::array<int, 3> n{};
    for (int a = 0; a < 3; ++a) n[std::size_t(a)] = int(std::ceil((box.hi[a] - box.lo[a]) / h));
    return n;
}

/// The lattice point (i, j, k): spacing h from the box's lower corner, half a spacing in.
Vec3 latticePoint(const Box& box, double h, int i, int j, int k) {
    return box.lo + (Vec3(double(i), double(j), double(k)) + 0.5) * h;
}

/// The cells (by lower lattice corner, from one point outside the box on each side) that the
/// exact part's surface crosses as one square across an axis: corners split by that axis alone,
/// four crossings at one height, each with the part's normal along the axis.
std::size_t expectedPlainCells(const CarvedPart& part, double h) {
    const std::array<int, 3> n = pointsPerAxis(part.box, h);
    std::size_t plain = 0;
    for (int i = -1; i < n[0]; ++i)
        for (int j = -1; j < n[1]; ++j)
            for (int k = -1; k < n[2]; ++k) {
                std::array<bool, 8> in{};
                for (int c = 0; c < 8; ++c)
                    in[std::size_t(c)] = part.inside(latticePoint(part.box, h, i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)));
                for (int a = 0; a < 3; ++a) {
                    // Every corner on the axis's lower side as corner 0, every one on its upper
                    // side the other way.
                    bool slab = true;
                    for (int c = 0; c < 8; ++c) {
                        const bool upper = (c >> a) & 1;
                        if (in[std::size_t(c)] != (upper ? !in[0] : in[0])) slab = false;
                    }
                    if (!slab) continue;
                    bool flat = true;
                    double height = 0.0;
                    for (int c = 0; c < 8 && flat; ++c) {
                        if ((c >> a) & 1) continue;
                        const Vec3 p0 = latticePoint(part.box, h, i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
                        Vec3 p1 = p0;
                        p1[a] += h;
                        // Bisect the change of membership along the edge.
                        Vec3 lo = p0, hi = p1;
                        for (int it = 0; it < 80; ++it) {
                            const Vec3 mid = 0.5 * (lo + hi);
                            (part.inside(mid) == in[std::size_t(c)] ? lo : hi) = mid;
                        }
                        const Vec3 x = 0.5 * (lo + hi);
                        Vec3 want(0.0);
                        want[a] = in[std::size_t(c)] ? 1.0 : -1.0;  // material below: outward is +a
                        const Vec3 normal = outwardNormal(part, x, a);
                        if (glm::length(normal - want) > 1e-12) flat = false;
                        if (c == 0) height = x[a];
                        else if (std::abs(x[a] - height) > kSameHeight) flat = false;
                    }
                    // No other surface meets the cell's edges: a wall or slot thinner than the
                    // spacing across one of them is not in a flat square's cell.
                    for (int e = 0; e < 12 && flat; ++e) {
                        const int axis = e >> 2, b = (axis + 1) % 3, c = (axis + 2) % 3;
                        std::array<int, 3> lo{i, j, k};
                        lo[std::size_t(b)] += e & 1;
                        lo[std::size_t(c)] += (e >> 1) & 1;
                        const Vec3 p0 = latticePoint(part.box, h, lo[0], lo[1], lo[2]);
                        int changes = 0;
                        bool prev = part.inside(p0);
                        for (int s = 1; s <= kEdgeSamples; ++s) {
                            Vec3 x = p0;
                            x[axis] += h * double(s) / kEdgeSamples;
                            const bool now = part.inside(x);
                            changes += now != prev;
                            prev = now;
                        }
                        flat = changes == (axis == a ? 1 : 0);
                    }
                    plain += flat;
                }
            }
    return plain;
}

struct Contoured {
    Mesh mesh;
    ContourStats stats;
    MeshCheck check;
};

Contoured contour(const CarvedPart& part, double h) {
    TriDexelStock stock = TriDexelStock::fromBox(part.box, h);
    for (const Cutter& c : part.cuts) testing::carve(stock, c);
    const LevelSet ls = rebuildLevelSet(stock);
    Contoured r;
    r.mesh = contourStock(ls, stock, {}, &r.stats);
    r.check = checkMesh(r.mesh);
    return r;
}

/// The triangles with no patch vertex, and how many of them are not a square's half on the exact
/// surface: their normal must be a lattice axis, their corners at one height along it, and the
/// part's membership must change across each corner within kOnSurface. (Between the corners the
/// part may hold a notch narrower than a cell, which no lattice edge crosses and the fan of a
/// patch vertex would miss alike.)
struct PlainTriangles {
    std::size_t count = 0, offSurface = 0;
};

constexpr double kOnSurface = 1e-6;

PlainTriangles plainTriangles(const Contoured& r, const CarvedPart& part) {
    PlainTriangles out;
    for (const Mesh::Triangle& tri : r.mesh.triangles) {
        if (tri[0] >= r.stats.crossings || tri[1] >= r.stats.crossings || tri[2] >= r.stats.crossings) continue;
        ++out.count;
        const Vec3 a = r.mesh.vertices[tri[0]], b = r.mesh.vertices[tri[1]], c = r.mesh.vertices[tri[2]];
        const Vec3 area = glm::cross(b - a, c - a);
        int axis = 0;
        for (int k = 1; k < 3; ++k)
            if (std::abs(area[k]) > std::abs(area[axis])) axis = k;
        const Vec3 n = glm::normalize(area);
        bool on = area[(axis + 1) % 3] == 0.0 && area[(axis + 2) % 3] == 0.0 && a[axis] == b[axis] && b[axis] == c[axis];
        for (const Vec3& p : {a, b, c}) on = on && part.inside(p - kOnSurface * n) && !part.inside(p + kOnSurface * n);
        out.offSurface += !on;
    }
    return out;
}

}  // namespace

TEST_CASE("contour: plain cells are the flat squares across an axis", "[surface][contour]") {
    std::mt19937 rng(20261127);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::size_t plainSeen = 0, stepped = 0, tilted = 0;
    for (int n = 0; n < 24; ++n) {
        const double h = n % 2 ? 1.0 : 0.7;
        const Box box{Vec3(-2.0 + u(rng), 1.0 + u(rng), 0.5 * u(rng)),
                      Vec3(14.0 + 3.0 * u(rng), 12.0 + 3.0 * u(rng), 9.0 + 2.0 * u(rng))};
        CarvedPart part{box, {}};
        // Two pockets in disjoint x ranges: from above (past the top), a slot through a side, or a
        // void inside.
        const double midX = 0.5 * (box.lo.x + box.hi.x);
        std::array<Box, 2> pockets;
        for (int side = 0; side < 2; ++side) {
            const double x0 = side ? midX + 0.5 : box.lo.x + 1.0 + u(rng);
            const double x1 = side ? box.hi.x - 1.0 - u(rng) : midX - 0.5;
            const double y0 = box.lo.y + 1.0 + 2.0 * u(rng), y1 = box.hi.y - 1.0 - 2.0 * u(rng);
            const double z0 = box.lo.z + 1.0 + 4.0 * u(rng);
            Box& pocket = pockets[std::size_t(side)];
            pocket = Box{Vec3(x0, y0, z0), Vec3(x1, y1, box.hi.z + 1.0)};
            const int kind = (n + side) % 3;
            if (kind == 1) pocket.lo.y = box.lo.y - 1.0;
            if (kind == 2) pocket.hi.z = z0 + 1.5 + 2.0 * u(rng);
        }
        part.cuts.push_back(testing::boxCutter(pockets[0]));
        if (n % 4 == 1) {
            // The second pocket's floor tilted about y by 1e-4 to 0.2 radians: its cells are not
            // plain (the normal is off the axis, and the heights differ by up to 0.2 h).
            const double angle = std::exp(std::log(1e-4) + u(rng) * (std::log(0.2) - std::log(1e-4)));
            const Box& p = pockets[1];
            const Vec3 up = glm::normalize(Vec3(std::sin(angle), 0.0, std::cos(angle)));
            const Vec3 centre(0.5 * (p.lo.x + p.hi.x), 0.5 * (p.lo.y + p.hi.y), p.lo.z);
            part.cuts.push_back(testing::halfSpaces({{Vec3(1, 0, 0), p.hi.x}, {Vec3(-1, 0, 0), -p.lo.x},
                                                     {Vec3(0, 1, 0), p.hi.y}, {Vec3(0, -1, 0), -p.lo.y},
                                                     {Vec3(0, 0, 1), p.hi.z}, {-up, -glm::dot(up, centre)}}));
            ++tilted;
        } else {
            part.cuts.push_back(testing::boxCutter(pockets[1]));
        }
        if (n % 3 == 0) {
            // A step a twentieth of a cell down in the first pocket's floor, over half its width:
            // the cells across the step hold crossings at two heights, and are not plain.
            Box step = pockets[0];
            step.hi.x = 0.5 * (step.lo.x + step.hi.x);
            step.hi.z = std::min(step.hi.z, box.hi.z + 1.0);
            step.lo.z -= 0.05 * h;
            part.cuts.push_back(testing::boxCutter(step));
            ++stepped;
        }
        const Contoured r = contour(part, h);
        const std::size_t expected = expectedPlainCells(part, h);
        std::ostringstream what;
        what << "part " << n << " at h " << h << ": " << r.stats.plainCells << " plain cells, " << expected
             << " expected; " << r.mesh.triangles.size() << " triangles";
        INFO(what.str());
        CHECK(r.check.ok());
        CHECK(r.stats.plainCells == expected);
        plainSeen += r.stats.plainCells;
        // The plain cells' triangles are the only ones with no patch vertex (crossings come
        // first in the vertex list): two per cell, each on the exact surface.
        const PlainTriangles t = plainTriangles(r, part);
        CHECK(t.count == 2 * r.stats.plainCells);
        CHECK(t.offSurface == 0);
    }
    CHECK(plainSeen > 0);
    CHECK(stepped > 0);
    CHECK(tilted > 0);
}

TEST_CASE("contour: plain cells leave the block's volume and faces as they were", "[surface][contour]") {
    // An uncut block: every cell inside a face is plain, and the mesh holds the box's volume.
    const Box box{Vec3(-3.1, 2.05, 0.3), Vec3(9.37, 13.9, 7.77)};
    const double h = 0.7;
    const CarvedPart part{box, {}};
    const Contoured r = contour(part, h);
    CHECK(r.check.ok());
    CHECK(r.stats.plainCells == expectedPlainCells(part, h));
    // The cells across each face, less the rows along its edges: (n_b - 1)(n_c - 1) per face
    // from n lattice points per axis, which the oracle counted one by one.
    const std::array<int, 3> n = pointsPerAxis(box, h);
    std::size_t faces = 0;
    for (int a = 0; a < 3; ++a) faces += std::size_t(2 * (n[std::size_t((a + 1) % 3)] - 1) * (n[std::size_t((a + 2) % 3)] - 1));
    CHECK(r.stats.plainCells == faces);
    CHECK(r.check.signedVolume == Approx(box.volume()).epsilon(1e-7));
    CHECK(r.stats.patches + r.stats.plainCells == r.stats.cells);
}

TEST_CASE("contour: a floor at one height on the lattice's edges but tilted there is not plain",
          "[surface][contour]") {
    // The floor z = z0 + A sin(2 pi (x - x0) / h), with x0 on the lattice: every vertical lattice
    // edge meets it at height z0, but its normal there leans in x, and between the edges it waves.
    // Its cells hold four crossings at one height, and are not plain; the block's faces are.
    const double h = 0.8, A = 0.05 * h, z0 = 5.3;
    const Box box{Vec3(0.0), Vec3(9.6, 7.2, 8.0)};
    const double x0 = box.lo.x + 0.5 * h, k = 2.0 * 3.14159265358979323846 / h;
    const Cutter wave{[=](const Vec3& p) { return p.z > z0 + A * std::sin(k * (p.x - x0)); },
                      {[=](const Vec3& p) { return std::abs(p.z - z0 - A * std::sin(k * (p.x - x0))); }},
                      [=](const Vec3& p) { return glm::normalize(Vec3(A * k * std::cos(k * (p.x - x0)), 0.0, -1.0)); }};
    const CarvedPart part{box, {wave}};
    const Contoured r = contour(part, h);
    CHECK(r.check.ok());
    const std::size_t expected = expectedPlainCells(part, h);
    CHECK(r.stats.plainCells == expected);
    // The bottom's cells are among them, and no triangle at the floor's height has no patch vertex.
    const std::array<int, 3> n = pointsPerAxis(box, h);
    CHECK(expected >= std::size_t((n[0] - 1) * (n[1] - 1)));
    std::size_t atFloor = 0;
    for (const Mesh::Triangle& tri : r.mesh.triangles) {
        bool plain = true, floor = true;
        for (std::uint32_t v : tri) {
            plain = plain && v < r.stats.crossings;
            floor = floor && std::abs(r.mesh.vertices[v].z - z0) < 1e-6;
        }
        atFloor += plain && floor;
    }
    CHECK(atFloor == 0);
    const PlainTriangles t = plainTriangles(r, part);
    CHECK(t.count == 2 * r.stats.plainCells);
    CHECK(t.offSurface == 0);
}
