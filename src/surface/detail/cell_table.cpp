#include "surface/detail/cell_table.h"

#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace dexelmill::detail {

namespace {

int cornerIndex(int x, int y, int z) { return x | (y << 1) | (z << 2); }

int cornerAt(const int off[3]) { return cornerIndex(off[0], off[1], off[2]); }

/// The edge joining two corners that differ along one axis.
int edgeBetween(int c0, int c1) {
    const int diff = c0 ^ c1;
    const int a = diff == 1 ? 0 : (diff == 2 ? 1 : 2);
    const int lower = (c0 >> a) & 1 ? c1 : c0;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    return 4 * a + cornerOffset(lower, b) + 2 * cornerOffset(lower, c);
}

glm::dvec3 cornerPoint(int k) { return {double(k & 1), double((k >> 1) & 1), double((k >> 2) & 1)}; }

glm::dvec3 edgeMidpoint(int e) {
    return 0.5 * (cornerPoint(edgeCorner(e, 0)) + cornerPoint(edgeCorner(e, 1)));
}

/// One face segment between the crossings of two of its edges, oriented (from, to).
struct Segment {
    int from, to;
};

/// The segments of one face: 0, 1 or 2, oriented so that the fan triangle (cell centre, from, to)
/// faces out of the material.
void faceSegments(int face, std::uint8_t inside, bool joined, std::vector<Segment>& out) {
    const std::array<int, 4> k = faceCorners(face);
    bool in[4];
    for (int i = 0; i < 4; ++i) in[i] = (inside >> k[i]) & 1;
    int edge[4];  // edge[i] joins corners i and i + 1
    for (int i = 0; i < 4; ++i) edge[i] = edgeBetween(k[i], k[(i + 1) % 4]);
    int crossings = 0;
    for (int i = 0; i < 4; ++i) crossings += in[i] != in[(i + 1) % 4];
    if (crossings == 0) return;

    // Each segment cuts a set of corners off the face; `pointsInward` is the direction from the
    // segment's midpoint towards the material on the face.
    auto add = [&](int e0, int e1, const glm::dvec3& pointsInward) {
        const glm::dvec3 centre(0.5), m0 = edgeMidpoint(e0), m1 = edgeMidpoint(e1);
        const glm::dvec3 n = glm::cross(m0 - centre, m1 - centre);
        if (glm::dot(n, -pointsInward) > 0.0) out.push_back({e0, e1});
        else out.push_back({e1, e0});
    };
    if (crossings == 2) {
        int e[2], m = 0;
        for (int i = 0; i < 4; ++i)
            if (in[i] != in[(i + 1) % 4]) e[m++] = edge[i];
        glm::dvec3 inCentroid(0.0);
        int nIn = 0;
        for (int i = 0; i < 4; ++i)
            if (in[i]) inCentroid += cornerPoint(k[i]), ++nIn;
        inCentroid /= double(nIn);
        const glm::dvec3 mid = 0.5 * (edgeMidpoint(e[0]) + edgeMidpoint(e[1]));
        add(e[0], e[1], inCentroid - mid);
        return;
    }
    // Ambiguous: corners alternate. Cut off the inside corners, or (joined) the outside ones.
    for (int i = 0; i < 4; ++i) {
        if (in[i] == joined) continue;  // not a corner to cut off
        const int e0 = edge[(i + 3) % 4], e1 = edge[i];
        const glm::dvec3 corner = cornerPoint(k[i]);
        const glm::dvec3 mid = 0.5 * (edgeMidpoint(e0) + edgeMidpoint(e1));
        add(e0, e1, in[i] ? corner - mid : mid - corner);
    }
}

CellPatches buildPatches(std::uint8_t inside, std::uint8_t joined) {
    std::vector<Segment> segs;
    for (int f = 0; f < kCellFaces; ++f) faceSegments(f, inside, (joined >> f) & 1, segs);
    // Each crossing edge starts one segment and ends another: chain them into loops.
    int next[kCellEdges];
    for (int& n : next) n = -1;
    for (const Segment& s : segs) next[s.from] = s.to;
    CellPatches p;
    p.patchOf.fill(0xff);
    int at = 0;
    for (int start = 0; start < kCellEdges; ++start) {
        if (next[start] < 0 || p.patchOf[start] != 0xff) continue;
        int e = start, len = 0;
        do {
            p.patchOf[e] = p.count;
            p.edges[at + len++] = std::uint8_t(e);
            e = next[e];
        } while (e != start);
        p.size[p.count++] = std::uint8_t(len);
        at += len;
    }
    return p;
}

/// The patches of every configuration, for every choice on its ambiguous faces only (656 entries
/// in all, most configurations having none).
struct Tables {
    std::vector<CellPatches> patches;
    std::uint16_t first[256];      // first entry of configuration m
    std::uint8_t ambiguous[256];

    Tables() {
        for (int m = 0; m < 256; ++m) {
            ambiguous[m] = 0;
            for (int f = 0; f < kCellFaces; ++f) {
                const std::array<int, 4> k = faceCorners(f);
                const bool a = (m >> k[0]) & 1, b = (m >> k[1]) & 1, c = (m >> k[2]) & 1, d = (m >> k[3]) & 1;
                if (a == c && b == d && a != b) ambiguous[m] |= std::uint8_t(1u << f);
            }
            first[m] = std::uint16_t(patches.size());
            const int n = __builtin_popcount(ambiguous[m]);
            for (int choice = 0; choice < (1 << n); ++choice)
                patches.push_back(buildPatches(std::uint8_t(m), expand(ambiguous[m], choice)));
        }
    }

    /// Spreads the bits of `choice` over the set bits of `mask` (lowest first).
    static std::uint8_t expand(std::uint8_t mask, int choice) {
        std::uint8_t out = 0;
        for (int f = 0, i = 0; f < kCellFaces; ++f)
            if ((mask >> f) & 1) out |= std::uint8_t(((choice >> i++) & 1) << f);
        return out;
    }
    /// The inverse: gathers the bits of `joined` at the set bits of `mask`.
    static int compress(std::uint8_t mask, std::uint8_t joined) {
        int out = 0;
        for (int f = 0, i = 0; f < kCellFaces; ++f)
            if ((mask >> f) & 1) out |= ((joined >> f) & 1) << i++;
        return out;
    }
};

const Tables& tables() {
    static const Tables t;
    return t;
}

/// The face of a cell holding both of two of its edges (they are two edges of one face).
int faceOfEdges(int e0, int e1) {
    for (int face = 0; face < kCellFaces; ++face) {
        const std::array<int, 4> k = faceCorners(face);
        int found = 0;
        for (int i = 0; i < 4; ++i) {
            const int c0 = k[i], c1 = k[(i + 1) % 4];
            for (int e : {e0, e1}) {
                const int a = edgeCorner(e, 0), b = edgeCorner(e, 1);
                if ((a == c0 && b == c1) || (a == c1 && b == c0)) ++found;
            }
        }
        if (found == 2) return face;
    }
    return -1;
}

/// The same physical edge seen from the neighbour across `face`: the edge's index there.
int edgeAcross(int edge, int face) {
    const int a = face >> 1;
    int c0 = edgeCorner(edge, 0), c1 = edgeCorner(edge, 1);
    c0 ^= 1 << a;
    c1 ^= 1 << a;
    for (int e = 0; e < kCellEdges; ++e) {
        const int x = edgeCorner(e, 0), y = edgeCorner(e, 1);
        if ((x == c0 && y == c1) || (x == c1 && y == c0)) return e;
    }
    return -1;
}

}  // namespace

int edgeCorner(int edge, int end) {
    const int a = edgeAxis(edge), j = edge & 3;
    int off[3];
    off[a] = end;
    off[(a + 1) % 3] = j & 1;
    off[(a + 2) % 3] = j >> 1;
    return cornerAt(off);
}

std::array<int, 4> faceCorners(int face) {
    const int a = face >> 1, s = face & 1, b = (a + 1) % 3, c = (a + 2) % 3;
    std::array<int, 4> k{};
    const int bc[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < 4; ++i) {
        int off[3];
        off[a] = s;
        off[b] = bc[i][0];
        off[c] = bc[i][1];
        k[i] = cornerAt(off);
    }
    return k;
}

std::uint8_t ambiguousFaces(std::uint8_t inside) { return tables().ambiguous[inside]; }

const CellPatches& cellPatches(std::uint8_t inside, std::uint8_t joined) {
    const Tables& t = tables();
    const std::uint8_t amb = t.ambiguous[inside];
    return t.patches[t.first[inside] + (amb ? std::size_t(Tables::compress(amb, joined)) : 0)];
}

bool insideJoinedAcrossFace(float f00, float f10, float f11, float f01) {
    // Bilinear f(s, t) = f00 (1-s)(1-t) + f10 s (1-t) + f11 s t + f01 (1-s) t has its saddle value
    // (f00 f11 - f10 f01) / (f00 + f11 - f10 - f01). On an ambiguous face the denominator is
    // non-zero (f00, f11 share a sign opposite to f10, f01), and its sign is f00's.
    const double num = double(f00) * f11 - double(f10) * f01;
    const double den = double(f00) + f11 - f10 - f01;
    return num / den < 0.0;
}

EdgeTables::EdgeTables() {
    for (int i = 0; i < kCellEdges; ++i) {
        for (int j = 0; j < kCellEdges; ++j) face[i][j] = std::int8_t(i == j ? -1 : faceOfEdges(i, j));
        for (int f = 0; f < kCellFaces; ++f) across[i][f] = std::int8_t(edgeAcross(i, f));
    }
}

const EdgeTables& edgeTables() {
    static const EdgeTables t;
    return t;
}

const std::array<EdgeStart, kCellEdges>& edgeStarts() {
    static const std::array<EdgeStart, kCellEdges> t = [] {
        std::array<EdgeStart, kCellEdges> out{};
        for (int e = 0; e < kCellEdges; ++e) {
            const int c = edgeCorner(e, 0);
            out[std::size_t(e)] = {c & 1, (c >> 1) & 1, (c >> 2) & 1, edgeAxis(e)};
        }
        return out;
    }();
    return t;
}

}  // namespace dexelmill::detail
