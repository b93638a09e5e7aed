// One line's search over a turning sweep's linear nodes (notes h and i of turning.cpp), with
// the tests that settle a node by its end poses' faces (notes j to o, turning_linear_search.cpp),
// the bands it cannot reach (note p) and the gaps between a node's poses (note q).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "dexelmill/sweep/turning.h"
#include "turning_union.h"

namespace dexelmill {

class TurningSweep::LinearSearch {
  public:
    /// Searches `line` band by band (models_), adding to `found` what `care` needs.
    LinearSearch(const TurningSweep& sweep, const Line& line, const turning::Care& care, turning::Union& found);
    void run();
    /// The Hermite data of an output end at line parameter t that part `part` made at the first or
    /// last pose (u), where that end's crossing found it (endFaces_): true, with normal and sharp
    /// as TurningSweep::endNormal gives them; false where not.
    bool knownEndNormal(double t, double u, std::size_t part, Vec3& normal, bool& sharp) const {
        // The first two poses solved are the part's end poses (addEnds), where it is endsAdded_:
        // not a ball's (whose index follows the parts', as endsAdded_'s does before addEnds).
        if (part >= s_.parts_.size() || endsAdded_ != part) return false;
        for (std::size_t e = 0; e < 2; ++e) {
            const Solved& pose = solved_[e];
            if (pose.u != u) continue;
            for (const int upper : {0, 1}) {
                const EndFace& f = endFaces_[e][upper];
                if (f.alone && t == (upper ? pose.range.hi : pose.range.lo)) {
                    normal = f.normal, sharp = false;
                    return true;
                }
            }
        }
        return false;
    }

  private:
    /// Per end of a solved pose's interval (lower, upper), what note j asks of the face the line
    /// crosses there, found when first needed.
    struct Crossing {
        bool found = false;
        double across = 0.0;  ///< n.d: the face's outward normal n along the line
        double speed = 0.0;   ///< n.v, v the velocity of the tool point there
        double bend = 0.0;    ///< C: how far the face's supporting plane strays in second order
        int face = 0;         ///< the face's index up the meridian (faceNormal)
    };
    /// Per end of the end poses' intervals (solved_[0] and [1]), whether its crossing found no
    /// other face near (faceNormal's `alone`), and that face's normal: then the Hermite data of
    /// an output end there.
    struct EndFace {
        bool alone;
        Vec3 normal;
    };
    /// A static pose of the part in O at u, and its interval.
    struct Solved {
        double u = 0.0;
        ToolPose pose;
        Interval range;
        Crossing ends[2];
        TurnPhase phase;  ///< u's, which the velocities take
    };

    /// A pose where the line passes through rim `rim` of the part searched (note k), and the
    /// part's interval there.
    struct RimPose {
        std::size_t part = 0;
        int rim = 0;
        double u = 0.0;
        TurnPhase phase;
        ToolPose pose;
        Interval range;
    };

    bool held(const Interval& g) const { return care_.held(g); }
    /// The part's static poses at u = 0 and 1: into O, and the first two of `solved_`.
    void addEnds(std::size_t p);
    /// Note j's C for a tool point at `height` above the tip and `off` from the axis.
    double bendAt(double height, double off) const;
    const Crossing& crossing(Solved& pose, std::size_t p, int upper);
    /// How far from `pose`, on (sign 1) or back (sign -1) in u, the crossing at end `upper` of
    /// its interval bounds the points on the line beyond `cut`: the stretch tau below which
    /// note j's bound holds, with the distance D from the crossing to `cut` as slack (note m).
    double stretch(Solved& pose, std::size_t p, int upper, double cut, double sign);
    bool graze(std::size_t p, int upper, Solved& a, Solved& b, double& end);
    bool corner(std::size_t p, int upper, Solved& a, Solved& b, const Interval& swept, double& end);
    bool faceDip(std::size_t p, int upper, Solved& a, Solved& b, double& end);
    bool anchoredSettled(std::size_t p, double w, std::uint32_t a, std::uint32_t b, const Interval& swept, bool aim);
    /// Whether poses solved between those that made the ends of the gaps O leaves in `cut`,
    /// within the node [ua, ub], close them (note q); the poses go into O.
    bool bridge(std::size_t p, const Interval& cut, double ua, double ub);
    /// A node's grown band swept along its move, along the line: empty where it misses the care.
    Interval sweptWithin(const MoveSweep& sweep) const;
    /// Searches band b's nodes from its root down.
    void searchBand(std::size_t b, bool rootOpen);
    /// Whether a point of the care may lie at the band's heights above the tip at some pose
    /// (note p).
    bool reaches(const LinearPart& band);
    static std::vector<Solved>& threadSolved();

    const TurningSweep& s_;
    const Line& line_;
    const turning::Care& care_;
    turning::Union& found_;
    /// The poses solved, nodes referring to them by index: kept per thread, so that a query
    /// allocates nothing once its thread has seen one as deep.
    std::vector<Solved>& solved_;
    std::optional<LocalLine> atStart_, atEnd_;
    std::optional<Interval> heights_;  ///< the heights the care may take (reaches)
    turning::ShortList<RimPose, 4> rimPoses_;  ///< the rim poses found (corner)
    std::size_t endsAdded_;  ///< the part whose end poses are in O already
    /// Per end pose and end, for endsAdded_'s part: cleared by addEnds, set by crossing.
    EndFace endFaces_[2][2];
};

}  // namespace dexelmill
