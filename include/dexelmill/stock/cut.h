/// @file cut.h
/// @brief The cutting loop: applies a tool path to a tri-dexel stock (the paper's section 4,
/// method.md sections 4-5), with localisation by tiles, TBB threads and collision reports.
///
/// Per move, the volume the cutting part of the tool sweeps (heights [0, cutting length]) is
/// removed from every dexel it meets (MoveSweep, sweep.h; for a feed move whose axis turns,
/// TurningSweep, turning.h, solved to its tolerance where the dexel has material, and where it
/// turns far, piece by piece: MovePieces). Localisation: the sweep's tight
/// axis-aligned box selects the 16 x 16 dexel tiles of each family it overlaps; inside a tile,
/// only the dexels whose line crosses the box and whose material reaches into it are intersected
/// with the sweep.
///
/// Threads: tiles are independent. Each tile applies its moves in program order, so the stock
/// does not depend on the thread count. Statistics are summed per tile and reduced over tiles in
/// a fixed order, so the result is identical bit for bit for any thread count.
///
/// Collisions (reported as data, never printed):
///  - a rapid move whose cutting part removes material (a crash through the stock);
///  - material met by the shank region (heights [cutting length, total length]) swept along the
///    move. It is measured after the move's cutting part has removed what it sweeps, so a shank
///    following its flutes into their own cut is not a collision; a move swept in pieces
///    (MovePieces) sweeps all its pieces' flutes before its shank's. By default that material is
///    removed as well (the tool went through it; CutOptions::removeShankMaterial = false keeps
///    it, to show what the flutes alone would have cut).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <vector>

#include "dexelmill/path/toolpath.h"
#include "dexelmill/stock/tridexel.h"
#include "dexelmill/sweep/sweep.h"
#include "dexelmill/sweep/turning.h"

namespace dexelmill {

/// @brief Options of the cutting loop.
struct CutOptions {
    /// Remove the material the shank region meets as well as report it (it is reported either way).
    bool removeShankMaterial = true;
    /// A move meeting at most this volume (mm^3) is not reported as a collision: float endpoint
    /// storage makes grazing contacts of about 1e-7 mm per dexel.
    double collisionVolume = 1e-6;
    /// The tolerance epsilon (mm) of the sweep of a feed move whose tool axis turns (TurningSweep).
    /// A move that turns so little that no tool point moves farther than this is swept with its end
    /// axis as a fixed-axis move.
    double turnTolerance = kDefaultTurnTolerance;
    /// Worker threads: 0 uses TBB's default, 1 runs on the calling thread only.
    int threads = 0;
    /// Moves per batch (progress is reported after each batch). 0: about 1% of the program, at
    /// least 64. A batch also ends before its turning sweeps could keep more linear nodes than
    /// their budget (TurningSweep::linearNodeBound). Neither changes the result.
    std::size_t batchMoves = 0;
    /// Called after each batch with (moves done, total moves), on the calling thread, with the
    /// same sequence of values whatever the thread count.
    std::function<void(std::size_t done, std::size_t total)> progress;
    /// The design part, cast on the stock's lattice (same families or more), or null. With it,
    /// every removal is intersected with the design's material on the same dexel: its length goes
    /// into MoveStats::designRemoved, and the stretches that may lie deeper inside the design than
    /// `designDepth` (mm) go into CutResult::designStretches.
    const TriDexelStock* design = nullptr;
    double designDepth = 0.01;
    /// The design's whole extent (mm). Where it reaches past the lattice's box, the cast cut its
    /// material off at the box's faces; a design segment ending there is taken to run on, so that
    /// no stretch is dropped for lack of design beyond the stock. Empty: the design lies within.
    Box designBounds;
};

/// @brief What one move did.
struct MoveStats {
    /// dexels inside the move's box with material there, whose cheap bound (MoveSweep::bound) was
    /// taken: the work of the localisation itself
    std::uint64_t bounded = 0;
    std::uint64_t visited = 0;   ///< dexels whose line was intersected with the move's sweep (exactly)
    std::uint64_t changed = 0;   ///< dexels that lost material
    double removed = 0.0;        ///< material removed (mm^3), mean over the stock's families
    double shankVolume = 0.0;    ///< material met by the shank region (mm^3), mean over families
    double holderVolume = 0.0;   ///< of shankVolume, what the holder met (ToolRegions::holder)
    /// Design material removed (mm^3) as each family measures it (CutOptions::design); 0 for
    /// families the stock does not keep. A layer thinner than the spacing is measured exactly only
    /// by the family across it, so the families are not averaged.
    std::array<double, 3> designRemoved{0.0, 0.0, 0.0};
};

/// @brief A stretch of one dexel where a move removed material the design keeps, and which may lie
/// deeper inside the design than CutOptions::designDepth: along the dexel the design's material
/// reaches farther than that beyond some point of the stretch on both sides. (The distance to the
/// design's surface is at most the distance along any line, so the other stretches cannot.)
struct DesignStretch {
    std::uint32_t move = 0;
    Axis family = Axis::Z;
    int ib = 0, ic = 0;  ///< the dexel's lattice indexes across the family's axis (DexelFamily::axisB, axisC)
    float lo = 0.0f, hi = 0.0f;  ///< along the dexel, relative to the lattice origin
    /// How far the design's segment reaches along the dexel on both sides of the stretch's point
    /// farthest inside it (mm). The segment's ends lie on the design's surface, so no point of the
    /// stretch is farther from that surface than this, to the float rounding of the ends. Infinity
    /// where the segment runs on past the lattice's box (its end there is no surface point).
    double reach = std::numeric_limits<double>::infinity();
};

/// @brief The kinds of collision the cutting loop reports.
enum class CollisionKind {
    Rapid,  ///< a rapid (G0) move removed material
    Shank,  ///< the shank region met material, the holder's share left out (a tool with a holder)
    Holder  ///< the holder met material (ToolRegions::holder)
};

/// @brief A collision: which move, where it came from, what and how much (mm^3).
struct CutCollision {
    std::size_t move = 0;
    SourceRef source;
    CollisionKind kind = CollisionKind::Rapid;
    double volume = 0.0;
};

/// @brief The result of a cut: per-move statistics, collisions in move order, totals.
struct CutResult {
    std::vector<MoveStats> moves;
    std::vector<CutCollision> collisions;
    std::uint64_t bounded = 0;
    std::uint64_t visited = 0;
    std::uint64_t changed = 0;
    double removedVolume = 0.0;
    double shankVolume = 0.0;
    double holderVolume = 0.0;
    /// With CutOptions::design: the stretches that may gouge, by move, then family, then dexel.
    std::vector<DesignStretch> designStretches;
};

/// @brief A tool split at its cutting length: the part that cuts (heights [bottom, cutting length])
/// and the shank above it, if there is one. Where the tool has a holder (withHolder), the shank
/// region holds it, and `holder` is the holder alone (from the stick-out's top up), swept only to
/// tell what the holder met from what the shank did.
struct ToolRegions {
    std::optional<Tool> cutting;
    std::optional<Tool> shank;
    std::optional<Tool> holder;
};

/// @brief The regions of every tool `path` uses, by tool number.
/// @throw Error if a move uses a tool that is not in `tools` (naming the move and its source) or
/// a region has more convex parts than the sweep handles.
std::map<int, ToolRegions> toolRegions(const ToolPath& path, const ToolTable& tools);

/// @brief One tool region's sweep on one move: fixed-axis, or turning (a feed move whose axis
/// turns by more than the tolerance allows, CutOptions::turnTolerance). Empty when the tool has no
/// such region.
struct RegionSweep {
    std::optional<MoveSweep> fixed;
    std::optional<TurningSweep> turning;

    explicit operator bool() const { return fixed || turning; }
    /// @brief The box of the swept volume. Not empty.
    const Box& bounds() const { return fixed ? fixed->bounds() : turning->bounds(); }
    /// @brief A cheap interval of `line` holding every swept interval (MoveSweep::bound,
    /// TurningSweep::bound). Not empty.
    Interval bound(const Line& line) const { return fixed ? fixed->bound(line) : turning->bound(line); }
};

/// @brief Whether the cutting loop sweeps `move` turning: where either region of its tool turns
/// past the tolerance (sweepsTurning).
bool sweptTurning(const ToolRegions& regions, const Move& move, double turnTolerance);

/// @brief Which regions of its tool a move's sweeps take: both, or for a move swept in pieces
/// (MovePieces) one of them, its cutting part's pieces coming before its shank's (a shank's sweep
/// takes its holder's with it).
enum class Regions { Both, Cutting, Shank };

/// @brief One move's sweeps: its cutting part's, its shank's if the tool has one (with its
/// holder's, where it has one, ToolRegions::holder), and the box that holds them (of `which`
/// regions). All are turning when the cutting or shank region's turn exceeds the tolerance; a
/// rapid that turns is swept with its end axis (its path is the machine's, not the program's).
struct MoveGeometry {
    RegionSweep cutting;
    RegionSweep shank;
    RegionSweep holder;  ///< within the shank's sweep: measured apart, never subtracted on its own
    Box box;

    MoveGeometry() = default;
    MoveGeometry(const ToolRegions& regions, const Move& move, double turnTolerance = kDefaultTurnTolerance,
                 Regions which = Regions::Both);
    /// @brief The most linear nodes the move's turning sweeps can keep (TurningSweep::linearNodeBound).
    std::size_t linearNodeBound() const;
};

/// @brief The most a piece of a turning move turns (radians, MotionLaw::rateSum): 10 degrees.
/// A move swept turning whose turns sum past it is swept in the fewest equal stretches of u that
/// keep within it (MovePieces), each a sweep with its own box, whose union is the move's sweep.
/// A move swept whole is searched along every line its one box crosses, down to where the tool
/// is near it: a 4-axis helix turning A ten times in one block (ball D3, 50 mm along a bar) took
/// 75 s to cut on one thread, the same helix as 360 blocks of 10 degrees 0.72 s (0.70 at 5, 0.76
/// at 3, 1.42 at 30, 4.4 at 90 degrees a block).
constexpr double kMaxPieceTurn = 10.0 * 3.14159265358979323846 / 180.0;

/// @brief The fraction of a piece by which a move's turn may pass a multiple of kMaxPieceTurn and
/// still take that many pieces: the quotient of a 150-degree turn rounds to 15 + 4e-15 pieces.
constexpr double kPieceRounding = 1e-9;

/// @brief The sweeps the cutting loop makes of a path's moves, in the moves' order: each move
/// whole, or a turning move cut into equal stretches (kMaxPieceTurn, subMove), all its pieces'
/// cutting parts first and then, where its tool has a shank, all its pieces' shanks (regions).
/// Sweep i belongs to move(i); a move's statistics and reports sum its sweeps'. Holds an entry
/// for each move it cuts, none for the others.
class MovePieces {
  public:
    MovePieces(const ToolPath& path, const std::map<int, ToolRegions>& regions, double turnTolerance);
    std::size_t size() const { return size_; }
    /// @brief The move sweep `i` belongs to.
    std::size_t move(std::size_t i) const;
    /// @brief Sweep `i`'s move: its stretch of its move, or the move itself.
    Move piece(std::size_t i) const;
    /// @brief The regions of its tool sweep `i` takes.
    Regions regions(std::size_t i) const;

  private:
    /// A move cut into `count` pieces, swept `sweeps` times (count, or twice that with a shank),
    /// the first of them sweep `first`.
    struct Cut {
        std::size_t move = 0, first = 0, count = 0, sweeps = 0;
    };
    /// The cut move at or before sweep i, if any.
    const Cut* before(std::size_t i) const;

    const ToolPath& path_;
    std::vector<Cut> cuts_;
    std::size_t size_ = 0;
};

/// @brief The sweeps the cutting loop has built ahead, in order. A batch ends where the node
/// budget says, often after one turning sweep, and drops its sweeps from the front: a deque
/// drops them without moving the rest (a vector moved every sweep built ahead each time: 400
/// blocks each winding A ten times on xyza, 144,000 pieces, took 15.2 s to cut, now 4.0 s).
using BuiltSweeps = std::deque<MoveGeometry>;

/// @brief How many of the first `count` sweeps of `geoms` one batch may hold: as many as keep
/// their turning sweeps' linear nodes within the budget (TurningSweep::linearNodeBudget,
/// MoveGeometry::linearNodeBound), and at least one. Past the budget a query makes each node it
/// needs and drops it.
std::size_t movesWithinNodeBudget(const BuiltSweeps& geoms, std::size_t count);

/// @brief Whether the cutting loop sweeps `move` of `tool` as a turning move with tolerance
/// `turnTolerance`: a feed move whose axis turns far enough to move some tool point (all within
/// hypot(total length, max radius) of the tip) by more than the tolerance. A machine's rotary move
/// (rapid or feed: the machine's law says where it goes) is swept turning when its turns can move
/// a tool point by more than that (MotionLaw::turnBound).
bool sweepsTurning(const Move& move, const Tool& tool, double turnTolerance);

/// @brief Applies every move of `path`, in order, to `stock`.
/// @param tools the tools by number; every move's tool must be in it.
/// @throw Error if a move uses a tool that is not in the table (naming the move and its source)
/// or a tool has more convex parts than the sweep handles.
CutResult cutStock(TriDexelStock& stock, const ToolPath& path, const ToolTable& tools,
                   const CutOptions& options = {});

}  // namespace dexelmill
