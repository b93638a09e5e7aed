/// @file sweep.h
/// @brief The volume a tool sweeps on one linear move, intersected with lines: the paper's
/// envelope method (method.md sections 3-5, Eqs. 13-37) made exact for every line direction.
///
/// A 3+2-axis linear move translates the tool by u f, u in [0, 1] (Eq. 1). Each convex part P of
/// the tool sweeps the convex set S = P + [0, 1] f, so a line meets S in one interval. Its ends
/// are found from the shadow cylinder Z = P + R f (P translated along the whole feed line):
///
///  - The boundary of Z is made of the grazing points of P (outward normal perpendicular to f,
///    Eqs. 15-21) translated along f: the grazing strips of cones and cylinders (Eqs. 28-31), the
///    grazing cylinder of a sphere, the grazing surface of a torus (Eq. 36), the sweep of the rims
///    where two pieces meet at an angle, and for horizontal moves the flat faces themselves.
///  - A line (direction w, not parallel to f) crosses the boundary of Z at most twice, at
///    parameters v_lo <= v_hi, each at a feed parameter u_lo, u_hi. Along the line, the largest v
///    inside P + u f is a concave function of u whose maximum over all u is v_hi at u_hi, so the
///    largest v inside S is v_hi when u_hi is in [0, 1], and otherwise the static tool's upper end
///    at u = 0 or 1, whichever is nearer (the same for the lower end, mirrored).
///
/// This is the paper's hull of (start tool, end tool, grazing surfaces) with two savings: the
/// grazing candidates need no u-range test to be kept, and the static tools are only intersected
/// when an end of the interval actually lies on them. The degenerate cases of method.md section 5
/// each have a branch: zero-length moves (the static tool), plunges and retracts (f parallel to
/// the axis: Z is the cylinder of the largest radius), horizontal moves (the profile projected
/// along f, with the flat faces), and lines parallel to the move (the static intervals at both
/// ends, hulled). Non-convex tools are swept part by part; the parts' intervals are united.
///
/// Hermite data (intersectParts with LineHit): an end on the shadow cylinder's boundary takes the
/// tool's normal at the grazing point there (perpendicular to f), an end on a static tool that
/// tool's normal. The solver records where each candidate end came from, and the normals are found
/// for the two chosen ends only; the Interval queries run the same solver without the record.
/// An end is sharp on a crease of the static tool, where two tied crossings' normals differ, and
/// where a crossing that only the start or end pose reaches lies on a crease of that static tool.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <vector>

#include "dexelmill/geometry/frame.h"
#include "dexelmill/geometry/types.h"
#include "dexelmill/path/toolpath.h"
#include "dexelmill/tool/tool.h"

namespace dexelmill {

/// Named tolerances of the sweep solver.
namespace sweep_tol {

/// A line whose direction makes a sine below this with the feed is parallel to the move (its
/// interval is the static intervals at both ends, hulled). The error of that model is at most
/// this sine times the move length.
constexpr double kParallelFeed = 1e-9;

/// A move whose feed has an axial component below this fraction of its length is horizontal: its
/// flat faces graze. The height error of that model is this fraction times the move length.
constexpr double kHorizontal = 1e-12;

/// Slack on the generator parameter of a strip and on heights of grazing points (relative): keeps
/// a crossing exactly at a joint between two pieces from being rejected by both.
constexpr double kParam = 1e-12;

/// Two boundary crossings closer than this along the line (mm) are the same crossing; their feed
/// parameter ranges are united.
constexpr double kTie = 1e-9;

/// Below this kappa = |n.f| / |f| the stretch of a torus's grazing curve near the d-n plane is
/// solved in the spine chart (see torusCrossings in src/sweep/torus.cpp): the normal-angle chart
/// resolves it only to about kAngleRoot / kappa there.
constexpr double kSpineChart = 1e-3;

/// Root brackets on the torus's grazing curve stop at this width of the half-angle tangent
/// parameter (dimensionless, in [-1, 1]); a position error of about (rc + rho) times this.
constexpr double kAngleRoot = 1e-13;

/// Slack on the cheap bounds of a line's interval (bound(), the parts' boxes), in mm: keeps a
/// grazing contact the exact solver finds from being cut off by the rounding of the bounds.
constexpr double kBoxSlack = 1e-9;

/// An end of an interval within this distance (mm) of a crease of the static tool (a rim where two
/// of its faces meet at an angle, or a cone's apex) lies on the crease: the end is sharp.
constexpr double kCrease = 1e-9;

/// Two boundary crossings tied at an end of an interval (within kTie) whose normals differ by more
/// than this angle (rad) meet at a crease of the swept volume: the end is sharp. About the
/// resolution of the normals the stock keeps (PackedNormal::kMaxAngleError): a finer crease could
/// not be told from a smooth surface there anyway.
constexpr double kCreaseAngle = 1e-4;

}  // namespace sweep_tol

/// @brief How a move is swept, decided once per move from its feed f and tool axis n.
enum class SweepKind {
    Static,      ///< |f| below tol::kZeroMove: the tool at the start pose
    Plunge,      ///< f parallel to n (plunge or retract)
    Horizontal,  ///< n . f = 0: flat faces graze
    General      ///< everything else, ascending or descending
};

/// @brief The swept volume of one tool (or tool region) on one linear move, for line queries.
///
/// Built once per move; every per-move quantity (tool frame, grazing generators, torus grazing
/// arcs, rims) is precomputed so a line query costs a few dot products per piece. Pure maths: no
/// storage, threads or files. Thread-safe for concurrent queries.
class MoveSweep {
public:
    /// The most convex parts a tool may have.
    static constexpr std::size_t kMaxParts = 8;

    /// @brief Sweeps `tool` (typically a whole tool, or `Tool::region` for the cutting part or the
    /// shank) with its tip moving from `start` to `end`, its axis along `axis`.
    /// @throw Error if the axis has zero length or the tool has more than kMaxParts convex parts.
    MoveSweep(const Tool& tool, const Vec3& start, const Vec3& end, const Vec3& axis);
    /// @brief Sweeps `tool` along `move` (its start, end and axis; the move's tool id is ignored).
    MoveSweep(const Tool& tool, const Move& move);
    /// @brief Sweeps one convex solid of revolution, given as its profile pieces bottom to top
    /// (heights above the tip, which may be negative: a tool part grown by offsetPart).
    /// @throw Error if the axis has zero length.
    MoveSweep(const std::vector<ProfilePiece>& pieces, const Vec3& start, const Vec3& end, const Vec3& axis);

    MoveSweep(const MoveSweep&);
    MoveSweep(MoveSweep&&) noexcept;
    MoveSweep& operator=(const MoveSweep&);
    MoveSweep& operator=(MoveSweep&&) noexcept;
    ~MoveSweep();

    SweepKind kind() const { return kind_; }
    /// @brief The tool frame (d, e, n) of the move (Eq. 2).
    const ToolFrame& frame() const { return frame_; }
    /// @brief The tight axis-aligned box of the swept volume (from the support function of each
    /// part, exact up to rounding).
    const Box& bounds() const { return bounds_; }
    /// @brief Number of convex parts (one interval each).
    std::size_t partCount() const;

    /// @brief The interval of `line` (unit direction) inside the swept volume, as line parameters.
    /// For a convex tool this is the exact answer; for a non-convex tool it is the hull of the
    /// parts' intervals (use intersectParts or intersectAll to keep the gaps).
    Interval intersect(const Line& line) const;
    /// @brief One interval per convex part, written to `out[0 .. partCount())`; empty ones included.
    /// @return partCount().
    std::size_t intersectParts(const Line& line, Interval* out) const;
    /// @brief As intersectParts, with the Hermite data of each interval: the swept volume's outward
    /// unit normal at both ends (LineHit). An end on a smooth piece of the envelope takes that
    /// piece's normal: the tool's surface normal at the contact point. An end on a crease of the
    /// swept part (a rim of the static tool, where two of its faces meet at an angle) is marked
    /// sharp, with a normal from the crease's normal cone.
    /// @return partCount().
    std::size_t intersectParts(const Line& line, LineHit* out) const;
    /// Which ends of a part's interval want their Hermite data: kEndLo, kEndHi or both.
    static constexpr unsigned kEndLo = 1, kEndHi = 2;
    using EndFilter = std::function<unsigned(std::size_t part, const Interval& range)>;
    /// @brief As intersectParts with LineHit, computing the Hermite data only of the ends `wanted`
    /// asks for, once it has seen the part's interval (world line parameters); the other ends keep
    /// a zero normal. A cutting loop asks only for the ends its subtraction will make.
    std::size_t intersectParts(const Line& line, LineHit* out, const EndFilter& wanted) const;
    /// One part's interval with the move's feed parameter u in [0, 1] of a pose that makes each
    /// end: 0 or 1 where the end lies on the static tool at the start or end, and on the envelope
    /// the middle of the parameters that put a tool point on the crossing there.
    struct EndPoses {
        Interval range;
        double uLo = 0.0, uHi = 0.0;
    };
    /// @brief Part `index`'s interval on `line` and where on the move its ends are made. A turning
    /// sweep's linear node (turning.h) takes an end's Hermite data from the true pose there.
    EndPoses endPoses(const Line& line, std::size_t index = 0) const;
    /// @brief The swept material along `line`: the parts' intervals united, sorted, non-empty.
    std::vector<Interval> intersectAll(const Line& line) const;
    /// @brief A cheap interval of `line` (unit direction) that holds every part's interval: the
    /// line inside each part's oriented box in the move frame, and for a line parallel to the tool
    /// axis the heights where the profile is at least as wide as the line's distance from the
    /// swept axis. Empty when the line surely misses; a few dot products, no root finding.
    Interval bound(const Line& line) const;
    /// @brief bound(line) cut to the heights the parts' sweeps reach, and empty where the line
    /// passes beside them in a corner of their boxes (farther than a part's largest radius from
    /// the tip's path). About twice bound's cost: for a caller whose miss costs far more than a
    /// fixed-axis sweep's (a turning sweep's search, turning.cpp).
    Interval narrowBound(const Line& line) const;
    /// @brief As narrowBound, for a caller that knows a range `within` that holds every part's
    /// interval it needs (bound(line), or the part of it where it has material): `within` cut and
    /// tested as narrowBound cuts and tests the boxes' range, without the boxes.
    Interval narrowBound(const Line& line, const Interval& within) const;

    /// @brief A line in the move's frame, re-anchored at its point nearest the start tip. A caller
    /// that bounds a line and then intersects it makes it once (toLocal) and passes it to both:
    /// the answers are those of the Line overloads, to the bit.
    struct LocalLine {
        Vec3 o{0.0}, w{0.0};
        double vShift = 0.0;  ///< world line parameter = local parameter + vShift
        Vec3 c{0.0};          ///< w x f: normal of the plane through the line spanned by w and f
        double c2 = 0.0;      ///< |c|^2
        double co = 0.0;      ///< c . o
        bool parallel = false;
    };
    LocalLine toLocal(const Line& line) const;
    Interval bound(const LocalLine& q) const;
    std::size_t intersectParts(const LocalLine& q, Interval* out) const;
    std::size_t intersectParts(const LocalLine& q, LineHit* out, const EndFilter& wanted) const;

    /// The precomputed sweep of one convex part (defined in src/sweep/parts.h).
    struct Part;
    /// One convex part as the normals of its static tool need it (defined in src/sweep/parts.h).
    struct StaticProfile;

private:
    /// The convex parts to sweep, each as a run of profile pieces, bottom to top; read, not kept.
    struct PartPieces {
        std::array<const ProfilePiece*, kMaxParts> first{};
        std::array<std::size_t, kMaxParts> count{};
        std::size_t parts = 0;
    };
    static PartPieces partPieces(const Tool& tool);
    static PartPieces partPieces(const std::vector<ProfilePiece>& pieces);
    MoveSweep(const PartPieces& parts, const Vec3& start, const Vec3& end, const Vec3& axis);

    struct EndTrace;
    /// The part's interval of the query line in local parameters. With kTrace, also where each end
    /// came from (`trace`), for endNormal; without it, `trace` is unused and nothing is recorded.
    template <bool kTrace>
    Interval intersectLocal(const Part& part, const LocalLine& q, EndTrace* trace) const;
    /// The Hermite data of part `index`'s interval `local` (local line parameters, non-empty), whose
    /// ends intersectLocal<true> traced: the world-frame outward unit normals and sharp marks of
    /// `hit` at the ends in `ends` (kEndLo, kEndHi; its range is the caller's).
    void hermite(std::size_t index, const LocalLine& q, Interval local, const EndTrace& trace, unsigned ends,
                 LineHit& hit) const;
    Interval boxLocal(const Part& part, const LocalLine& q) const;
    /// `range` (parameters of the line o + v w, in the move frame from the start tip) cut to the
    /// heights of the part's sweep, and empty where that stretch passes farther than the part's
    /// largest radius from the tip's path (narrowBound); invWz is 1 / w.z (0 where w.z is).
    Interval roundBound(const Part& part, Interval range, const Vec3& o, const Vec3& w, double invWz) const;
    /// bound(Line), narrowed by roundBound with kRound.
    template <bool kRound>
    Interval boxBound(const Line& line) const;

    SweepKind kind_ = SweepKind::Static;
    ToolFrame frame_;
    Vec3 start_{0.0};
    Vec3 feedLocal_{0.0};  ///< f in the frame (d, e, n): (f.d, 0, f.n)
    /// Axes of the parts' oriented boxes in the frame: e, and two spanning the d-n plane (across
    /// and along the feed for a moving tool).
    std::array<Vec3, 3> boxAxes_{};
    /// boxAxes_ in world coordinates, with which bound(Line) tests a line against the boxes
    /// without putting it in the frame.
    std::array<Vec3, 3> worldBoxAxes_{};
    double feedLength_ = 0.0;
    double creaseU_ = 0.0;  ///< kCrease / |f|: the feed parameters that close to 0 or 1 reach a static tool
    // Per-move constants of a General sweep's queries.
    double invF2_ = 0.0;  ///< 1 / |f|^2
    double invFn_ = 0.0;  ///< 1 / (n . f)
    double kappa_ = 0.0;  ///< |n . f| / |f|
    Vec3 qDir_{0.0};      ///< (-fn, 0, fd) / |f|: across the feed in the d-n plane
    Box bounds_;
    std::vector<Part> parts_;
    std::vector<StaticProfile> staticProfiles_;  ///< one per part, for the normals of static ends
};

}  // namespace dexelmill
