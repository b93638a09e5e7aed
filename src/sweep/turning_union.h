// What a turning sweep's query (TurningSweep::intersect, turning.cpp) builds for one line and
// asks of it, shared by its searches: the union O of the intervals found so far, and whether O
// holds the line's care over an interval.
#pragma once

#include <algorithm>
#include <cstdint>

#include <boost/container/small_vector.hpp>

#include "dexelmill/geometry/types.h"

namespace dexelmill::turning {

/// One output interval with where each end came from: the pose u and the part whose interval
/// made it, or the linear node (note h) whose move made it.
struct Piece {
    Interval range;
    double uLo = 0.0, uHi = 0.0;
    std::size_t partLo = 0, partHi = 0;
    /// The heap index of the linear node whose sweep made the end; 0 when a pose made it.
    std::uint32_t nodeLo = 0, nodeHi = 0;
};

/// A query's short lists, kept in place: most lines meet a tool in a few intervals and settle
/// with a few poses, and a heap allocation per list cost a tenth of a short move's query.
template <class T, std::size_t N = 8>
using ShortList = boost::container::small_vector<T, N>;

/// The union of static-pose intervals found so far: sorted, disjoint.
class Union {
  public:
    void add(const Interval& iv, double u, std::size_t part) { add(iv, u, u, part); }
    /// Adds an interval whose ends were made at different poses.
    void add(const Interval& iv, double uLo, double uHi, std::size_t part, std::uint32_t node = 0) {
        Piece p{iv, uLo, uHi, part, part, node, node};
        auto it = std::lower_bound(pieces_.begin(), pieces_.end(), iv.lo,
                                   [](const Piece& q, double lo) { return q.range.hi < lo; });
        // Merge every piece that overlaps or touches the new one.
        auto last = it;
        while (last != pieces_.end() && last->range.lo <= iv.hi) {
            if (last->range.lo < p.range.lo)
                p.range.lo = last->range.lo, p.uLo = last->uLo, p.partLo = last->partLo, p.nodeLo = last->nodeLo;
            if (last->range.hi > p.range.hi)
                p.range.hi = last->range.hi, p.uHi = last->uHi, p.partHi = last->partHi, p.nodeHi = last->nodeHi;
            ++last;
        }
        it = pieces_.erase(it, last);
        pieces_.insert(it, p);
    }
    /// Whether [lo, hi] lies inside one piece.
    bool holds(double lo, double hi) const {
        auto it = std::lower_bound(pieces_.begin(), pieces_.end(), lo,
                                   [](const Piece& q, double v) { return q.range.hi < v; });
        return it != pieces_.end() && it->range.lo <= lo && hi <= it->range.hi;
    }
    const ShortList<Piece>& pieces() const { return pieces_; }

  private:
    ShortList<Piece> pieces_;
};

/// The parts of the line where the answer matters (sorted, disjoint), and O so far.
class Care {
  public:
    Care(const Interval* begin, const Interval* end, const Union& found)
        : begin_(begin), end_(end), within_(begin->hull(end[-1])), found_(found) {}
    /// The hull of the care.
    const Interval& within() const { return within_; }
    /// Whether `g` holds no point of care outside O.
    bool held(const Interval& g) const {
        for (const Interval* c = begin_; c != end_ && !g.isEmpty(); ++c) {
            const Interval part = g.intersect(*c);
            if (!part.isEmpty() && !found_.holds(part.lo, part.hi)) return false;
        }
        return true;
    }
    /// The first stretch of `g` within the care that O leaves out: from its start to the next
    /// piece of O or the end of that stretch of care; empty when O holds all of it.
    Interval firstGap(const Interval& g) const {
        for (const Interval* c = begin_; c != end_ && !g.isEmpty(); ++c) {
            const Interval part = g.intersect(*c);
            if (part.isEmpty()) continue;
            double from = part.lo;
            for (const Piece& p : found_.pieces()) {
                if (p.range.hi < from) continue;
                if (p.range.lo > from) return {from, std::min(p.range.lo, part.hi)};
                from = p.range.hi;
                if (from >= part.hi) break;
            }
            // A stretch of a single point that no piece reached is a gap too, as held says.
            if (from < part.hi || !found_.holds(from, from)) return {from, part.hi};
        }
        return Interval::empty();
    }
    /// Whether some of the care lies in `g`.
    bool meets(const Interval& g) const {
        return std::any_of(begin_, end_, [&](const Interval& c) { return !c.intersect(g).isEmpty(); });
    }

  private:
    const Interval* begin_;
    const Interval* end_;
    Interval within_;
    const Union& found_;
};

}  // namespace dexelmill::turning
