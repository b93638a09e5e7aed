/// @file motion.cpp
/// @brief Motion (lines, arcs, helices), the tilted work plane and canned cycles.
#include "path/gcode/interpreter.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "path/detail/arc.h"
#include "path/detail/text.h"

namespace dexelmill::detail::gcode {

void Interpreter::changeTool(int tool) {
    if (tool == toolInSpindle_ && haveChanged_) return;
    haveChanged_ = true;
    toolInSpindle_ = tool;
    ToolChange tc;
    tc.moveIndex = out_.path.moves.size();
    tc.tool = tool;
    tc.source = {files_[std::size_t(curFile_)]->pathIndex, curLineNo_};
    out_.path.toolChanges.push_back(tc);
}

void Interpreter::emit(const Vec3& target, bool rapid) {
    if (!std::isfinite(target.x) || !std::isfinite(target.y) || !std::isfinite(target.z))
        fail(0, "move to a non-finite position", std::string(line_.substr(0, 40)));
    if (!withinReach(target))
        fail(0, "move to " + detail::formatPoint(target) + " mm, beyond the 1e9 mm a program may reach",
             std::string(line_.substr(0, 40)));
    if (out_.path.moves.size() >= opt_.maxMoves)
        fail(0, detail::tooManyMoves(opt_.maxMoves, opt_.maxMovesReason), std::string(line_.substr(0, 40)));
    if (twp_ && opt_.machine)
        fail(0, "a tilted work plane (G68.2) together with --machine is not supported", std::string(line_.substr(0, 40)));
    const bool targetKnown = known_[0] && known_[1] && known_[2];
    if (!positionKnown_ || !targetKnown) {
        // A move from or to a place the program does not state only sets the position: swept, it
        // would run from or to a guessed one, through the stock.
        if (!positionKnown_ && everKnown_)
            warn("the position is unknown since a move to a place the program does not state (a warning "
                 "there says which): this move only sets the position and is not simulated until X, Y and Z "
                 "are all programmed again",
                 "position lost");
        else if (!positionKnown_)
            warn("the start position is unknown until X, Y and Z are all programmed: this move only sets "
                 "the position and is not simulated",
                 "unknown start");
        ++out_.movesNotSimulated;
        positionKnown_ = targetKnown;
        everKnown_ = everKnown_ || targetKnown;
        mpos_ = target;
        angles_ = nextAngles_;
        return;
    }
    Move m;
    m.start = mpos_;
    m.end = target;
    m.axis = axis_;
    m.tool = toolInSpindle_;
    m.rapid = rapid;
    m.source = {files_[std::size_t(curFile_)]->pathIndex, curLineNo_};
    if (opt_.machine) {
        // The machine's kinematics give the pose in the part frame: with TCP the positions are
        // the tip there already; in identity kinematics they are joints, carried by the tables.
        const Machine& mc = *opt_.machine;
        if (!tcp_) {
            m.start = mc.partFromJoints(mpos_, angles_);
            m.end = mc.partFromJoints(target, nextAngles_);
            if (!withinReach(m.start) || !withinReach(m.end))
                fail(0, "the machine's kinematics put this move beyond the 1e9 mm a program may reach",
                     std::string(line_.substr(0, 40)));
        }
        m.axis = mc.toolAxis(nextAngles_);
        if (nextAngles_ != angles_) {
            m.startAxis = mc.toolAxis(angles_);
            m.rotary = std::make_shared<const RotaryMotion>(mc.motion(angles_, nextAngles_, tcp_, mpos_, target));
        }
    }
    if (opt_.machine)
        for (const RotaryAxisSpec& ax : opt_.machine->axes) {
            Interval& r = out_.rotaryRanges[std::size_t(ax.letter - 'A')];
            r = r.hull({angles_[ax.letter], angles_[ax.letter]}).hull({nextAngles_[ax.letter], nextAngles_[ax.letter]});
        }
    out_.path.moves.push_back(m);
    mpos_ = target;
    angles_ = nextAngles_;
}

void Interpreter::setMachineKnown(const std::array<bool, 3>& known) {
    const bool all = known[0] && known[1] && known[2];
    for (int a = 0; a < 3; ++a) known_[a] = twp_ ? all : known[std::size_t(a)];
}

Vec3 Interpreter::targetOf(Block& b, const Vec3& from, bool incremental, bool warnUnknown) {
    Vec3 t = from;
    static const char letters[3] = {'X', 'Y', 'Z'};
    for (int a = 0; a < 3; ++a)
        if (b.has(letters[a])) {
            const double v = b.get(letters[a]) * units_;
            t[a] = incremental ? from[a] + v : v;
            // A distance from an unknown place leads to an unknown one.
            if (!incremental)
                known_[a] = true;
            else if (!known_[a] && warnUnknown)
                warn(std::string("incremental (G91) ") + letters[a] + " from a position where " + letters[a] +
                         " is unknown: it stays unknown until it is programmed in G90 (or the start position is given)",
                     "incremental from unknown", b.col[letters[a] - 'A']);
        }
    return t;
}

RotaryAngles Interpreter::rotaryTarget(Block& b, bool incremental, bool machineCoords) {
    RotaryAngles next = angles_;
    for (int a = 0; a < 3; ++a) {
        const char c = char('A' + a);
        if (!b.has(c)) continue;
        const double v = b.get(c);  // degrees, whatever the length units
        const double offset = machineCoords ? 0.0 : rotaryOffset_[std::size_t(a)] + g5xRotary_[std::size_t(coordSys_)][std::size_t(a)];
        const double target = incremental ? angles_.deg[a] + v : v + offset;
        if (!std::isfinite(target)) fail(b.col[a], "rotary axis " + std::string(1, c) + " to a non-finite angle", tokenAt(b.col[a]));
        if (std::abs(target) > kMaxRotaryDegrees)
            fail(b.col[a],
                 "rotary axis " + std::string(1, c) + " to " + detail::formatNumber(target) +
                     " degrees, beyond the 1e6 degrees a program may turn an axis to",
                 tokenAt(b.col[a]));
        if (std::abs(target - angles_.deg[a]) > kMaxMoveTurnDegrees)
            fail(b.col[a],
                 "rotary axis " + std::string(1, c) + " turns " + detail::formatNumber(target - angles_.deg[a]) +
                     " degrees in one move; at most 3600 (ten turns) are supported: split the move",
                 tokenAt(b.col[a]));
        // An axis the machine lacks stays at zero: a word that leaves it there is ignored, with
        // a warning, and one that would turn it is refused.
        if (opt_.machine && !opt_.machine->has(c)) {
            const std::string lacks = "the machine '" + opt_.machine->name + "' has no " + std::string(1, c) + " axis";
            if (target != angles_.deg[a]) fail(b.col[a], lacks, tokenAt(b.col[a]));
            warn(lacks + ": '" + tokenAt(b.col[a]) + "' leaves it at zero and is ignored", lacks, b.col[a]);
            continue;
        }
        if (target == angles_.deg[a]) {
            if (!opt_.machine)
                warn("rotary word '" + tokenAt(b.col[a]) + "' turns nothing and is ignored: rotary axes "
                     "are simulated only with --machine NAME|FILE.json",
                     "rotary word without --machine", b.col[a]);
            continue;
        }
        if (!opt_.machine) {
            std::string names;
            for (const std::string& n : builtinMachineNames()) names += (names.empty() ? "" : ", ") + n;
            fail(b.col[a],
                 "rotary axis " + std::string(1, c) + " turns, and what it turns depends on the machine: give "
                 "--machine NAME|FILE.json (built-in: " + names + ")",
                 tokenAt(b.col[a]));
        }
        next.deg[a] = target;
    }
    refuseUvw(b);
    return next;
}

void Interpreter::refuseUvw(Block& b) {
    for (char c : {'U', 'V', 'W'})
        if (b.has(c)) fail(b.col[c - 'A'], "U/V/W axes are not supported", tokenAt(b.col[c - 'A']));
}

void Interpreter::checkRotary(Block& b, bool incremental) {
    if (rotaryTarget(b, incremental) == angles_) return;
    const char c = b.has('A') ? 'A' : b.has('B') ? 'B' : 'C';
    fail(b.col[c - 'A'], "a rotary axis turns in a block whose motion is not a straight G0/G1 move (not supported)",
         tokenAt(b.col[c - 'A']));
}

void Interpreter::setTcp(bool on, int col, const char* code) {
    if (!opt_.machine) {
        warn(std::string(code) + " (tool centre point control " + (on ? "on" : "off") +
                 ") has no effect without --machine",
             code, col);
        return;
    }
    if (on == tcp_) return;
    mpos_ = on ? opt_.machine->partFromJoints(mpos_, angles_) : opt_.machine->jointsFromPart(mpos_, angles_);
    tcp_ = on;
    if (positionKnown_ || !(known_[0] || known_[1] || known_[2])) return;
    // Each coordinate in the new frame may mix all three of the old: with one of them never
    // programmed, none of the converted ones is known, and the program must give X, Y and Z anew.
    const std::string unknown = axisNames({!known_[0], !known_[1], !known_[2]});
    std::fill(std::begin(known_), std::end(known_), false);
    warn(std::string(code) + " before X, Y and Z are all known (" + unknown +
             " not yet programmed): the position stays unknown until X, Y and Z are all programmed "
             "in the new frame",
         std::string(code) + " with the position unknown", col);
}

void Interpreter::defineTwp(Block& b) {
    const int p = b.has('P') ? int(std::lround(b.get('P'))) : 0;
    if (p != 0) fail(b.col['P' - 'A'], "G68.2 P" + std::to_string(p) + " is not supported (only P0, Euler angles)", tokenAt(b.col['P' - 'A']));
    int q = b.has('Q') ? int(std::lround(b.get('Q'))) : 313;
    const int d0 = q / 100, d1 = (q / 10) % 10, d2 = q % 10;
    if (q < 111 || q > 333 || d0 < 1 || d0 > 3 || d1 < 1 || d1 > 3 || d2 < 1 || d2 > 3 || d0 == d1 || d1 == d2)
        fail(b.has('Q') ? b.col['Q' - 'A'] : 0, "G68.2 Q must name an Euler order such as 313 or 121", "Q" + std::to_string(q));
    const double ai = b.has('I') ? b.get('I') * kDeg : 0.0;
    const double aj = b.has('J') ? b.get('J') * kDeg : 0.0;
    const double ak = b.has('K') ? b.get('K') * kDeg : 0.0;
    Mat3 r = rotation(d0 - 1, ai) * rotation(d1 - 1, aj) * rotation(d2 - 1, ak);
    if (b.has('R')) r = r * rotation(2, b.get('R') * kDeg);
    // The origin is given in the current (untilted) work coordinates.
    Vec3 origin(0.0);
    static const char letters[3] = {'X', 'Y', 'Z'};
    for (int a = 0; a < 3; ++a)
        if (b.has(letters[a])) origin[a] = b.get(letters[a]) * units_;
    if (twp_)
        fail(b.gColumn(682), "G68.2 while a tilted plane is active: cancel it with G69 first",
             "G68.2");
    twp_ = true;
    twpRot_ = r;
    twpOrigin_ = origin;
    diags_.note(where(), "G68.2 tilted work plane: coordinates are rotated; the tool axis "
                         "follows on G53.1/G53.3/G53.6",
                "twp");
}

void Interpreter::orientTool(int code, Block& b) {
    if (!twp_)
        fail(b.gColumn(code), "G" + codeText(code) + " without an active G68.2 plane",
             "G" + codeText(code));
    if (b.has('P')) b.use('P');
    axis_ = glm::normalize(twpRot_ * Vec3(0, 0, 1));
    if (code == 533) {
        const Vec3 pp = toProgram(mpos_);
        checkRotary(b, false);
        const Vec3 t = targetOf(b, pp, false);
        emit(toMachine(t), true);
    }
}

void Interpreter::cancelTwp() {
    twp_ = false;
    twpRot_ = Mat3{};
    twpOrigin_ = Vec3(0.0);
    axis_ = baseAxis_;
}

void Interpreter::executeMotion(int mode, Block& b, bool g53, int motionCol) {
    // LinuxCNC's convert_straight and convert_arc: in inverse time the F word is the move's
    // time, so a feed move without one has no feed at all.
    if (inverseTime_ && (mode == 10 || mode == 20 || mode == 30) && !b.has('F')) {
        const int col = motionCol ? motionCol : b.col[firstAxisLetter(b) - 'A'];
        fail(col,
             std::string("F word missing with inverse time ") + (mode == 10 ? "G1" : "arc") +
                 " move: after G93 each G1, G2 and G3 block needs its own F, as LinuxCNC requires",
             tokenAt(col));
    }
    // LinuxCNC's convert_straight, convert_arc and convert_cycle refuse to feed at a zero feed
    // rate. Feeds are not simulated, so the move is, as programmed; the user learns that a
    // controller would stop there.
    const bool feeds = mode == 10 || mode == 20 || mode == 30 || mode == 730 || (mode >= 810 && mode <= 890);
    if (feeds && !inverseTime_ && feedRate_ == 0.0)
        hot(kHotZeroFeed,
            "feed move with a zero feed rate (no F yet, F0, or G94/G95 since the last F, which reset it in LinuxCNC): "
            "LinuxCNC refuses it; feeds are not simulated, so it is simulated as programmed",
            motionCol ? motionCol : b.col[firstAxisLetter(b) - 'A']);
    // LinuxCNC's convert_cycle: a canned cycle's feeds have no time to take from an F word.
    if (inverseTime_ && (mode == 730 || (mode >= 810 && mode <= 890))) {
        const int col = motionCol ? motionCol : b.col[firstAxisLetter(b) - 'A'];
        fail(col, "cannot use inverse time feed with canned cycles: give G94 before G" + codeText(mode),
             tokenAt(col));
    }
    switch (mode) {
    case 0: case 10: {
        Vec3 target;
        if (g53) {
            if (!absolute_ && (b.has('X') || b.has('Y') || b.has('Z')))
                fail(b.gColumn(530), "G53 in incremental mode (G91)", "G53");
            target = mpos_;
            // A machine coordinate is a known place on the part only where the program states the
            // active work offset (the ones set at the machine are not in the program), no guess
            // enters it, and, for Z, no tool length offset lifts the point G53 names off the tip.
            std::array<bool, 3> known{known_[0], known_[1], known_[2]};
            std::array<bool, 3> lost{};
            static const char letters[3] = {'X', 'Y', 'Z'};
            for (int a = 0; a < 3; ++a)
                if (b.has(letters[a])) {
                    target[a] = b.get(letters[a]) * units_;
                    known[std::size_t(a)] = machineCoordKnown(a);
                    lost[std::size_t(a)] = !known[std::size_t(a)];
                }
            nextAngles_ = rotaryTarget(b, false, true);
            if (const std::string axes = axisNames(lost); !axes.empty())
                warnMachineUnknown("G53 moves " + axes + " in machine coordinates", lost, "G53 unknown", b.gColumn(530));
            setMachineKnown(known);
        } else {
            target = toMachine(targetOf(b, toProgram(mpos_), !absolute_));
            nextAngles_ = rotaryTarget(b, !absolute_);
        }
        emit(target, mode == 0);
        return;
    }
    case 20: case 30:
        arc(mode == 20, b, motionCol);
        return;
    case 730: case 810: case 820: case 830: case 850: case 890:
        cycle(mode, b);
        return;
    default:
        fail(motionCol, "unsupported motion G" + codeText(mode), "G" + codeText(mode));
    }
}

void Interpreter::arc(bool clockwise, Block& b, int motionCol) {
    int p0, p1, p2;
    char o0, o1, o2;
    if (plane_ == 17) { p0 = 0; p1 = 1; p2 = 2; o0 = 'I'; o1 = 'J'; o2 = 'K'; }
    else if (plane_ == 18) { p0 = 2; p1 = 0; p2 = 1; o0 = 'K'; o1 = 'I'; o2 = 'J'; }
    else { p0 = 1; p1 = 2; p2 = 0; o0 = 'J'; o1 = 'K'; o2 = 'I'; }
    // LinuxCNC's convert_arc: the centre word of the axis across the plane is an error, not a
    // word dropped (K on a G17 arc).
    if (b.has(o2))
        fail(b.col[o2 - 'A'],
             std::string(1, o2) + " word given for an arc in the G" + std::to_string(plane_) +
                 " plane: its centre takes " + o0 + " and " + o1 + " only, as LinuxCNC reads it",
             tokenAt(b.col[o2 - 'A']));
    checkRotary(b, !absolute_);
    const Vec3 s = toProgram(mpos_);
    const Vec3 e = targetOf(b, s, !absolute_);
    const int arcCol = motionCol;
    double c0, c1;
    const bool rForm = b.has('R');
    double turns = 1.0;
    if (b.has('P')) {
        turns = b.get('P');
        if (turns < 1 || std::abs(turns - std::nearbyint(turns)) > 1e-6 || turns > 1e6)
            fail(b.col['P' - 'A'], "arc P (turns) must be a positive integer", tokenAt(b.col['P' - 'A']));
    }
    if (rForm && (b.has(o0) || b.has(o1)))
        fail(b.col['R' - 'A'], "arc with both R and I/J/K", tokenAt(b.col['R' - 'A']));
    if (!rForm && !b.has(o0) && !b.has(o1))
        fail(arcCol, std::string("arc without ") + o0 + "/" + o1 + " or R", tokenAt(motionCol));
    if (!rForm && arcAbsolute_ && !(b.has(o0) && b.has(o1))) {
        // LinuxCNC's convert_arc: an absolute centre has no default for a word left out.
        const char given = b.has(o0) ? o0 : o1, missing = b.has(o0) ? o1 : o0;
        fail(b.col[given - 'A'],
             std::string(1, missing) +
                 " word missing in absolute center arc (G90.1): LinuxCNC needs both " + o0 +
                 " and " + o1 + " in the G" + std::to_string(plane_) + " plane",
             tokenAt(b.col[given - 'A']));
    }
    if (!positionKnown_) {
        // The arc's way hangs on its start (its centre, or its radius's side): from an unknown
        // start only its end is known, and the move places the tool there.
        for (char c : {'R', o0, o1})
            if (b.has(c)) b.use(c);
        emit(toMachine(e), false);
        return;
    }
    if (rForm) {
        const double r = b.get('R') * units_;
        const double dx = e[p0] - s[p0], dy = e[p1] - s[p1];
        const double d = std::hypot(dx, dy);
        if (d < 1e-9) fail(b.col['R' - 'A'], "R-form arc with the same start and end point", tokenAt(b.col['R' - 'A']));
        const double half = d / 2;
        double h2 = r * r - half * half;
        if (h2 < 0) {
            if (half - std::abs(r) > kArcRadiusFit)
                fail(b.col['R' - 'A'], "arc radius too small to reach the end point", tokenAt(b.col['R' - 'A']));
            h2 = 0;
        }
        const double h = std::sqrt(h2);
        const double tx = dx / d, ty = dy / d;
        // Left normal of the chord: the centre of a short counter-clockwise arc.
        const double nx = -ty, ny = tx;
        double sign = clockwise ? -1.0 : 1.0;
        if (r < 0) sign = -sign;
        c0 = s[p0] + dx / 2 + sign * h * nx;
        c1 = s[p1] + dy / 2 + sign * h * ny;
    } else {
        const double i0 = b.has(o0) ? b.get(o0) * units_ : 0.0;
        const double i1 = b.has(o1) ? b.get(o1) * units_ : 0.0;
        if (arcAbsolute_) {
            // G90.1: the centre in program coordinates (of the plane axes).
            c0 = i0;
            c1 = i1;
        } else {
            c0 = s[p0] + i0;
            c1 = s[p1] + i1;
        }
    }
    const double rs = std::hypot(s[p0] - c0, s[p1] - c1);
    const double re = std::hypot(e[p0] - c0, e[p1] - c1);
    if (rs < 1e-9) fail(motionCol, "arc of zero radius", tokenAt(motionCol));
    const double absTol = units_ == kInch ? kArcSpiralAbsTolInch * kInch : kArcSpiralAbsTolMm;
    const double absErr = std::abs(rs - re);
    const double relErr = absErr / std::max(rs, re);
    if (absErr > kArcSpiralCapFactor * absTol || (absErr > absTol && relErr > kArcSpiralRelTol))
        fail(rForm ? b.col['R' - 'A'] : motionCol,
             "radius to end of arc differs from radius to start (" + std::to_string(re) + " vs " +
                 std::to_string(rs) + " mm): LinuxCNC accepts a difference up to " +
                 detail::formatNumber(absTol) + " mm, or up to " +
                 detail::formatNumber(kArcSpiralCapFactor * absTol) + " mm within " +
                 detail::formatNumber(100 * kArcSpiralRelTol) + " % of the radius",
             tokenAt(rForm ? b.col['R' - 'A'] : motionCol, 60));
    const double as = std::atan2(s[p1] - c1, s[p0] - c0);
    const double ae = std::atan2(e[p1] - c1, e[p0] - c0);
    // The sweep in (0, 2 pi] in the direction of travel; coinciding ends make a full circle.
    double sweep = 2 * kPi;
    if (!samePlanePoint(s, e, p0, p1)) {
        sweep = std::fmod(clockwise ? as - ae : ae - as, 2 * kPi);
        if (sweep <= 0) sweep += 2 * kPi;
    }
    sweep += 2 * kPi * (turns - 1);
    if (clockwise) sweep = -sweep;
    detail::ArcSpec spec;
    Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    spec.u = axes[p0];
    spec.v = axes[p1];
    spec.w = axes[p2];
    spec.centre = c0 * spec.u + c1 * spec.v;
    spec.startAngle = as;
    spec.sweep = sweep;
    spec.startRadius = rs;
    spec.endRadius = re;
    spec.startHeight = s[p2];
    spec.endHeight = e[p2];
    const std::size_t n = detail::arcSegments(std::max(rs, re), sweep, opt_.chordTolerance, opt_.maxArcSegments);
    if (n == 0) fail(motionCol, "arc needs more chords than allowed at this tolerance", tokenAt(motionCol));
    arcPts_.clear();
    detail::arcPoints(spec, n, arcPts_);
    arcPts_.back() = e;
    const std::size_t before = out_.path.moves.size();
    for (const Vec3& p : arcPts_) emit(toMachine(p), false);
    if (const double sag = detail::chordSag(std::max(rs, re), sweep, n);
        out_.path.moves.size() > before && sag > out_.arcSag) {
        out_.arcSag = sag;
        out_.arcSagSource = out_.path.moves.back().source;
    }
}

bool Interpreter::samePlanePoint(const Vec3& a, const Vec3& b, int p0, int p1) {
    return std::abs(a[p0] - b[p0]) < 1e-9 && std::abs(a[p1] - b[p1]) < 1e-9;
}

void Interpreter::cycle(int mode, Block& b) {
    int ia, ib, ic;  // in-plane axes and the cycle (drill) axis
    if (plane_ == 17) { ia = 0; ib = 1; ic = 2; }
    else if (plane_ == 18) { ia = 2; ib = 0; ic = 1; }
    else { ia = 1; ib = 2; ic = 0; }
    const char cl = char('X' + ic);
    const char al = char('X' + ia), bl = char('X' + ib);
    const bool newCycle = prevMotion_ != mode || !cycleActive_;
    double ccWord;
    if (b.has(cl)) ccWord = b.get(cl) * units_;
    else if (!newCycle) ccWord = cycleCc_;
    else fail(b.gColumn(mode), std::string("canned cycle without ") + cl + " depth", "G" + codeText(mode));
    double rWord;
    if (b.has('R')) rWord = b.get('R') * units_;
    else if (!newCycle) rWord = cycleR_;
    else fail(b.gColumn(mode), "canned cycle without R plane", "G" + codeText(mode));
    double q = cycleQ_;
    if (mode == 730 || mode == 830) {
        if (b.has('Q')) q = b.get('Q') * units_;
        else if (newCycle) fail(b.gColumn(mode), "G73/G83 without Q peck depth", "G" + codeText(mode));
        if (!(q > 0)) fail(b.col['Q' - 'A'], "Q peck depth must be positive", tokenAt(b.col['Q' - 'A']));
    }
    if (mode == 820 || mode == 890) {
        if (b.has('P')) b.use('P');
        else if (newCycle) fail(b.gColumn(mode), "G82/G89 without P dwell", "G" + codeText(mode));
        warn("dwell in canned cycle ignored (time is not simulated)", "cycle dwell");
    }
    long repeats = 1;
    if (b.has('L')) {
        const double l = b.get('L');
        if (l < 0 || std::abs(l - std::nearbyint(l)) > 1e-6 || l > 1e7) fail(b.col['L' - 'A'], "L repeat must be a non-negative integer", tokenAt(b.col['L' - 'A']));
        repeats = long(std::nearbyint(l));
    }
    checkRotary(b, !absolute_);
    Vec3 pp = toProgram(mpos_);
    if (!cycleIlFlag_) {
        cycleIl_ = pp[ic];
        cycleIlKnown_ = known_[ic];
        cycleIlFlag_ = true;
    }
    // LinuxCNC's convert_cycle_xy: old_cc, the level the series of cycles began at, and
    // current_cc, where this block begins (the R plane after a G99 hole). Either may be unknown.
    double oldcc = cycleIl_;
    double currentCc = pp[ic];
    bool currentKnown = known_[ic];
    double r, cc, aa, bb, da = 0, db = 0;
    if (absolute_) {
        r = rWord;
        cc = ccWord;
        aa = b.has(al) ? b.get(al) * units_ : pp[ia];
        bb = b.has(bl) ? b.get(bl) * units_ : pp[ib];
    } else {
        if (b.has(al)) da = b.get(al) * units_;
        if (b.has(bl)) db = b.get(bl) * units_;
        r = rWord + oldcc;
        cc = r + ccWord;
        aa = pp[ia];
        bb = pp[ib];
    }
    if (r < cc) fail(b.has('R') ? b.col['R' - 'A'] : 0, "R plane below the cycle's bottom", "R");
    auto at = [&](double a, double bv, double c) {
        Vec3 p;
        p[ia] = a;
        p[ib] = bv;
        p[ic] = c;
        return toMachine(p);
    };
    // The holes' places are known where the position or the block's absolute words state them;
    // in G91 the R plane and the depth count from the level the series began at.
    const bool aKnown = known_[ia] || (absolute_ && b.has(al)), bKnown = known_[ib] || (absolute_ && b.has(bl));
    const bool rKnown = absolute_ || cycleIlKnown_;
    auto go = [&](double a, double bv, double c, bool cKnown, bool rapid) {
        known_[ia] = aKnown;
        known_[ib] = bKnown;
        known_[ic] = cKnown;
        emit(at(a, bv, c), rapid);
    };
    if (!cycleIlKnown_) {
        const int col = b.gColumn(mode) ? b.gColumn(mode) : b.col[firstAxisLetter(b) - 'A'];
        if (!absolute_)
            warn(std::string("canned cycle in G91 from an unknown ") + cl + ": its R plane and depth count from the " +
                     cl + " where the cycle began, so the cycle is not simulated",
                 "G91 cycle from unknown", col);
        else if (retract_ == 980)
            warn(std::string("G98 retracts to the ") + cl + " where the cycle began, which is unknown: the "
                     "retracts and the moves between the holes are not simulated, the holes are",
                 "G98 to unknown", col);
    }
    // The whole depth is known before the first move: a bottom out of reach, or more pecks
    // than an arc may have chords, stops here rather than after filling memory with pecks.
    const Vec3 bottom = at(aa + double(repeats) * da, bb + double(repeats) * db, cc);
    if (!std::isfinite(cc) || !withinReach(bottom))
        fail(b.has(cl) ? b.col[cl - 'A'] : 0,
             "canned cycle bottom " + detail::formatPoint(bottom) + " mm is beyond the 1e9 mm a program may reach",
             b.has(cl) ? tokenAt(b.col[cl - 'A']) : std::string(1, cl));
    if (mode == 730 || mode == 830) {
        const double pecks = std::ceil((r - cc) / q);
        if (pecks > double(opt_.maxArcSegments))
            fail(b.has('Q') ? b.col['Q' - 'A'] : 0,
                 "peck depth Q makes " + std::to_string(std::llround(std::min(pecks, 1e18))) + " pecks, more than the " +
                     std::to_string(opt_.maxArcSegments) + " a cycle may make",
                 b.has('Q') ? tokenAt(b.col['Q' - 'A']) : "Q");
    }
    // Below R, the tool first rises to it. From an unknown level it is unknown whether it does:
    // the level it then stands at, and G98 retracts to, is max(level, R), unknown too.
    if (cycleIlKnown_ && oldcc < r) {
        known_[ic] = true;
        emit(at(pp[ia], pp[ib], r), true);
        oldcc = r;
        currentCc = r;
        currentKnown = true;
    }
    if (!cycleIlKnown_) oldcc = std::max(oldcc, r);
    const double clear = retract_ == 990 ? r : oldcc;
    const bool clearKnown = retract_ == 990 ? rKnown : cycleIlKnown_;
    for (long rep = 0; rep < repeats; ++rep) {
        aa += da;
        bb += db;
        // LinuxCNC's CYCLE_MACRO: the first hole is reached at the block's starting level when
        // that is above R, every other at the clearance level, where the previous hole left it.
        const bool fromCurrent = rep == 0 && (currentCc > r || !currentKnown);
        const double travel = fromCurrent ? currentCc : clear;
        const bool travelKnown = fromCurrent ? currentKnown : clearKnown;
        go(aa, bb, travel, travelKnown, true);
        if (travel > r || !travelKnown) go(aa, bb, r, rKnown, true);
        switch (mode) {
        case 810: case 820:
            go(aa, bb, cc, rKnown, false);
            go(aa, bb, clear, clearKnown, true);
            break;
        case 850: case 890:
            go(aa, bb, cc, rKnown, false);
            go(aa, bb, r, rKnown, false);
            if (clear != r || !clearKnown) go(aa, bb, clear, clearKnown, true);
            break;
        case 830: {
            double depth = r - q;
            std::size_t guard = 0;
            for (; depth > cc; depth -= q) {
                if (++guard > opt_.maxArcSegments) fail(0, "too many pecks", "Q");
                go(aa, bb, depth, rKnown, false);
                go(aa, bb, r, rKnown, true);
                go(aa, bb, depth + kG83RapidDelta, rKnown, true);
            }
            go(aa, bb, cc, rKnown, false);
            go(aa, bb, clear, clearKnown, true);
            break;
        }
        case 730: {
            double depth = r - q;
            std::size_t guard = 0;
            for (; depth > cc; depth -= q) {
                if (++guard > opt_.maxArcSegments) fail(0, "too many pecks", "Q");
                go(aa, bb, depth, rKnown, false);
                go(aa, bb, depth + kG73Clearance, rKnown, true);
            }
            go(aa, bb, cc, rKnown, false);
            go(aa, bb, clear, clearKnown, true);
            break;
        }
        }
    }
    cycleActive_ = true;
    cycleCc_ = ccWord;
    cycleR_ = rWord;
    cycleQ_ = q;
}

}  // namespace dexelmill::detail::gcode
