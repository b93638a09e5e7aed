/// @file interpreter.h
/// @brief The RS274/NGC interpreter behind parseGcode: its state and the blocks, parameters and
/// frames it works on. Its parts are defined by job: interpreter.cpp (set-up, errors), flow.cpp
/// (O-word structure, the execution loop, subroutines, endless loops), expressions.cpp
/// (parameters and expressions), blocks.cpp (block parsing, modal groups, Fanuc calls),
/// offsets.cpp (coordinates, work offsets, G92, G10, G28 and G30) and motion.cpp (the tilted work
/// plane, motion, canned cycles).
/// Semantics follow LinuxCNC's interpreter (the RS274/NGC interpreter of NIST, Kramer et al.
/// 2000, and LinuxCNC's G-code documentation); Fanuc macro forms (IF ... THEN/GOTO, WHILE ...
/// DOn/ENDn, M98/M99) follow the Fanuc programming manuals.
///
/// Each file's text is split into lines once (SourceFile, which also finds the O-word lines);
/// the O-word structures (sub, loops, if chains) and Fanuc program numbers are paired before the
/// file runs, so that flow jumps are table lookups. Each executed line is parsed into a Block (one
/// value per letter, the G and M codes, parameter assignments) and executed in the RS274/NGC
/// order of execution.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "dexelmill/path/gcode.h"
#include "path/detail/diagnostics.h"
#include "path/detail/gcode_source.h"

namespace dexelmill::detail::gcode {

inline constexpr double kInch = 25.4;
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDeg = kPi / 180.0;
/// LinuxCNC parameters #1..#5602 (and Fanuc system variables below #10000).
inline constexpr int kNumParams = 10000;

/// The letters of the axes X, Y, Z that `axes` marks, for messages: "X, Z".
inline std::string axisNames(const std::array<bool, 3>& axes) {
    std::string names;
    for (std::size_t a = 0; a < 3; ++a)
        if (axes[a]) names += (names.empty() ? "" : ", ") + std::string(1, char('X' + a));
    return names;
}
/// How far a centre-format arc's radius to its end may differ from its radius to its start: the
/// rule of LinuxCNC's arc_data_ijk (interp_arc.cc) with its default tolerances
/// (interp_internal.hh). With t the absolute tolerance of the program's units
/// (CENTER_ARC_RADIUS_TOLERANCE_MM or _INCH) and e = |r_end - r_start|, the arc is refused when
/// e > kArcSpiralCapFactor t, or when e > t and e / max(r_start, r_end) > kArcSpiralRelTol.
inline constexpr double kSqrt2 = 1.41421356237309504880;
inline constexpr double kArcSpiralAbsTolMm = 2 * 0.01 * kSqrt2;    ///< mm, in G21
inline constexpr double kArcSpiralAbsTolInch = 2 * 0.001 * kSqrt2; ///< inch, in G20
inline constexpr double kArcSpiralRelTol = 0.001;                 ///< SPIRAL_RELATIVE_TOLERANCE
inline constexpr double kArcSpiralCapFactor = 100.0;
/// An R-form arc whose chord exceeds the diameter by less than this (mm) is a half circle.
inline constexpr double kArcRadiusFit = 0.002;
/// Peck clearances of G83 and G73 (LinuxCNC: 0.010 inch and 0.002 inch).
inline constexpr double kG83RapidDelta = 0.010 * kInch;
inline constexpr double kG73Clearance = 0.002 * kInch;

/// The deepest nesting of an expression: each bracket (a function's argument included), unary
/// sign and right-associative ** adds one level. LinuxCNC's own parser stops far sooner; the limit
/// keeps the recursive reader (two to four frames a level, and one more for each precedence an
/// operator chain in it climbs) as deep as it went when a bracket counted twice against 1000
/// levels, which the sanitizer and fuzz builds, whose frames are larger, have run.
inline constexpr int kMaxExpressionDepth = 500;

/// Hot warning kinds, counted without building strings.
enum HotKind { kHotFeed, kHotSpeed, kHotZeroFeed, kHotCount };

/// A subroutine (O-word sub) or a Fanuc program (O number).
struct Sub {
    int file = 0;
    int start = 0;  ///< line index of `sub` or of the Fanuc program number
    int end = -1;   ///< line index of `endsub`; -1 for Fanuc programs (end at M99)
    bool called = false;
};

/// One line's words, as parsed.
struct Block {
    std::uint32_t mask = 0;  ///< letters present (bit = letter - 'A')
    std::uint32_t used = 0;  ///< letters that took effect
    double val[26];
    int col[26] = {};
    int g[16];
    int gcol[16];
    int ng = 0;
    int m[8];
    int mcol[8];
    int nm = 0;

    bool has(char c) const { return mask & (1u << (c - 'A')); }
    double get(char c) {
        used |= 1u << (c - 'A');
        return val[c - 'A'];
    }
    void use(char c) { used |= 1u << (c - 'A'); }
    bool hasG(int code) const {
        for (int i = 0; i < ng; ++i)
            if (g[i] == code) return true;
        return false;
    }
    /// The column of G-code `code` in the block; 0 when the block lacks it (a modal code).
    int gColumn(int code) const {
        for (int i = 0; i < ng; ++i)
            if (g[i] == code) return gcol[i];
        return 0;
    }
    /// The column of M-code `code` in the block; 0 when the block lacks it.
    int mColumn(int code) const {
        for (int i = 0; i < nm; ++i)
            if (m[i] == code) return mcol[i];
        return 0;
    }
};

/// A parameter a line names: #n, #<name>.
struct ParamRef {
    int index = 0;     ///< numbered parameter, when name is empty
    std::string name;  ///< named parameter, lower case
    int col = 0;
};

/// A subroutine call in progress.
struct Frame {
    int file = 0;
    int returnLine = 0;     ///< line to continue at after return
    int subStart = 0;       ///< first line of the body (Fanuc repeats)
    long repeatsLeft = 0;   ///< Fanuc M98 L repeats still to run
    bool fanuc = false;
    bool savedNumbered = false;
    std::array<double, 31> saved{};  ///< #1..#30 of the caller (O-call)
    std::unordered_map<std::string, double> locals;
    std::unordered_map<int, long> repeatCounters;
};

/// A 3 x 3 matrix by columns (the tilted work plane's rotation).
struct Mat3 {
    Vec3 c0{1, 0, 0}, c1{0, 1, 0}, c2{0, 0, 1};  ///< columns
    Vec3 operator*(const Vec3& p) const { return c0 * p.x + c1 * p.y + c2 * p.z; }
    Vec3 transposeTimes(const Vec3& p) const {
        return {glm::dot(c0, p), glm::dot(c1, p), glm::dot(c2, p)};
    }
    Mat3 operator*(const Mat3& o) const { return {(*this) * o.c0, (*this) * o.c1, (*this) * o.c2}; }
};

/// The rotation by `angle` (radians) about axis 0, 1 or 2.
inline Mat3 rotation(int axis, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    Mat3 r;
    if (axis == 0) {
        r.c1 = {0, c, s};
        r.c2 = {0, -s, c};
    } else if (axis == 1) {
        r.c0 = {c, 0, -s};
        r.c2 = {s, 0, c};
    } else {
        r.c0 = {c, s, 0};
        r.c1 = {-s, c, 0};
    }
    return r;
}

/// The interpreter: one per reading, fed one or more files in turn (they share the machine).
class Interpreter {
public:
    Interpreter(const GcodeOptions& options, Program& out);

    void run(std::string name, std::string text);

    /// Hands the diagnostics to the program; one that made no moves first learns of each
    /// subroutine it defines and never calls.
    void finish();

private:
    static constexpr std::size_t kNone = std::size_t(-1);

    // ---- errors and diagnostics ----
    [[noreturn]] void fail(int col, const std::string& message, std::string offending = {}) const;
    SourceLocation where(int col = 0) const;
    /// The text of a token starting at column col (1-based) of the current line.
    std::string tokenAt(int col, std::size_t maxLen = 24) const;
    void warn(const std::string& message, const std::string& key = {}, int col = 0);
    void hot(HotKind kind, const char* message, int col);

    // ---- structure ----
    [[noreturn]] void failAt(const SourceFile& f, int k, const std::string& message);

    int findForward(const SourceFile& f, int from, const std::string& label,
                    std::initializer_list<OKind> kinds, int stopAt = -1);

    void matchStructures(SourceFile& f);

    // ---- execution loop ----
    void execute(int file);

    static constexpr int kEndProgram = -2;

    int executeLine(SourceFile& f, int pc);

    // ---- O-words ----
    int executeOWord(SourceFile& f, int pc);

    int nextBranch(SourceFile& f, int k);

    /// A loop about to run `count` times executes at least one block per pass (its end line): a
    /// count the block limit cannot cover stops here, before any pass runs, rather than after
    /// the passes have filled memory with moves.
    void chargeRepeats(double count, int col, const char* what);

    std::unordered_map<int, long>& frameCounters();

    void checkRestIsComment(std::size_t pos);

    int callSub(const OWord& li, int pc, std::size_t pos);

    /// LinuxCNC looks for an undefined subroutine `o<name>` in the file `name.ngc` of the
    /// subroutine path; here: the folder of the calling file. Returns that file's path, read or not.
    std::string loadSubroutineFile(const std::string& label);

    int popFrame();

    // ---- endless loops ----
    /// What a loop's conditions can read: the parameters (the numbered ones also hold the work
    /// offsets, the coordinate system and G92), named and local ones, the position in the program
    /// frame (#5420..#5422) and the tool (#5400); and which subroutine activation runs.
    struct LoopState {
        std::uint64_t paramWrites = 0;
        std::uint64_t flowEpoch = 0;
        int tool = 0;
        Vec3 position;
        bool operator==(const LoopState& o) const {
            return paramWrites == o.paramWrites && flowEpoch == o.flowEpoch && tool == o.tool && position == o.position;
        }
    };
    /// The program frame as an affine map (units, offsets, tilted plane): the images of the
    /// origin and the unit points. Taken only while the rest of LoopState stays put.
    using FrameMap = std::array<Vec3, 4>;
    struct LoopWatch {
        LoopState last;
        std::optional<FrameMap> frame;
        int unchangedPasses = 0;
    };

    FrameMap frameMap() const;

    /// At the jump from line pc back to its loop's head. The interpreter is deterministic, and
    /// the path a pass takes through the loop depends only on what LoopState and the frame hold.
    /// If two passes in a row change none of it, whatever else they changed (a modal code, an
    /// offset taken from a parameter) the next pass sets again to the same value, so the whole
    /// state repeats and the loop would run until the block limit: it stops here instead.
    void backEdge(int pc);

    /// Writes a parameter, counting the writes that change it (LoopState).
    void store(double& slot, double v);
    void storeNamed(std::unordered_map<std::string, double>& table, const std::string& name, double v);

    // ---- parameters ----
    double getParam(const ParamRef& r);
    void setParam(const ParamRef& r, double v);

    ParamRef readParamRef(std::size_t& i);

    // ---- real values and expressions ----
    /// Counts one level of expression nesting while it lives; fails past kMaxExpressionDepth.
    class Nesting {
    public:
        Nesting(const Interpreter& self, int& depth, std::size_t i) : depth_(depth) {
            if (++depth_ > kMaxExpressionDepth) {
                --depth_;
                self.fail(int(i) + 1, "expression nested deeper than " + std::to_string(kMaxExpressionDepth) + " levels",
                          self.tokenAt(int(i) + 1));
            }
        }
        ~Nesting() { --depth_; }
        Nesting(const Nesting&) = delete;
        Nesting& operator=(const Nesting&) = delete;

    private:
        int& depth_;
    };

    double readRealValue(std::size_t& i);

    double readFunction(std::size_t& i);

    /// Binary operator at i: returns precedence (1 lowest .. 5 highest) and code, 0 if none.
    int peekOperator(std::size_t i, int& code, std::size_t& len);

    double parseExpression(std::size_t& i, int minPrec);

    // ---- block parsing ----
    /// @return false when the line has nothing to execute (e.g. a Fanuc IF that is false).
    bool parseBlock(Block& b, int& fanucJump, SourceFile& f, int pc);

    // ---- modal groups ----
    static int gGroup(int code);

    int executeBlock(Block& b, SourceFile& f, int pc);

    static char firstAxisLetter(const Block& b);

    static std::string codeText(int code);

    int callFanuc(Block& b, int pc);

    int returnFanuc(SourceFile&, int);

    // ---- coordinates ----
    Vec3 offset() const { return g5x_[std::size_t(coordSys_)] + g92_; }
    Vec3 toMachine(const Vec3& p) const;
    Vec3 toProgram(const Vec3& m) const;

    /// Selects G54..G59.3 (`code` in tenths) at column col. A system selected anew takes its
    /// offsets from its parameters (#5221 + 20 k ..), which an assignment may have changed: as in
    /// LinuxCNC, reselecting the active system changes nothing.
    void setCoordSystem(int code, int col);
    /// The active work coordinate system's code, G54 to G59.3.
    std::string coordSystemName() const;

    /// A guessed machine position enters the active offset of axis a: G92 or G10 L20 named the
    /// present point where it was unknown, and the offset was taken as it stood.
    bool offsetGuessed(int a) const { return g92Guessed_[std::size_t(a)] || g5xGuessed_[std::size_t(coordSys_)][std::size_t(a)]; }
    /// A machine coordinate of axis a (G53, G28, G30) is a known place in the part frame: the
    /// active work offset is stated and not guessed, and for Z no tool length offset is active
    /// (a machine Z is then the spindle's gauge line, a tool length above the tip).
    bool machineCoordKnown(int a) const {
        return g5xStated_[std::size_t(coordSys_)][std::size_t(a)] && !offsetGuessed(a) && !(a == 2 && tlo_);
    }
    /// Warns that `what` (e.g. "G53 moves X, Z in machine coordinates") goes where machine
    /// coordinates do not place the tool on the part, saying why for the axes `axes`.
    void warnMachineUnknown(const std::string& what, const std::array<bool, 3>& axes, const std::string& key, int col);
    /// An offset change that a guess enters (`axes`): the position was known only against the
    /// guessed offset, so the known axes among them become unknown, with a warning at col.
    void loseGuessedAxes(const std::array<bool, 3>& axes, const std::string& code, int col);

    void changeTool(int tool);

    /// Moves to `target`, whose coordinates known_ says are known (the callers set it first). A move
    /// from or to a position not wholly known is not simulated: it only sets the position.
    void emit(const Vec3& target, bool rapid);

    /// Sets which machine axes of the next target are known. Under a tilted work plane each
    /// program coordinate mixes all three machine axes: there a target is known wholly or not.
    void setMachineKnown(const std::array<bool, 3>& known);

    /// The program-frame target of the axis words (unspecified axes keep their place). An
    /// incremental word from an unknown coordinate is warned of, but for G28's and G30's point
    /// on the way (`warnUnknown` false), whose axes go on to the stored position: "G28 G91 Z0",
    /// the first line of many programs, would warn of a G91 move that is never made.
    Vec3 targetOf(Block& b, const Vec3& from, bool incremental, bool warnUnknown = true);

    /// The rotary angles the block's A, B, C words ask for (letters it lacks keep theirs).
    /// Without a machine, or for a letter the machine lacks, a word that turns an axis fails.
    /// In machine coordinates (G53) an angle is the axis's own, without the work offsets.
    RotaryAngles rotaryTarget(Block& b, bool incremental, bool machineCoords = false);
    /// For blocks whose motion cannot turn a rotary axis (arcs, cycles, G28, offsets): fails if
    /// an A, B or C word would turn one.
    void checkRotary(Block& b, bool incremental);
    /// Fails if the block has a U, V or W word.
    void refuseUvw(Block& b);
    /// Switches tool centre point control (M428 / G43.4 on, M429 / G49 off), keeping the tool where
    /// it is: the position changes from joints to part-frame tip or back.
    void setTcp(bool on, int col, const char* code);

    // ---- non-modal codes ----
    bool executeNonModal(int code, Block& b, int motion);

    // ---- tilted work plane (G68.2 / G53.x / G69) ----
    void defineTwp(Block& b);

    void orientTool(int code, Block& b);

    void cancelTwp();

    // ---- motion ----
    void executeMotion(int mode, Block& b, bool g53, int motionCol);

    void arc(bool clockwise, Block& b, int motionCol);

    static bool samePlanePoint(const Vec3& a, const Vec3& b, int p0, int p1);

    // ---- canned cycles ----
    void cycle(int mode, Block& b);

    const GcodeOptions& opt_;
    Program& out_;
    detail::DiagnosticCollector diags_;
    std::array<std::size_t, kHotCount> hot_;
    std::vector<std::unique_ptr<SourceFile>> files_;
    std::unordered_map<std::string, Sub> subs_;
    std::unordered_map<std::string, Sub> programs_;
    std::vector<Frame> frames_;
    std::unordered_map<int, long> topCounters_;
    /// #0..#9999. The stored positions and offsets among them (G28 #5161.., G30 #5181.., G92
    /// #5211.., G54..G59.3 #5221..) are in mm, the machine's units: LinuxCNC keeps them in its
    /// machine units and converts on use (USER_TO_PROGRAM_LEN), whatever G20/G21 is active. The
    /// reader is a machine configured in mm, as it starts in G21: on one configured in inches a
    /// program that reads these parameters after G20 would get inches.
    std::vector<double> params_;
    std::unordered_map<std::string, double> named_;
    std::vector<std::pair<ParamRef, double>> pending_;
    std::vector<Vec3> arcPts_;

    int curFile_ = -1;
    int curLineNo_ = 0;
    std::string_view line_;
    int depth_ = 0;  ///< expression nesting now (Nesting)
    std::size_t blocks_ = 0;

    // Machine state.
    double units_ = 1.0;
    int plane_ = 17;
    bool absolute_ = true;
    bool arcAbsolute_ = false;
    int motion_ = 800;
    int prevMotion_ = 800;
    int retract_ = 980;
    int coordSys_ = 0;
    std::array<Vec3, 9> g5x_{};
    /// G54..G59.3's offsets of the rotary axes A, B, C (degrees, set by G10 L2 / L20).
    std::array<std::array<double, 3>, 9> g5xRotary_{};
    Vec3 g92_{0.0};
    Vec3 mpos_{0.0};
    /// Which coordinates of the position (of the target, while a block computes one) the program
    /// has stated, and whether all three of the position are. A coordinate is unknown before the
    /// program gives it, and after a move to a machine position the program does not state (G28,
    /// G30, G53).
    bool known_[3] = {false, false, false};
    bool positionKnown_ = false;
    /// The position has been wholly known: an unknown one was lost on the way, not at the start.
    bool everKnown_ = false;
    /// Which of G54..G59.3's X, Y, Z offsets the program has stated (G10 L2, L20 where the
    /// position was known in machine coordinates, or its parameters when the system was selected).
    /// A machine coordinate (G53, G28, G30) is a known place in the frame the moves are simulated
    /// in only where the active system's offset is stated: the offsets set at the machine are not
    /// in the program.
    std::array<std::array<bool, 3>, 9> g5xStated_{};
    /// Which of them were taken from a guessed machine position (G10 L20 where the position was
    /// unknown, or rested on a guess).
    std::array<std::array<bool, 3>, 9> g5xGuessed_{};
    /// The same two for the parameters #5221 + 20 k ..: an assignment states one, and the system
    /// takes it when next selected.
    std::array<std::array<bool, 3>, 9> g5xParamStated_{}, g5xParamGuessed_{};
    /// The G92 offset's X, Y, Z, and those kept in #5211.. for G92.3, were taken from a guessed
    /// machine position (G92 where the position was unknown, or rested on a guess).
    std::array<bool, 3> g92Guessed_{}, g92StoredGuessed_{};
    /// A tool length offset is active (G43, G43.1, G43.2 until G49).
    bool tlo_ = false;
    /// Which X, Y, Z of the G28 (#5161..) and G30 (#5181..) positions the program has stated, by
    /// assignment or by G28.1 / G30.1 at a known position: the ones kept in the machine's
    /// parameter file are not in the program.
    std::array<std::array<bool, 3>, 2> homeStated_{};
    /// The rotary angles now, and those the current G0/G1 block moves to (emit).
    RotaryAngles angles_, nextAngles_;
    /// Tool centre point control: positions are the tip in the part frame, not joints.
    bool tcp_ = false;
    bool tcpByG434_ = false;
    /// G93 inverse-time feed is on: every G1, G2 and G3 move needs its own F word.
    bool inverseTime_ = false;
    /// The feed rate the last F set (program units per minute or per revolution); 0 before any
    /// F and after G94 or G95, which reset it, as LinuxCNC's convert_feed_mode does.
    double feedRate_ = 0.0;
    /// G92 / G52 offsets of the rotary axes (degrees): machine angle = programmed + this offset +
    /// the coordinate system's (g5xRotary_).
    std::array<double, 3> rotaryOffset_{0.0, 0.0, 0.0};  ///< TCP came from G43.4, so G49 ends it
    Vec3 baseAxis_{0, 0, 1};
    Vec3 axis_{0, 0, 1};
    bool twp_ = false;
    Mat3 twpRot_;
    Vec3 twpOrigin_{0.0};
    int toolInSpindle_ = 0;
    std::uint64_t paramWrites_ = 0;  ///< writes that changed a parameter
    std::uint64_t flowEpoch_ = 0;    ///< subroutine calls, returns and repeats so far
    std::unordered_map<std::uint64_t, LoopWatch> loops_;  ///< by file and back-edge line
    std::uint64_t lastLoopKey_ = 0;
    LoopWatch* lastLoop_ = nullptr;
    int selectedTool_ = 0;
    bool haveChanged_ = false;
    bool cycleIlFlag_ = false;
    bool cycleActive_ = false;
    double cycleIl_ = 0, cycleCc_ = 0, cycleR_ = 0, cycleQ_ = 0;
    /// The level the series of cycles began at (cycleIl_) is known: G98 retracts there, and in
    /// G91 the R plane counts from it.
    bool cycleIlKnown_ = false;
};

}  // namespace dexelmill::detail::gcode
