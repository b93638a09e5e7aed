/// @file cut.h
/// @brief The cutting loop: a tool path applied to the tri-dexel stock (the paper's section 4).
///
/// Localisation: each move's swept volume has a tight axis-aligned box (MoveSweep::bounds). For
/// every dexel family the moves are bucketed by the 16 x 16 tiles their box overlaps, so a tile
/// only ever looks at the moves that can reach it, and inside a tile only the dexels under the
/// box, whose material lies within the box's range along the ray, are queried.
///
/// Threads: tiles are independent. Each tile applies its moves in program order; per-move
/// statistics are kept per tile and summed in a fixed tile order afterwards, so the result is
/// the same bit for bit whatever the number of threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "dexelmill/path/toolpath.h"
#include "dexelmill/stock/tridexel.h"

namespace dexelmill {

/// @brief What kind of collision a move caused.
enum class CollisionKind {
    Rapid,  ///< a rapid (G0) move removed material
    Shank   ///< material above the cutting length met the tool (shank or holder)
};

/// @brief A collision, with the volume of material involved (mm^3).
struct CutCollision {
    std::size_t move = 0;  ///< index into ToolPath::moves
    SourceRef source;
    CollisionKind kind = CollisionKind::Rapid;
    double volume = 0.0;
};

/// @brief Per-move statistics.
struct MoveStats {
    std::uint64_t visited = 0;  ///< dexels whose interval was computed
    std::uint64_t changed = 0;  ///< dexels that lost material
    double removed = 0.0;       ///< mm^3, as the families measure it (their mean)
    double shankVolume = 0.0;   ///< mm^3 of material the shank region met (also removed)
};

struct CutOptions {
    /// Worker threads; 0 uses every core.
    int threads = 0;
    /// Called with (moves done, total) as the work proceeds: from any thread, never two at once.
    std::function<void(std::size_t done, std::size_t total)> progress;
};

struct CutResult {
    std::vector<MoveStats> moves;  ///< one per move of the path
    std::vector<CutCollision> collisions;
    double removedVolume = 0.0;  ///< mm^3, the sum of the moves' removed volumes
    std::uint64_t visited = 0, changed = 0;
};

/// @brief Applies every move of `path` to the stock, in order.
/// @throw Error if a move names a tool that is not in `tools`.
CutResult cutStock(TriDexelStock& stock, const ToolPath& path, const ToolTable& tools,
                   const CutOptions& options = {});

}  // namespace dexelmill
