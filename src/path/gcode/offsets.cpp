/// @file offsets.cpp
/// @brief Coordinates and offsets: the work coordinate systems, G92 and G52, G10, the stored
/// positions of G28 and G30, and which of them the program states.
#include "path/gcode/interpreter.h"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "path/detail/text.h"

namespace dexelmill::detail::gcode {

Vec3 Interpreter::toMachine(const Vec3& p) const {
    return offset() + (twp_ ? twpOrigin_ + twpRot_ * p : p);
}

Vec3 Interpreter::toProgram(const Vec3& m) const {
    const Vec3 w = m - offset();
    return twp_ ? twpRot_.transposeTimes(w - twpOrigin_) : w;
}

namespace {
/// G54..G59.3 in tenths, in the order of their offsets (g5x_, #5221 + 20 k).
constexpr int kCoordSystemCodes[9] = {540, 550, 560, 570, 580, 590, 591, 592, 593};
}  // namespace

std::string Interpreter::coordSystemName() const { return "G" + codeText(kCoordSystemCodes[coordSys_]); }

void Interpreter::setCoordSystem(int code, int col) {
    int k = coordSys_;
    for (int c = 0; c < 9; ++c)
        if (kCoordSystemCodes[c] == code) k = c;
    if (k == coordSys_) return;
    std::array<bool, 3> guessed{};
    for (int a = 0; a < 3; ++a) {
        const std::size_t i = std::size_t(a);
        g5x_[std::size_t(k)][a] = params_[std::size_t(5221 + 20 * k + a)];
        g5xRotary_[std::size_t(k)][i] = params_[std::size_t(5224 + 20 * k + a)];
        g5xStated_[std::size_t(k)][i] = g5xParamStated_[std::size_t(k)][i];
        g5xGuessed_[std::size_t(k)][i] = g5xParamGuessed_[std::size_t(k)][i];
        guessed[i] = g5xGuessed_[std::size_t(coordSys_)][i] || g5xGuessed_[std::size_t(k)][i];
    }
    coordSys_ = k;
    store(params_[5220], coordSys_ + 1);
    loseGuessedAxes(guessed, "G" + codeText(code), col);
}

void Interpreter::loseGuessedAxes(const std::array<bool, 3>& axes, const std::string& code, int col) {
    const std::string names = axisNames({axes[0] && known_[0], axes[1] && known_[1], axes[2] && known_[2]});
    if (names.empty()) return;
    // Under a tilted plane each program coordinate mixes all three: one lost loses them all.
    for (int a = 0; a < 3; ++a)
        if (axes[std::size_t(a)] || twp_) known_[a] = false;
    positionKnown_ = false;
    warn(code + " changes the offset of " + names + ", which was taken from a guessed machine position (G92 or " +
             "G10 L20 named the present point where it was unknown): where the tool stands on the part is unknown, so " +
             names + (names.size() == 1 ? " becomes" : " become") +
             " unknown and the moves are not simulated until X, Y and Z are all programmed again",
         code + " after a guessed position", col);
}

void Interpreter::warnMachineUnknown(const std::string& what, const std::array<bool, 3>& axes, const std::string& key,
                                     int col) {
    std::array<bool, 3> unstatedAxes{}, guessedAxes{};
    for (int a = 0; a < 3; ++a) {
        const std::size_t i = std::size_t(a);
        unstatedAxes[i] = axes[i] && !g5xStated_[std::size_t(coordSys_)][i];
        guessedAxes[i] = axes[i] && !unstatedAxes[i] && offsetGuessed(a);
    }
    const std::string names = axisNames(axes), unstated = axisNames(unstatedAxes), guessed = axisNames(guessedAxes);
    std::vector<std::string> why;
    if (!unstated.empty())
        why.push_back("the program never states the " + coordSystemName() + " work offset (G10 L2) of " + unstated +
                      " that places machine coordinates on the part");
    if (!guessed.empty())
        why.push_back("the offset of " + guessed + " was taken from a guessed machine position (G92 or G10 L20 named " +
                      "the present point where it was unknown)");
    if (axes[2] && tlo_)
        why.push_back("with a tool length offset active (G43) a machine Z is the spindle's gauge line, and the tip "
                      "stands a tool length below it, which the program does not state");
    std::string reasons;
    for (std::size_t i = 0; i < why.size(); ++i) reasons += (i == 0 ? "" : "; and ") + why[i];
    warn(what + ", and " + reasons + ": where the tool goes on the part is unknown, so " + names +
             (names.size() == 1 ? " stays" : " stay") +
             " unknown and the moves are not simulated until X, Y and Z are all programmed again",
         key, col);
}

bool Interpreter::executeNonModal(int code, Block& b, int motion) {
    const bool anyXYZ = b.has('X') || b.has('Y') || b.has('Z');
    auto axisConflict = [&]() {
        if (motion >= 0 && motion != 800 && anyXYZ)
            fail(b.col[firstAxisLetter(b) - 'A'],
                 "axis words used by both G" + codeText(code) + " and a motion",
                 tokenAt(b.col[firstAxisLetter(b) - 'A']));
    };
    switch (code) {
    case 100: {  // G10
        axisConflict();
        if (!b.has('L')) fail(b.gColumn(100), "G10 without L", "G10");
        const int l = int(std::lround(b.get('L')));
        if (l == 1 || l == 10 || l == 11) {
            for (char c : {'P', 'X', 'Y', 'Z', 'R', 'I', 'J', 'Q', 'D'})
                if (b.has(c)) b.use(c);
            warn("G10 L" + std::to_string(l) + " (tool table edit) ignored", "G10 L1");
            return true;
        }
        if (l != 2 && l != 20) fail(b.col['L' - 'A'], "unsupported G10 L" + std::to_string(l), tokenAt(b.col['L' - 'A']));
        if (!b.has('P')) fail(b.gColumn(100), "G10 L" + std::to_string(l) + " without P", "G10");
        const int p = int(std::lround(b.get('P')));
        if (p < 0 || p > 9) fail(b.col['P' - 'A'], "G10 P out of range 0..9", tokenAt(b.col['P' - 'A']));
        const int cs = p == 0 ? coordSys_ : p - 1;
        if (b.has('R') && b.get('R') != 0.0)
            fail(b.col['R' - 'A'], "G10 R (XY rotation of a coordinate system) is not supported", tokenAt(b.col['R' - 'A']));
        // A rotary axis's offset in that system: L2 sets it, L20 makes the current angle read as
        // the value given there (LinuxCNC's parameters 5224 to 5226, A to C, for G54).
        for (int a = 0; a < 3; ++a) {
            const char c = char('A' + a);
            if (!b.has(c)) continue;
            if (opt_.machine && !opt_.machine->has(c))
                fail(b.col[a], "the machine '" + opt_.machine->name + "' has no " + std::string(1, c) + " axis", tokenAt(b.col[a]));
            const double v = b.get(c);
            double& offset = g5xRotary_[std::size_t(cs)][std::size_t(a)];
            offset = l == 2 ? v : angles_.deg[a] - rotaryOffset_[std::size_t(a)] - v;
            if (!std::isfinite(offset)) fail(b.col[a], "G10: a non-finite rotary offset", tokenAt(b.col[a]));
            store(params_[std::size_t(5224 + 20 * cs + a)], offset);
        }
        refuseUvw(b);
        static const char letters[3] = {'X', 'Y', 'Z'};
        if (l == 20 && twp_)
            fail(b.gColumn(100), "G10 L20 with an active G68.2 is not supported", "G10");
        std::array<bool, 3> changed{};
        for (int a = 0; a < 3; ++a) {
            if (!b.has(letters[a])) continue;
            const double v = b.get(letters[a]) * units_;
            const std::size_t i = std::size_t(a);
            bool& stated = g5xStated_[std::size_t(cs)][i];
            bool& guessed = g5xGuessed_[std::size_t(cs)][i];
            if (l == 2) {
                // A new offset for the active system moves the part frame: a guess in the old one
                // leaves the position unknown in the new.
                changed[i] = cs == coordSys_ && guessed;
                g5x_[std::size_t(cs)][a] = v;
                stated = true;
                guessed = false;
            } else {
                // Taken from where the tool stands: as good as that position and the active offset.
                stated = known_[a] && g5xStated_[std::size_t(coordSys_)][i] && !offsetGuessed(a);
                guessed = !known_[a] || offsetGuessed(a);
                if (cs == coordSys_ && !known_[a]) {
                    // Touching off the active system names the present point, as G92 does (the
                    // operator's "here is X0"): where that is on the machine is unknown, so it is
                    // taken where the offset stays as it was, and the moves after it follow.
                    mpos_[a] = g5x_[std::size_t(cs)][a] + g92_[a] + v;
                    known_[a] = true;
                }
                g5x_[std::size_t(cs)][a] = mpos_[a] - g92_[a] - v;
            }
            store(params_[std::size_t(5221 + 20 * cs + a)], g5x_[std::size_t(cs)][a]);
            g5xParamStated_[std::size_t(cs)][i] = stated;
            g5xParamGuessed_[std::size_t(cs)][i] = guessed;
        }
        positionKnown_ = known_[0] && known_[1] && known_[2];
        everKnown_ = everKnown_ || positionKnown_;
        loseGuessedAxes(changed, "G10 L2", b.gColumn(100));
        return true;
    }
    case 280: case 300: {  // G28, G30: via the given point to the stored position
        axisConflict();
        const std::size_t which = code == 280 ? 0 : 1;
        const int base = code == 280 ? 5161 : 5181;
        const Vec3 home(params_[std::size_t(base)], params_[std::size_t(base + 1)],
                        params_[std::size_t(base + 2)]);
        const Vec3 pp = toProgram(mpos_);
        checkRotary(b, !absolute_);
        Vec3 end = home;
        if (anyXYZ) {
            const Vec3 via = targetOf(b, pp, !absolute_, false);
            emit(toMachine(via), true);
            end = mpos_;
        }
        // The stored position the program never states is the machine's own (LinuxCNC keeps it in
        // its parameter file): the axes that go there become unknown, as at the start.
        // A stored position the program states is a machine position: it is a place on the part
        // only where machine coordinates are (machineCoordKnown), as for G53.
        std::array<bool, 3> known{known_[0], known_[1], known_[2]};
        std::array<bool, 3> offPart{};
        std::string axes, params, placed, placedParams;
        for (int a = 0; a < 3; ++a)
            if (!anyXYZ || b.has(char('X' + a))) {
                const std::size_t i = std::size_t(a);
                end[a] = home[a];
                known[i] = homeStated_[which][i] && machineCoordKnown(a);
                if (known[i]) continue;
                std::string& list = homeStated_[which][i] ? placed : axes;
                std::string& nums = homeStated_[which][i] ? placedParams : params;
                offPart[i] = homeStated_[which][i];
                list += (list.empty() ? "" : ", ") + std::string(1, char('X' + a));
                nums += (nums.empty() ? "#" : ", #") + std::to_string(base + a);
            }
        if (!axes.empty())
            warn("G" + codeText(code) + " moves " + axes + " to the stored position (" + params +
                     "), which the program never sets (by assignment or G" + codeText(code + 1) +
                     "): where the machine goes is unknown, so " + axes + (axes.size() == 1 ? " stays" : " stay") +
                     " unknown and the moves are not simulated until X, Y and Z are all programmed again",
                 "G" + codeText(code) + " unknown", b.gColumn(code));
        if (!placed.empty())
            warnMachineUnknown("G" + codeText(code) + " moves " + placed + " to the stored position (" + placedParams +
                                   "), a machine position",
                               offPart, "G" + codeText(code) + " off the part", b.gColumn(code));
        setMachineKnown(known);
        emit(end, true);
        return true;
    }
    case 281: case 301: {
        const std::size_t which = code == 281 ? 0 : 1;
        const int base = code == 281 ? 5161 : 5181;
        for (int a = 0; a < 3; ++a) {
            store(params_[std::size_t(base + a)], mpos_[a]);
            // The machine position is known where the tool's place and the offsets are.
            homeStated_[which][std::size_t(a)] = known_[a] && machineCoordKnown(a);
        }
        return false;
    }
    case 520: case 920: {  // G52, G92
        axisConflict();
        if (opt_.machine) {
            // A rotary axis's offset: G92 makes its current angle read as the value given.
            for (int a = 0; a < 3; ++a) {
                const char c = char('A' + a);
                if (!b.has(c)) continue;
                if (!opt_.machine->has(c))
                    fail(b.col[a], "the machine '" + opt_.machine->name + "' has no " + std::string(1, c) + " axis", tokenAt(b.col[a]));
                const double v = b.get(c);
                rotaryOffset_[std::size_t(a)] =
                    code == 920 ? angles_.deg[a] - g5xRotary_[std::size_t(coordSys_)][std::size_t(a)] - v : v;
            }
        } else {
            checkRotary(b, false);
        }
        static const char letters[3] = {'X', 'Y', 'Z'};
        const Vec3 before = g92_;
        std::array<bool, 3> changed{};
        for (int a = 0; a < 3; ++a) {
            if (!b.has(letters[a])) continue;
            const double v = b.get(letters[a]) * units_;
            const std::size_t i = std::size_t(a);
            // G92 takes its offset from where the tool stands, guessed there if that is unknown;
            // G52 sets it outright, moving the part frame away from any guess in the old one.
            if (code == 920)
                g92Guessed_[i] = g92Guessed_[i] || !known_[a];
            else
                changed[i] = std::exchange(g92Guessed_[i], false);
            g92StoredGuessed_[i] = g92Guessed_[i];
            if (code == 920 && !known_[a] && !twp_) {
                // G92 names the present point, which is where the program says it is: an old-style
                // program's start (G92 X0 Y0 Z0 where the operator put the tool). Where that is on
                // the machine is unknown, so it is taken where the offset stays as it was: the moves
                // after it stay in the program's frame.
                mpos_[a] = g5x_[std::size_t(coordSys_)][a] + g92_[a] + v;
                known_[a] = true;
            }
            if (code == 920)
                g92_[a] = mpos_[a] - g5x_[std::size_t(coordSys_)][a] - v;
            else
                g92_[a] = v;
            store(params_[std::size_t(5211 + a)], g92_[a]);
        }
        positionKnown_ = known_[0] && known_[1] && known_[2];
        everKnown_ = everKnown_ || positionKnown_;
        // Offsets that change under a tilted plane would need the plane's frame.
        if (twp_ && g92_ != before)
            fail(b.gColumn(code),
                 "G52/G92 changing the offset under an active G68.2 is not supported",
                 "G" + codeText(code));
        loseGuessedAxes(changed, "G52", b.gColumn(code));
        return true;
    }
    case 921: case 922: {
        // Cleared, a guessed offset no longer keeps the part frame where the guess put it.
        const std::array<bool, 3> changed = g92Guessed_;
        g92_ = Vec3(0.0);
        g92Guessed_ = {false, false, false};
        rotaryOffset_ = {0.0, 0.0, 0.0};
        if (code == 921) {
            for (int a = 0; a < 3; ++a) store(params_[std::size_t(5211 + a)], 0.0);
            g92StoredGuessed_ = {false, false, false};
        }
        loseGuessedAxes(changed, "G" + codeText(code), b.gColumn(code));
        return false;
    }
    case 923: {
        std::array<bool, 3> changed{};
        for (int a = 0; a < 3; ++a) {
            const std::size_t i = std::size_t(a);
            g92_[a] = params_[std::size_t(5211 + a)];
            changed[i] = g92Guessed_[i] || g92StoredGuessed_[i];
        }
        g92Guessed_ = g92StoredGuessed_;
        loseGuessedAxes(changed, "G92.3", b.gColumn(code));
        return false;
    }
    default:
        return false;
    }
}

}  // namespace dexelmill::detail::gcode
