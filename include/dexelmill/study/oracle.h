/// @file oracle.h
/// @brief The exact machined solid by brute force (method.md section 6): a point is removed iff
/// some move puts it inside the tool at some feed parameter u in [0, 1]. Shares no code with the
/// sweep solver: it samples u densely and refines with a golden-section search, using only the
/// tool's profile radius and the move's pose at u (a turning move's from its MotionLaw, the
/// move's definition). Slow, simple and independent: the yardstick of accuracy studies.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/path/motion.h"
#include "dexelmill/path/toolpath.h"

namespace dexelmill {

/// @brief Point membership in "stock minus the union of the swept volumes", localised with a
/// uniform grid of buckets over the stock so a query only visits the moves whose tool box
/// overlaps its bucket. The buckets are its own, not the cutting loop's dexel tiles: a mistake in
/// the loop's localisation must not hide itself by dropping the same moves here.
class MachinedSolidOracle {
public:
    /// @param stock the stock box; the program's moves are taken from `path`, their tools from
    /// `tools` (every tool a move names must be there). Both are copied.
    /// @param resolution the finest length the oracle must resolve along a move (mm); the feed
    /// parameter is sampled so that no tool point moves more than resolution / 4 between samples.
    /// @throw Error if a move names a tool that is not in the table.
    MachinedSolidOracle(const Box& stock, const ToolPath& path, const ToolTable& tools, double resolution);
    MachinedSolidOracle(const MachinedSolidOracle&) = delete;
    MachinedSolidOracle& operator=(const MachinedSolidOracle&) = delete;

    /// @brief True when some move's tool covers p at some u in [0, 1].
    bool removed(const Vec3& p) const;
    /// @brief True when p is in the stock box and not removed: inside the exact machined part.
    bool inside(const Vec3& p) const { return stock_.contains(p) && !removed(p); }
    const Box& stock() const { return stock_; }

private:
    struct MoveRef {
        Vec3 start, feed, axis;
        const Tool* tool;
        Box bounds;
        /// A move whose tool axis turns: its motion law, and a bound on how fast a tool point
        /// moves with u (mm per unit u). Null for a fixed axis.
        std::shared_ptr<const MotionLaw> law;
        double speed = 0.0;
    };
    bool inSweep(const MoveRef& m, const Vec3& p) const;
    std::size_t bucketOf(const Vec3& p) const;
    int bucketAlong(int axis, double v) const;

    Box stock_;
    double step_;
    ToolTable tools_;  ///< a copy: MoveRef points into it
    std::vector<MoveRef> moves_;
    int nb_[3] = {1, 1, 1};
    Vec3 bucketSize_{1.0};
    std::vector<std::vector<std::uint32_t>> buckets_;
};

}  // namespace dexelmill
