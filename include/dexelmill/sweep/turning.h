/// @file turning.h
/// @brief Moves whose tool axis turns (simultaneous 5-axis): the angle they turn through, a box
/// every pose of the tool stays in, and their swept volume along lines, exact within a stated
/// tolerance epsilon.
///
/// Motion law (path/motion.h). APT MULTAX: the tip runs on the straight line from `start` to
/// `end` and the unit axis turns on the great circle from `startAxis` to `axis` (the shorter arc,
/// at a uniform rate):
///   p(u) = start + u f,   a(u) = a0 cos(theta u) + b sin(theta u),   u in [0, 1],
/// with f = end - start, theta the angle between the axes and b the unit tangent at a0 towards
/// the end axis. A machine's rotary move follows its RotaryMotion instead. T(u) is the tool solid
/// at that pose, and the swept volume S is the union of T(u).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/path/motion.h"
#include "dexelmill/path/toolpath.h"
#include "dexelmill/sweep/sweep.h"
#include "dexelmill/tool/line_query.h"
#include "dexelmill/tool/offset.h"
#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// @brief The default tolerance epsilon (mm) of a turning move's sweep.
constexpr double kDefaultTurnTolerance = 1e-4;

/// @brief The finest tolerance (mm) a turning move's sweep is asked for. The stock keeps its
/// dexel ends as floats (stock/dexel.h), 8e-6 mm apart at 100 mm from the lattice origin, so a
/// finer answer could not be kept. Where the search takes linear nodes (turning.cpp, notes h and
/// j) a finer tolerance costs a few more levels of it (a one-move job: 0.8 s at 1e-4 mm, 1.3 s at
/// 1e-6); the search of static poses grows about as epsilon^-1/2 (43 s at 1e-6).
constexpr double kMinTurnTolerance = 1e-6;

/// @brief The coarsest tolerance (mm) a job may ask of a turning move's sweep. A move whose turn
/// moves no tool point by more than the tolerance is swept with its end axis (sweepsTurning): at
/// 1e300 mm a table's 360-degree turn became a straight cut. 0.1 mm is coarser than any finishing
/// tolerance of CAM.
constexpr double kMaxTurnTolerance = 0.1;

/// @brief How many linear nodes (turning.cpp, note h) the turning sweeps alive at once keep, by
/// default: 2 to 4 kB each (a bull nose's the most, its tori swept as cones: turning_nodes.cpp), so
/// 128 to 256 MiB. The cutting loop builds the sweeps of a batch of moves together, and ends a
/// batch before its sweeps' trees of nodes could pass the budget (TurningSweep::linearNodeBound);
/// past the budget a query makes the nodes it needs and drops them, slower but no larger.
constexpr std::size_t kDefaultLinearNodeBudget = std::size_t(1) << 16;

/// @brief The angle (radians, in [0, pi]) the axis of a move turns through; 0 for a fixed axis.
double turnAngle(const Move& move);

/// @brief How far a tool, or a region of one, reaches from its tip along a unit direction e at
/// c = a.e from its axis a: the largest s c + r sqrt(1 - c^2) over its points tip + s a + r n
/// (n a unit vector normal to a, r >= 0), the support of its meridian profile in the direction
/// (sqrt(1 - c^2), c). It is kept as terms s c + r sqrt(1 - c^2) + d over ranges of c, each
/// concave in c and so largest over an interval of c at its peak s / hypot(s, r) clamped to it:
/// the pieces' ends (d = 0, every c), where a cone piece's support lies, and for an arc (the
/// outer half of a circle, profile.h) its centre with d its radius over the c of its outward
/// normals, where the arc's support is that, or else at an end.
class ToolReach {
  public:
    /// A cylinder of `radius` over heights [bottom, length] above the tip.
    ToolReach(double bottom, double length, double radius);
    /// The tool's (or tool region's) own profile: a ball end's lowest point is its tip, where its
    /// cylinder's rim reaches below the tip by the radius times the tilt's sine.
    explicit ToolReach(const Tool& tool);
    /// The largest reach for c in [lo, hi], each clamped to [-1, 1].
    double along(double lo, double hi) const;
    /// The largest distance of a tool point from the tip.
    double extent() const { return extent_; }

  private:
    struct Term {
        double s, r, d, cLo, cHi;
    };
    std::vector<Term> terms_;
    double extent_ = 0.0;
};

/// @brief A box that holds the tool at every pose of a turning move; for a fixed-axis move, at its
/// one axis. A tool region above the tip, such as a shank (Tool::bottom), gives its own bottom:
/// the box of a shank 25 mm above the tip of a flat D10 x 40 was three times as large, in the
/// faces the dexels cross, with the heights from the tip.
///
/// The box is the tip's segment box plus the box of the turning tool with its tip held at the
/// origin. The second is exact: each of its faces touches some pose. The sum is exact for a turn
/// in place and larger than needed when the tip's extreme and the axis's lie at different points
/// of the move (at most by the tip's travel along each coordinate). Along the arc
/// a(t) = a0 cos t + b sin t (b the unit tangent at a0, t in [0, theta]) each coordinate a_i is
/// rho cos(t - phi), whose extremes are at the ends and where t - phi is 0 or pi; the tool
/// reaches ToolReach::along those.
/// A machine's rotary move (Move::rotary) gets the box of sampled poses padded by what the law's
/// acceleration bound K lets a tool point stray from them (turning_box.cpp): it holds every pose
/// and reaches at most 1e-3 mm beyond them, or K / (8 4096^2) where K passes 134,000 mm per unit
/// u squared (a table spinning turns on end far from its centre) and the samples their limit.
/// @throw Error if the axes are opposite (no one great circle joins them).
Box turningMoveBox(const Move& move, const ToolReach& reach);
/// @brief The same for the cylinder within `radius` of the axis over heights [bottom, length].
Box turningMoveBox(const Move& move, double bottom, double length, double radius);

/// @brief The swept volume of a tool (or tool region) on one move whose axis turns, along lines.
///
/// What a line query returns, for a unit-direction line and the set O of its output intervals:
///  1. O lies within epsilon of S: O is a union of exact static-pose intervals (inside S, up to
///     their rounding), of intervals of poses grown by at most epsilon, of sweeps of stretches of
///     the move taken with the axis held (each within epsilon of S), and of gaps between them
///     whose every point is within epsilon of a pose.
///  2. Every point of the line deeper than epsilon inside some T(u) (farther than epsilon from the
///     complement of T(u)) lies in O. So O's ends lie in the band of width 2 epsilon about the
///     boundary of S: a point O misses is within epsilon of S's outside, a point O holds within
///     epsilon of S.
/// The proof and the search are in turning.cpp (method notes at TurningSweep::intersect).
///
/// Built once per move; thread-safe for concurrent queries.
class TurningSweep {
  public:
    /// @brief Sweeps `tool` along `move`, whose axis turns from `*move.startAxis` to `move.axis`
    /// (a move with no start axis is swept with its one axis).
    /// @throw Error if the axes are opposite, epsilon is below kMinTurnTolerance or not finite, or
    /// the tool travels too far for the search to resolve to epsilon (kMaxLevel).
    TurningSweep(const Tool& tool, const Move& move, double epsilon = kDefaultTurnTolerance);

    /// @brief The tool pose at move parameter u in [0, 1].
    ToolPose pose(double u) const;
    /// @brief A bound on how fast the tool moves, in mm per unit of u: the tip's speed plus the
    /// axis's turning rate (MotionLaw::axisTurnBound) times the largest distance of a tool point
    /// from the tip, |f| + theta * that distance on a great circle (note a).
    double speed() const { return speed_; }
    double epsilon() const { return epsilon_; }
    /// @brief A box that holds every pose of the tool.
    const Box& bounds() const { return bounds_; }
    /// @brief Whether the search takes each stretch of the move as a fixed-axis linear move
    /// (turning.cpp, note h) rather than as static poses.
    bool linearNodes() const { return !models_.empty(); }
    /// @brief How many bands of heights the linear-node search runs on (turning.cpp, note i): one
    /// per part unless its parts are cut; 0 without linear nodes.
    std::size_t linearBands() const { return models_.size(); }
    /// @brief How many linear nodes the sweeps alive keep, and the most they may keep (default
    /// kDefaultLinearNodeBudget); a budget of 0 keeps none.
    static std::size_t keptLinearNodes();
    static std::size_t linearNodeBudget();
    static void setLinearNodeBudget(std::size_t nodes);
    /// @brief Whether the Hermite data of an output end that the first or last pose made come
    /// from the search's own look at the faces there, where it found no rim near (the default),
    /// or are found afresh as at any other pose: the same data, which a test checks.
    static void setEndNormalsFromSearch(bool fromSearch);
    /// @brief The most linear nodes this sweep can keep: every node of its bands' trees down to
    /// the deepest level kept (0 without linear nodes). The cutting loop keeps the sweeps it
    /// builds together within the budget by this bound.
    std::size_t linearNodeBound() const;
    /// @brief Whether the tool's ball end is swept as capsules along chords of its centre's path
    /// instead of searched (1) or not (0) (turning.cpp, note g), and into how many chords.
    std::size_t capsuleBalls() const { return balls_.size(); }
    int chords() const { return chords_; }
    /// @brief A cheap interval of `line` that holds every output interval: the line inside
    /// bounds() grown by epsilon (an output interval may be a pose's grown by up to epsilon), or
    /// with linear nodes, inside the boxes, in their own frames, of the tool's parts grown by
    /// their root node's reach plus epsilon and swept along its move (turning.cpp, note h).
    /// Empty when the line misses them.
    Interval bound(const Line& line) const;

    /// @brief The swept material along `line` (unit direction), sorted, disjoint, with the Hermite
    /// data at each end, from the tool at the pose that made it (turning_normals.cpp): the normal
    /// of the face the end lies on, or where a rim of that face grazes, the rim's swept normal;
    /// marked sharp near a rim that does not graze, a crease of the swept volume.
    /// @param care where along the line the answer matters (sorted, disjoint line parameters, for
    /// example a dexel's material); empty means everywhere. Outside it, guarantee 2 is waived:
    /// only the stretches of O that meet `care` are complete, and only the ends within `care` have
    /// their Hermite data (the others' are zero and not sharp: no material takes them). A care
    /// clipped to bound(line) saves the search the stretches where the sweep cannot be (note n).
    std::vector<LineHit> intersect(const Line& line, const std::vector<Interval>& care = {}) const;
    /// @brief As intersect, into `out` (cleared first): a caller that queries many lines keeps one
    /// vector and allocates nothing once it has grown.
    void intersect(const Line& line, const std::vector<Interval>& care, std::vector<LineHit>& out) const;
    /// @brief As intersect, without the Hermite data.
    std::vector<Interval> intersectAll(const Line& line) const;

  private:
    /// The Hermite data of an output end at line parameter t, the upper end of an interval or the
    /// lower, made by part `part` at pose u (turning_normals.cpp). Near a rim, at the pose that
    /// sweeps S there (contactPose) unless `atPose`.
    void endNormal(const Line& line, double t, double u, std::size_t part, bool upper, Vec3& normal, bool& sharp,
                   bool atPose = false) const;
    /// The pose near u at which part `part` reaches farthest out along the line at its upper end
    /// (lower), and the part's interval on the line there in `range`: u where none reaches farther.
    double contactPose(const Line& line, double u, std::size_t part, bool upper, Interval& range) const;

    /// A ball inside the tool whose sphere is the tool's lower face below its centre (a ball end
    /// mill's, at the bottom): swept as capsules along chords of its centre's path (turning.cpp,
    /// note g).
    struct Ball {
        double zc = 0.0, rho = 0.0;  ///< the centre's height above the tip, and the radius
        std::vector<Vec3> centres;   ///< the centre at u = j / chords, j = 0 .. chords
        /// Per run of consecutive chords (turning.cpp, kChordGroup), a ball that holds their
        /// capsules: a line that misses it meets none of them.
        struct Group {
            Vec3 centre{0.0};
            double radius = 0.0;
        };
        std::vector<Group> groups;
        /// Half the longest chord plus the radius: each capsule lies within it of its chord's
        /// middle.
        double capsuleReach = 0.0;
    };

    /// The search that takes each node as a fixed-axis linear move (turning.cpp, note h), for
    /// one band of heights of one part of parts_ (note i): the point of the axis the node's move
    /// carries exactly (the pivot, a height above the tip), and per level k the reach delta_k of a
    /// node of width 2^-k; the level whose reach is first at most epsilon is the last (a leaf).
    /// A node above it sweeps the band grown by delta_k - epsilon with square corners and its tori
    /// as chains of cones (mitredOffsetChain, made with the node: most moves make a few nodes of
    /// a few levels); a leaf, the band itself.
    struct LinearPart {
        std::size_t part = 0;  ///< the index in parts_ of the part the band is cut from
        double pivot = 0.0;
        double lo = 0.0, hi = 0.0;  ///< the band's heights above the tip, its pieces'
        std::vector<double> reach;
        std::vector<ProfilePiece> band;  ///< the band's pieces (clipChain)
        int leafLevel() const { return int(reach.size()) - 1; }
    };
    /// A node's linear move, made the first time a query needs it: the band of its level swept
    /// along it (its axis the middle's), the pose at the node's middle, where the node lies in u,
    /// and the middle's phase.
    struct LinearNode {
        MoveSweep sweep;
        ToolPose middle;
        double middleU = 0.0, width = 0.0;
        TurnPhase phase;  ///< the middle's
    };
    class NodeCache;
    /// One line's search over the linear nodes, with the tests of notes j to q
    /// (turning_linear_search.cpp).
    class LinearSearch;
    /// Sets models_ and nodes_ when the linear-node search applies and its leaves lie enough
    /// levels above the static search's closing level (turning.cpp, note h).
    void chooseLinearNodes();
    /// The linear-node search of part p's band of heights [lo, hi] (note i); none when its leaves
    /// would lie below level `deepest`.
    std::optional<LinearPart> linearBand(std::size_t p, double lo, double hi, int deepest) const;
    /// Node `heap` of band `band`'s search, kept or, past the nodes the sweeps may keep, made in
    /// `scratch`.
    const LinearNode& linearNode(std::size_t band, std::uint32_t heap, std::unique_ptr<LinearNode>& scratch) const;
    /// Node `heap` of the search of `band`, made.
    LinearNode makeNode(const LinearPart& band, std::uint32_t heap) const;
    /// A face of a convex part in its meridian half-plane, as the searches for the faces near a
    /// point take it (turning_normals.cpp): a disk at height z0 (= z1), or a lateral cone or arc
    /// on [z0, z1]. A disk's and a cone's outward normal, (nr across the axis, nz along it), is
    /// the same all over the face and kept; an arc's is found at its point.
    struct MeridianFace {
        enum class Kind { Disk, Cone, Arc } kind = Kind::Disk;
        double z0 = 0.0, z1 = 0.0;
        double r0 = 0.0, r1 = 0.0;           ///< a disk's radius (r0), a cone's at z0 and z1
        double nr = 0.0, nz = 0.0;           ///< a disk's or a cone's normal
        double rc = 0.0, zc = 0.0, rho = 0.0;  ///< an arc's circle (ArcPiece)
        /// A disk inside the tool: where the part meets a neighbouring part (or a ball end's ball)
        /// that covers the disk whole. It bounds its part, as the searches take the part, but is
        /// no face of the tool, and endNormal takes neither it nor its rims.
        bool covered = false;
        /// A covered disk whose rim is an edge of the tool: where the next part's face meets this
        /// part's at a concave angle (a necked ball's neck) or a step, not a ball end's equator.
        bool edge = false;
        /// R(z), z clamped to the face's heights, as pieceRadius; a disk's radius.
        double radius(double z) const;
        /// The outward normal (nr across the axis, nz along it) at the face's point of radius R at
        /// height z, as meridianNormal.
        void normal(double R, double z, double& nr, double& nz) const;
    };
    /// The faces of convex part `part` in order up the meridian: the bottom disk, the lateral
    /// pieces, the top disk (faceNormal's indices).
    static std::vector<MeridianFace> meridianFaces(const std::vector<ProfilePiece>& pieces, const ConvexPart& part);
    /// Marks the disks of `faces` (per part of `parts`, in order up the axis) that the next part
    /// or the one before covers, and with a ball end (`ball`) the lowest part's bottom disk, cut
    /// at the ball's equator.
    static void markCoveredDisks(std::vector<std::vector<MeridianFace>>& faces, const std::vector<ConvexPart>& parts,
                                 bool ball);
    /// The outward normal of the face of part `part` at pose `pose` nearest the point x
    /// (turning_normals.cpp); `face`, when given, gets that face's index up the meridian (0 the
    /// bottom face, then the lateral pieces, then the top face), and `alone` whether every other
    /// face lies farther from x than endNormal looks for a rim: then an output end at x that the
    /// first or last pose made takes this normal as its Hermite data, and is not sharp.
    Vec3 faceNormal(const ToolPose& pose, std::size_t part, const Vec3& x, int* face = nullptr,
                    bool* alone = nullptr) const;
    /// Where faces k and k + 1 of a part meet at an angle: the rim's height and radius, and each
    /// face's outward normal there in the meridian plane, (across the axis, along it).
    struct Rim {
        double z = 0.0, radius = 0.0;
        double across[2] = {0.0, 0.0}, along[2] = {0.0, 0.0};
    };
    /// The rim between faces k and k + 1 of part `part` (faceNormal's order); none where they
    /// meet smoothly, or on the axis (turning_normals.cpp).
    std::optional<Rim> rim(std::size_t part, int k) const;
    /// Whether faces k and k + 1 of `faces` meet smoothly: their normals at their common rim
    /// differ by less than kRimAngle (turning_normals.cpp).
    static bool smoothJoint(const std::vector<MeridianFace>& faces, std::size_t k);
    /// The Hermite data of an output end at line parameter t that band `band`'s leaf `heap` made
    /// (turning_normals.cpp).
    void nodeEndNormal(const Line& line, double t, std::size_t band, std::uint32_t heap, bool upper, Vec3& normal,
                       bool& sharp) const;

    Tool tool_;
    MotionLaw law_;
    double speed_ = 0.0;
    double axisTurn_ = 0.0;  ///< MotionLaw::axisTurnBound
    double tipSpeed_ = 0.0;  ///< MotionLaw::speedBound(0): the tip's
    double axisBend_ = 0.0;  ///< MotionLaw::axisBendBound: |a''|
    /// MotionLaw::axisPointAccelerationBound(0), the tip's: a point h up the axis adds axisBend_ h.
    double pivotBend_ = 0.0;
    double axisJerk_ = 0.0;  ///< MotionLaw::axisJerkBound: |a'''|
    double epsilon_ = kDefaultTurnTolerance;
    Box bounds_;
    /// The convex solids the search solves: the tool's convex parts, the lowest cut at its
    /// ball's centre when it is a ball end (the ball itself is in balls_).
    std::vector<ConvexPart> parts_;
    std::vector<Ball> balls_;  ///< none, or the lowest part's ball
    /// Chords per ball: enough that the centre's path lies within epsilon / 2 of them.
    int chords_ = 0;
    /// grown_[k][p]: part p of parts_ grown by g_k = speed / 2^(k + 1) - epsilon, the reach of a
    /// node of width 2^-k less the depth guarantee 2 leaves out (turning.cpp), for the levels k
    /// whose reach exceeds epsilon: its pieces (closing nodes take them), with tangent cones for
    /// its tori within kSettleSlack g_k (outerOffsetPart; the settling test takes those).
    std::vector<std::vector<OuterPart>> grown_;
    /// The phases and poses at u = 0 and 1, where every line's search starts.
    TurnPhase startPhase_, endPhase_;
    ToolPose startPose_, endPose_;
    /// The velocity fields there: most crossings a search takes are the end poses' (note n).
    Twist startTwist_, endTwist_;
    /// The phase and pose at u = 1/2: the root's middle, where a search splits the root without
    /// its linear node (note n).
    TurnPhase midPhase_;
    ToolPose midPose_;
    /// Per level k of grown_, the turns' change over half a node's width, 2^-(k + 1): the
    /// search steps to a node's middle pose from its start's phase (MotionLaw::advance).
    std::vector<TurnStep> halfSteps_;
    /// The first level whose growth g_k is at most epsilon: from there on, a node that does not
    /// settle is closed (turning.cpp, note c).
    int closingLevel_ = 0;
    /// The linear-node search's bands, part by part (empty: the search solves static poses), and
    /// their nodes, shared by the copies of this sweep.
    std::vector<LinearPart> models_;
    std::shared_ptr<NodeCache> nodes_;
    /// Per part cut into more than one band, the root node of its search taken whole (note i).
    /// A line it leaves held needs none of the part's bands.
    std::vector<std::optional<LinearNode>> wholeRoots_;
    /// With linear nodes, per convex part of the tool (a ball end whole), the part grown by its
    /// root node's reach plus epsilon, swept along the root's move: bound() takes their boxes.
    std::vector<MoveSweep> outer_;
    /// Per part of parts_, its faces (meridianFaces).
    std::vector<std::vector<MeridianFace>> faces_;
    /// Each part of parts_, then each ball, grown by epsilon: the reach that closes a gap between
    /// two intervals. An output piece's part index counts the same way.
    std::vector<std::vector<ProfilePiece>> grownEpsilon_;
};

}  // namespace dexelmill
