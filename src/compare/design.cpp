// The design part: its cast on the lattice and its exact distance (MeshDistance).
#include "dexelmill/compare/design.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <queue>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dexelmill/error.h"
#include "dexelmill/io/mesh_io.h"

namespace dexelmill {

namespace {

/// The depth search stops when no point of a move's stretches can lie deeper than the deepest
/// point found by more than this (mm), or a quarter of the tolerance if that is larger.
constexpr double kMinDepthBound = 1e-3;

std::string lowerExtension(const std::string& path) {
    const std::size_t dot = path.find_last_of('.');
    std::string ext = dot == std::string::npos ? std::string() : path.substr(dot);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

}  // namespace

DesignPart::DesignPart(TriDexelStock dexels) : dexels(std::move(dexels)) {}
DesignPart::~DesignPart() = default;
DesignPart::DesignPart(DesignPart&&) noexcept = default;
DesignPart& DesignPart::operator=(DesignPart&&) noexcept = default;

DesignPart loadDesign(const std::string& path, const Lattice& lattice, FamilySet families) {
    if (lowerExtension(path) != ".stl")
        throw Error("'" + path + "': a design must be an STL file (.stl, binary or ASCII)");
    const Mesh mesh = readStl(path);
    MeshCastStats cast;
    DesignPart d(stockFromMesh(mesh, lattice, families, &cast));
    d.cast = cast;
    d.file = path;
    d.bounds = mesh.bounds();
    if (d.dexels.volume(d.dexels.has(Axis::Z) ? Axis::Z : (d.dexels.has(Axis::X) ? Axis::X : Axis::Y)) <= 0.0)
        throw Error("'" + path + "': the design holds no material inside the stock's box");

    d.distance = std::make_unique<MeshDistance>(mesh);
    return d;
}

double depthBound(double tolerance) { return std::max(0.25 * tolerance, kMinDepthBound); }

std::vector<Gouge> findGouges(const DesignPart& design, const Lattice& lattice, const CutResult& cut, double tolerance) {
    const std::vector<DesignStretch>& stretches = cut.designStretches;
    // The stretches come in move order: one group per move.
    std::vector<std::size_t> groups;
    for (std::size_t i = 0; i < stretches.size(); ++i)
        if (i == 0 || stretches[i].move != stretches[i - 1].move) groups.push_back(i);
    groups.push_back(stretches.size());
    const double eps = depthBound(tolerance);

    struct Deepest {
        double depth = -std::numeric_limits<double>::infinity();
        Vec3 point{0.0};
    };
    std::vector<Deepest> deepest(groups.size() - 1);
    tbb::parallel_for(std::size_t(0), groups.size() - 1, [&](std::size_t g) {
        // An interval [t0, t1] of one stretch's coordinate with the depths at its ends. The
        // distance to a surface changes by at most the distance moved, so no point of it is deeper
        // than (f0 + f1 + (t1 - t0)) / 2.
        struct Piece {
            double bound, t0, t1, f0, f1;
            std::size_t stretch;
            bool operator<(const Piece& o) const { return bound < o.bound; }
        };
        auto pointOf = [&](std::size_t i, double t) {
            const DesignStretch& s = stretches[i];
            const int a = index(s.family), b = (a + 1) % 3, c = (a + 2) % 3;
            Vec3 p;
            p[a] = lattice.origin[a] + t;
            p[b] = lattice.coord(axisFromIndex(b), s.ib);
            p[c] = lattice.coord(axisFromIndex(c), s.ic);
            return p;
        };
        Deepest& best = deepest[g];
        auto depthAt = [&](std::size_t i, double t) {
            const Vec3 p = pointOf(i, t);
            const double d = design.distance->distance(p);
            if (d > best.depth) best.depth = d, best.point = p;
            return d;
        };
        std::priority_queue<Piece> queue;
        auto push = [&](std::size_t i, double t0, double t1, double f0, double f1) {
            const double bound = 0.5 * (f0 + f1 + (t1 - t0));
            if (bound > best.depth + eps) queue.push({bound, t0, t1, f0, f1, i});
        };
        // Start from samples half a spacing apart, then split the piece that could hold the
        // deepest point until none can beat the deepest sample by more than eps.
        for (std::size_t i = groups[g]; i < groups[g + 1]; ++i) {
            const double lo = double(stretches[i].lo), hi = double(stretches[i].hi);
            const int steps = std::max(1, int(std::ceil((hi - lo) / (0.5 * lattice.h))));
            double t0 = lo, f0 = depthAt(i, lo);
            for (int k = 1; k <= steps; ++k) {
                const double t1 = k == steps ? hi : lo + (hi - lo) * k / steps;
                const double f1 = depthAt(i, t1);
                push(i, t0, t1, f0, f1);
                t0 = t1, f0 = f1;
            }
        }
        while (!queue.empty()) {
            const Piece piece = queue.top();
            queue.pop();
            if (!(piece.bound > best.depth + eps)) break;
            const double tm = 0.5 * (piece.t0 + piece.t1);
            const double fm = depthAt(piece.stretch, tm);
            push(piece.stretch, piece.t0, tm, piece.f0, fm);
            push(piece.stretch, tm, piece.t1, fm, piece.f1);
        }
    });
    // Volumes as the report measures them: the z family's, else x's, else y's.
    const TriDexelStock& d = design.dexels;
    const Axis measure = d.has(Axis::Z) ? Axis::Z : (d.has(Axis::X) ? Axis::X : Axis::Y);
    std::vector<Gouge> gouges;
    for (std::size_t g = 0; g + 1 < groups.size(); ++g) {
        if (!(deepest[g].depth > tolerance)) continue;
        Gouge gouge;
        gouge.move = stretches[groups[g]].move;
        gouge.depth = deepest[g].depth;
        gouge.point = deepest[g].point;
        gouge.volume = cut.moves[gouge.move].designRemoved[std::size_t(index(measure))];
        gouges.push_back(gouge);
    }
    return gouges;
}

}  // namespace dexelmill
