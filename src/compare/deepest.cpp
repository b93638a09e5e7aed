// The deepest point of dexel stretches: a branch and bound with exact distances.
#include "compare/detail/deepest.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

namespace dexelmill {

namespace {

/// The point at t along a stretch's dexel (mm from the lattice's origin along it).
Vec3 stretchPoint(const Lattice& lattice, const DexelStretch& s, double t) {
    const int a = index(s.family), b = (a + 1) % 3, c = (a + 2) % 3;
    Vec3 p;
    p[a] = lattice.origin[a] + t;
    p[b] = lattice.coord(axisFromIndex(b), s.ib);
    p[c] = lattice.coord(axisFromIndex(c), s.ic);
    return p;
}

}  // namespace

Deepest deepestPoint(const MeshDistance& distance, const Lattice& lattice, StretchSpan stretches,
                     double eps) {
    // An interval [t0, t1] of one stretch's coordinate, with the depths at its ends and the
    // triangles nearest there, and a bound on the depth of any point between. Two bounds hold:
    // - the depth changes by at most the distance moved, so no point is deeper than
    //   (f0 + f1 + (t1 - t0)) / 2;
    // - the depth is at most the distance to any one triangle, which is convex along a line
    //   (a triangle is convex), so it is at most the larger of that triangle's distances at the
    //   ends: max(f0, distance from the far end to the triangle nearest t0), and likewise from
    //   t1. Where one face is nearest along the whole piece (a floor cut too deep) this bound
    //   is the ends' depth, and the piece needs no splitting.
    struct Sample {
        double t, f;
        std::uint32_t triangle;
    };
    struct Piece {
        double bound;
        Sample s0, s1;
        std::size_t stretch;
        bool operator<(const Piece& o) const { return bound < o.bound; }
    };
    auto pointOf = [&](std::size_t i, double t) { return stretchPoint(lattice, stretches[i], t); };
    Deepest best;
    // The search starts from the triangle nearest the last sample (usually close by); that
    // speeds it and does not change the answer.
    std::uint32_t hint = 0;
    auto sample = [&](std::size_t i, double t) {
        const Vec3 p = pointOf(i, t);
        const MeshDistance::Nearest n = distance.nearest(p, &hint);
        if (n.distance > best.depth) best.depth = n.distance, best.point = p;
        return Sample{t, n.distance, n.triangle};
    };
    std::priority_queue<Piece> queue;
    auto push = [&](std::size_t i, const Sample& s0, const Sample& s1) {
        double bound = std::min(stretches[i].bound, 0.5 * (s0.f + s1.f + (s1.t - s0.t)));
        if (bound > best.depth + eps) {
            bound = std::min(bound, std::max(s0.f, distance.distanceTo(pointOf(i, s1.t), s0.triangle)));
            bound = std::min(bound, std::max(s1.f, distance.distanceTo(pointOf(i, s0.t), s1.triangle)));
        }
        if (bound > best.depth + eps) queue.push({bound, s0, s1, i});
    };
    // Best bound first: a stretch is sampled at its ends only when its own bound is the highest
    // left, and a piece is split at its middle while its bound is; both stop when nothing left
    // can beat the deepest sample by more than eps.
    // The stretches wait in a heap, highest bound first and ties in their order: usually only a
    // few are taken before the search stops, so they are not sorted.
    using Waiting = std::pair<double, std::size_t>;  // (-bound, stretch)
    std::vector<Waiting> waiting(stretches.size);
    for (std::size_t i = 0; i < stretches.size; ++i) waiting[i] = {-stretches[i].bound, i};
    std::make_heap(waiting.begin(), waiting.end(), std::greater<Waiting>());
    constexpr double kNone = -std::numeric_limits<double>::infinity();
    for (;;) {
        const double queued = queue.empty() ? kNone : queue.top().bound;
        const double next = waiting.empty() ? kNone : -waiting.front().first;
        if (!(std::max(queued, next) > best.depth + eps)) break;
        if (next >= queued) {
            std::pop_heap(waiting.begin(), waiting.end(), std::greater<Waiting>());
            const std::size_t i = waiting.back().second;
            waiting.pop_back();
            push(i, sample(i, stretches[i].lo), sample(i, stretches[i].hi));
            continue;
        }
        const Piece piece = queue.top();
        queue.pop();
        const Sample mid = sample(piece.stretch, 0.5 * (piece.s0.t + piece.s1.t));
        push(piece.stretch, piece.s0, mid);
        push(piece.stretch, mid, piece.s1);
    }
    return best;
}

std::vector<Deepest> deepestPoints(const DesignPart& design, const Lattice& lattice,
                                   const std::vector<DexelStretch>& stretches, const std::vector<std::size_t>& groups,
                                   double eps) {
    const std::size_t count = groups.empty() ? 0 : groups.size() - 1;
    std::vector<Deepest> deepest(count);
    if (stretches.empty()) return deepest;
    const double radius = kNearSpacings * lattice.h;
    std::vector<Box> where(stretches.size());
    // Per group: the depth up to which local distances are exact.
    std::vector<double> trusted(count, std::numeric_limits<double>::infinity());
    for (std::size_t g = 0; g < count; ++g)
        for (std::size_t i = groups[g]; i < groups[g + 1]; ++i) {
            const DexelStretch& s = stretches[i];
            const double r = std::min(s.bound, radius);
            if (r < s.bound) trusted[g] = std::min(trusted[g], r);
            where[i] = Box{stretchPoint(lattice, s, s.lo) - Vec3(r), stretchPoint(lattice, s, s.hi) + Vec3(r)};
        }
    const NearDistance near = design.distanceNear(where);
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t g) {
        const StretchSpan span{stretches.data() + groups[g], groups[g + 1] - groups[g]};
        deepest[g] = deepestPoint(*near, lattice, span, eps);
        if (near.local && deepest[g].depth > trusted[g]) deepest[g] = deepestPoint(design.distance(), lattice, span, eps);
    });
    return deepest;
}

}  // namespace dexelmill
