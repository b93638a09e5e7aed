/// @file windows.h
/// @brief Short stretches of coordinate axes cut exactly: where the exact part's surface crosses
/// them (the refinement's queries).
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/path/toolpath.h"
#include "dexelmill/tool/tool.h"
#include "geometry/detail/coarse_grid.h"

namespace dexelmill::detail {

/// @brief A stretch [-reach, reach] of the coordinate axis `axis` through `point`, and which way
/// the surface sought there faces: with `outward` true the part's outward normal points along
/// +axis (the crossing is where material ends going up the axis), otherwise along -axis.
struct Window {
    Vec3 point{0.0};
    int axis = 2;
    bool outward = true;
};

/// @brief A coarse grid of the cells that some move's swept tool (cutting part or shank, whether
/// or not it removes material) may come near: where a window outside them finds only the stock.
class SweptCells {
public:
    /// @brief Cells of about `cell` mm over `stock` (coarser if there would be too many), marked
    /// where a conservative box of a move's swept regions, grown by `margin`, overlaps them.
    SweptCells(const Box& stock, const ToolPath& path, const ToolTable& tools, double cell, double margin);
    /// @brief Whether some sweep may come within the margin of p (always true outside the grid).
    bool reached(const Vec3& p) const;

private:
    CoarseGrid grid_;
    std::vector<char> marked_;
};

/// @brief The offset along a window's axis to the nearest crossing of the stock box's surface
/// facing its way, within [-reach, reach], NaN if none: exactCrossings' answer for a window no
/// sweep reaches.
double stockCrossing(const Window& window, double reach, const Box& stock);

/// @brief For each window, the offset along its axis from its point to the nearest crossing of the
/// exact part's surface that faces its way, within [-reach, reach]; NaN where there is none. The
/// part is `stock` (its open interior, or the face a window lies on) minus the closed sweep of
/// every move's cutting part, and of its shank when `removeShank`: the solids the cutting loop
/// subtracts, cut in double precision. A move the cutting loop sweeps turning (MoveGeometry with
/// `turnTolerance`) is cut as it cuts it, within that tolerance (TurningSweep's guarantees: where
/// such a move makes the crossing, it lies within the tolerance of the exact part's surface).
/// The moves are taken in batches, and each batch's sweeps are shared by the windows they reach,
/// so memory does not grow with the program. Runs in the caller's task arena; the answers do not
/// depend on the thread count.
/// @throw Error if a move uses a tool that is not in `tools`.
/// `progress(done, total)`, if given, is called from the calling thread after each batch of moves.
std::vector<double> exactCrossings(const std::vector<Window>& windows, double reach, const Box& stock,
                                   const ToolPath& path, const ToolTable& tools, bool removeShank,
                                   double turnTolerance,
                                   const std::function<void(std::size_t done, std::size_t total)>& progress = {});

}  // namespace dexelmill::detail
