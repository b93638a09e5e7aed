/// @file blocks.cpp
/// @brief Parsing a line into a Block, and executing a block in the RS274/NGC order: modal groups,
/// Fanuc subprogram calls.
#include "path/gcode/interpreter.h"

#include <cmath>
#include <string>

#include "path/detail/text.h"

namespace dexelmill::detail::gcode {

bool Interpreter::parseBlock(Block& b, int& fanucJump, SourceFile& f, int pc) {
    (void)pc;
    std::size_t i = 0;
    const std::size_t n = line_.size();
    bool first = true;
    while (true) {
        while (i < n && (line_[i] == ' ' || line_[i] == '\t')) ++i;
        if (i >= n) break;
        const char raw = line_[i];
        const int col = int(i) + 1;
        if (raw == '/' && first) { ++i; continue; }
        if (raw == '(') {
            const std::size_t e = line_.find(')', i);
            if (e == std::string_view::npos)
                fail(col, "unterminated comment", std::string(line_.substr(i, 40)));
            i = e + 1;
            continue;
        }
        if (raw == ';') break;
        if (raw == '#') {
            ParamRef r = readParamRef(i);
            i = skipSpaces(line_, i);
            if (i >= n || line_[i] != '=')
                fail(r.col, "parameter without '=' assignment", tokenAt(r.col));
            ++i;
            const double v = readRealValue(i);
            pending_.emplace_back(std::move(r), v);
            first = false;
            continue;
        }
        const char c = upper(raw);
        if (c < 'A' || c > 'Z') fail(col, "unexpected character", std::string(1, raw));
        // Fanuc macro statements.
        if (c == 'I' && i + 1 < n && upper(line_[i + 1]) == 'F') {
            i += 2;
            i = skipSpaces(line_, i);
            if (i >= n || line_[i] != '[') fail(col, "IF needs a [condition]", tokenAt(col));
            const bool cond = readRealValue(i) != 0.0;
            i = skipSpaces(line_, i);
            if (i + 4 <= n && upper(line_[i]) == 'T' && upper(line_[i + 1]) == 'H' &&
                upper(line_[i + 2]) == 'E' && upper(line_[i + 3]) == 'N') {
                if (!cond) return false;
                i += 4;
                continue;
            }
            if (i + 4 <= n && upper(line_[i]) == 'G' && upper(line_[i + 1]) == 'O' &&
                upper(line_[i + 2]) == 'T' && upper(line_[i + 3]) == 'O') {
                i += 4;
                const int jcol = int(i) + 1;
                const long target = std::lround(readRealValue(i));
                if (!cond) return false;
                fanucJump = f.lineOfN(target);
                if (fanucJump < 0)
                    fail(jcol, "GOTO to a missing N" + std::to_string(target), tokenAt(jcol));
                return true;
            }
            fail(col, "IF needs THEN or GOTO", tokenAt(col));
        }
        if (c == 'G' && i + 1 < n && upper(line_[i + 1]) == 'O') {
            i += 2;
            if (i + 2 <= n && upper(line_[i]) == 'T' && upper(line_[i + 1]) == 'O') {
                i += 2;
                const int jcol = int(i) + 1;
                const long target = std::lround(readRealValue(i));
                fanucJump = f.lineOfN(target);
                if (fanucJump < 0)
                    fail(jcol, "GOTO to a missing N" + std::to_string(target), tokenAt(jcol));
                return true;
            }
            fail(col, "unknown word", tokenAt(col));
        }
        ++i;
        if (c == 'N') {
            if (!first) fail(col, "N word not at the start of the block", tokenAt(col));
            double v;
            i = skipSpaces(line_, i);
            if (!detail::parseUnsignedDecimal(line_, i, v))
                fail(col, "N word without a number", tokenAt(col));
            first = false;
            continue;
        }
        first = false;
        if (c == 'O') fail(col, "O-word not at the start of the block", tokenAt(col));
        if (c == 'E') fail(col, "unknown word", tokenAt(col));
        const double v = readRealValue(i);
        if (!std::isfinite(v)) fail(col, "value is not finite", tokenAt(col));
        // LinuxCNC's read_f: a feed rate is a speed, never negative.
        if (c == 'F' && v < 0.0) fail(col, "negative feed rate F: a feed rate is a speed, at least 0", tokenAt(col));
        if (c == 'G') {
            const double t = v * 10.0;
            const double r = std::nearbyint(t);
            if (std::abs(t - r) > 1e-6 || r < 0 || r > 10000) fail(col, "bad G-code number", tokenAt(col));
            if (b.ng >= 16) fail(col, "too many G-codes in one block", tokenAt(col));
            b.gcol[b.ng] = col;
            b.g[b.ng++] = int(r);
            continue;
        }
        if (c == 'M') {
            const double r = std::nearbyint(v);
            if (std::abs(v - r) > 1e-6 || r < 0 || r > 1000) fail(col, "bad M-code number", tokenAt(col));
            if (b.nm >= 8) fail(col, "too many M-codes in one block", tokenAt(col));
            b.mcol[b.nm] = col;
            b.m[b.nm++] = int(r);
            continue;
        }
        const int k = c - 'A';
        if (b.mask & (1u << k)) fail(col, std::string("two ") + c + " words in one block", tokenAt(col));
        b.mask |= 1u << k;
        b.val[k] = v;
        b.col[k] = col;
    }
    // Assignments take effect after the whole line has been read.
    for (auto& [ref, v] : pending_) setParam(ref, v);
    return b.mask != 0 || b.ng != 0 || b.nm != 0;
}

int Interpreter::gGroup(int code) {
    switch (code) {
    case 0: case 10: case 20: case 30: case 330: case 382: case 383: case 384: case 385:
    case 730: case 760: case 800: case 810: case 820: case 830: case 840: case 850: case 860:
    case 870: case 880: case 890: case 50: case 51: case 52: case 331: case 740:
        return 1;
    case 170: case 180: case 190: case 171: case 181: case 191: return 2;
    case 900: case 910: return 3;
    case 901: case 911: return 4;
    case 930: case 940: case 950: return 5;
    case 200: case 210: return 6;
    case 400: case 410: case 420: case 411: case 421: return 7;
    case 430: case 431: case 432: case 434: case 490: return 8;
    case 980: case 990: return 10;
    case 540: case 550: case 560: case 570: case 580: case 590: case 591: case 592: case 593:
        return 12;
    case 610: case 611: case 640: return 13;
    case 40: case 100: case 280: case 281: case 300: case 301: case 520: case 530: case 920:
    case 921: case 922: case 923: return 0;
    case 682: case 690: return 16;
    case 531: case 533: case 536: return 17;
    default: return -1;
    }
}

int Interpreter::executeBlock(Block& b, SourceFile& f, int pc) {
    // Modal group checks.
    int groupCode[20], groupCol[20];
    std::fill(std::begin(groupCode), std::end(groupCode), -1);
    std::fill(std::begin(groupCol), std::end(groupCol), 0);
    int motion = -1, nonModal = -1, motionCol = 0, nonModalCol = 0;
    for (int k = 0; k < b.ng; ++k) {
        const int code = b.g[k];
        const int grp = gGroup(code);
        if (grp < 0) {
            fail(b.gcol[k], "unsupported G-code G" + codeText(code), tokenAt(b.gcol[k]));
        }
        // Fanuc and Haas write "G00 G80": cancel the cycle, then move.
        if (grp == 1 && groupCode[1] >= 0 && (code == 800 || groupCode[1] == 800)) {
            if (code == 800) continue;
            groupCode[1] = code;
            motion = code, motionCol = b.gcol[k];
            continue;
        }
        // LinuxCNC's read_g: one code per modal group in a block, G53 among the non-modal group 0.
        if (groupCode[grp] >= 0)
            fail(b.gcol[k],
                 "two G-codes from one modal group (group " + std::to_string(grp) +
                     "): LinuxCNC allows one per block",
                 tokenAt(b.gcol[k]));
        groupCode[grp] = code;
        groupCol[grp] = b.gcol[k];
        if (grp == 1) motion = code, motionCol = b.gcol[k];
        if (grp == 0 && code != 530) nonModal = code, nonModalCol = b.gcol[k];
    }
    // LinuxCNC's check_g_codes: the dwell's time and the arc's turns would both be the P word.
    if (nonModal == 40 && (motion == 20 || motion == 30))
        fail(nonModalCol,
             "G4 with G" + codeText(motion) +
                 " in one block: both use P (dwell time, arc turns); LinuxCNC refuses them together",
             tokenAt(nonModalCol));
    const bool g53 = b.hasG(530);
    int mGroups[12];
    std::fill(std::begin(mGroups), std::end(mGroups), -1);
    for (int k = 0; k < b.nm; ++k) {
        const int m = b.m[k];
        int grp = 11;
        if (m == 0 || m == 1 || m == 2 || m == 30 || m == 60) grp = 4;
        else if (m == 3 || m == 4 || m == 5) grp = 7;
        else if (m == 7 || m == 8 || m == 9) grp = (m == 9 ? 8 : 9);
        else if (m == 6) grp = 6;
        else if (m == 98 || m == 99) grp = 10;
        if (grp != 11 && grp != 9 && mGroups[grp] >= 0)
            fail(b.mcol[k], "two M-codes from one modal group", tokenAt(b.mcol[k]));
        mGroups[grp] = m;
    }

    // 1. Feed mode, feed, speed.
    if (groupCode[5] >= 0) {
        inverseTime_ = groupCode[5] == 930;
        if (groupCode[5] != 930) feedRate_ = 0.0;
        if (groupCode[5] == 930) warn("G93 inverse-time feed: feeds are not simulated", "G93", groupCol[5]);
        else if (groupCode[5] == 950) warn("G95 feed per revolution: feeds are not simulated", "G95", groupCol[5]);
    }
    if (b.has('F')) {
        feedRate_ = b.get('F');
        hot(kHotFeed, "feed rate F is not simulated (ignored)", b.col['F' - 'A']);
    }
    if (b.has('S')) { b.use('S'); hot(kHotSpeed, "spindle speed S is not simulated (ignored)", b.col['S' - 'A']); }
    // 2. Tool select and change.
    if (b.has('T')) {
        const double t = b.get('T');
        if (t < 0 || std::abs(t - std::nearbyint(t)) > 1e-6 || t > 1e7)
            fail(b.col['T' - 'A'], "bad tool number", tokenAt(b.col['T' - 'A']));
        selectedTool_ = int(std::nearbyint(t));
        if (opt_.toolChangeOnT) changeTool(selectedTool_);
    }
    for (int k = 0; k < b.nm; ++k) {
        if (b.m[k] == 6) changeTool(selectedTool_);
    }
    // 3. Spindle, coolant, other M-codes.
    for (int k = 0; k < b.nm; ++k) {
        const int m = b.m[k];
        const int col = b.mcol[k];
        switch (m) {
        case 3: case 4: case 5:
            warn("spindle M3/M4/M5 is not simulated (ignored)", "spindle", col);
            break;
        case 7: case 8: case 9:
            warn("coolant M7/M8/M9 is not simulated (ignored)", "coolant", col);
            break;
        case 0: case 1: case 60:
            warn("program stop M" + std::to_string(m) + " ignored: the simulation runs on",
                 "stop M" + std::to_string(m), col);
            break;
        case 48: case 49: case 50: case 51: case 52: case 53:
            warn("override control M" + std::to_string(m) + " ignored", "override", col);
            break;
        case 2: case 30: case 6: case 98: case 99:
            break;
        case 428: case 429:  // LinuxCNC's switchable kinematics (its sim configs' remaps)
            setTcp(m == 428, col, m == 428 ? "M428" : "M429");
            break;
        default:
            warn("unknown M-code M" + std::to_string(m) + " ignored", "M" + std::to_string(m), col);
        }
    }
    // 4. Dwell. LinuxCNC's check_g_codes needs the time in P. Fanuc writes it as X (seconds), and
    // a block "G04 X1.5" must not become a move to X1.5: without P, X is the time.
    if (nonModal == 40) {
        if (b.has('P')) {
            b.use('P');
            warn("dwell G4 ignored (time is not simulated)", "dwell");
        } else if (b.has('X')) {
            b.mask &= ~(1u << ('X' - 'A'));
            warn("dwell G4 X: the time in seconds, as Fanuc writes it; no move to X (time is not simulated)",
                 "dwell", b.col['X' - 'A']);
        } else {
            fail(nonModalCol, "dwell time missing with G4: give it as P (seconds), as LinuxCNC needs",
                 tokenAt(nonModalCol));
        }
    }
    // 5. Plane, units, cutter compensation, tool length offsets.
    if (groupCode[2] >= 0) {
        const int p = groupCode[2];
        if (p != 170 && p != 180 && p != 190)
            fail(b.gColumn(p), "UVW planes are not supported", "G" + codeText(p));
        plane_ = p / 10;
    }
    if (groupCode[6] >= 0) units_ = groupCode[6] == 200 ? kInch : 1.0;
    if (groupCode[7] >= 0) {
        if (groupCode[7] != 400) {
            if (b.has('D')) b.use('D');
            warn("cutter radius compensation G41/G42 is not simulated: the path is the "
                 "programmed path",
                 "cutter comp");
        }
    }
    bool axisConsumed = false;
    if (groupCode[8] >= 0) {
        if (b.has('H')) b.use('H');
        if (groupCode[8] == 431 || groupCode[8] == 432)
            for (char c : {'X', 'Y', 'Z', 'I', 'J', 'K'})
                if (b.has(c) && groupCode[1] < 0 && motion < 0) b.use(c);
        // LinuxCNC's enhance_block gives the axis words of a block with G43.1 and no motion code
        // to the offset alone: the modal motion does not run. G43.2's words still feed it there.
        if (groupCode[8] == 431 && motion < 0) axisConsumed = true;
        if (groupCode[8] != 434) tlo_ = groupCode[8] != 490;
        if (groupCode[8] == 434) {
            setTcp(true, 0, "G43.4");
            tcpByG434_ = true;
        } else if (groupCode[8] == 490 && tcpByG434_) {
            setTcp(false, 0, "G49");
            tcpByG434_ = false;
        }
        if (groupCode[8] != 490)
            diags_.note(where(), "tool length offset: the simulated tip follows the programmed "
                                 "point",
                        "tlo");
    }
    // 6. Coordinate system, path control, distance modes, retract mode.
    if (groupCode[12] >= 0) setCoordSystem(groupCode[12], b.gColumn(groupCode[12]));
    if (groupCode[13] >= 0) {
        if (b.has('P')) b.use('P');
        if (b.has('Q')) b.use('Q');
        warn("path control G61/G64 ignored (exact path is simulated)", "path control");
    }
    if (groupCode[3] >= 0) absolute_ = groupCode[3] == 900;
    if (groupCode[4] >= 0) arcAbsolute_ = groupCode[4] == 901;
    if (groupCode[10] >= 0) retract_ = groupCode[10];
    // 7. Tilted work plane.
    if (groupCode[16] >= 0) {
        if (groupCode[16] == 690) {
            cancelTwp();
        } else {
            defineTwp(b);
            axisConsumed = true;
        }
    }
    // 8. Non-modal codes.
    if (nonModal >= 0 && nonModal != 40) {
        if (executeNonModal(nonModal, b, motion)) axisConsumed = true;
    }
    // 9. Motion.
    if (motion == 800) {
        motion_ = 800;
        cycleIlFlag_ = false;
    }
    const bool anyAxis = b.has('X') || b.has('Y') || b.has('Z') || b.has('A') || b.has('B') ||
                         b.has('C') || b.has('U') || b.has('V') || b.has('W');
    // LinuxCNC's enhance_block allows all axes missing with G0 and G1 only: a canned cycle, a
    // probe or a spline code in a block without an axis word is an error, not a block that does
    // nothing (arcs get their own message below).
    if (motion >= 0 && !axisConsumed && !anyAxis && motion != 0 && motion != 10 && motion != 20 && motion != 30 &&
        motion != 800)
        fail(motionCol,
             "all axes missing with motion code G" + codeText(motion) +
                 ": LinuxCNC takes a block without X, Y, Z or a rotary axis for G0 and G1 only",
             "G" + codeText(motion));
    if (groupCode[17] >= 0) {
        orientTool(groupCode[17], b);
        axisConsumed = true;
    }
    const int active = motion >= 0 ? motion : motion_;
    prevMotion_ = motion_;
    if (motion >= 0 && motion != 800) {
        motion_ = motion;
        if (motion < 730) cycleIlFlag_ = false;
    }
    if (!axisConsumed && anyAxis) {
        const int axCol = b.col[firstAxisLetter(b) - 'A'];
        if (active == 800)
            fail(axCol, "axis words with no motion mode active (G80 or none yet)", tokenAt(axCol));
        if (g53 && active != 0 && active != 10) fail(axCol, "G53 needs G0 or G1", tokenAt(axCol));
        executeMotion(active, b, g53, motionCol);
    } else if (!axisConsumed && (motion == 20 || motion == 30 ||
                                 (motion < 0 && (active == 20 || active == 30) &&
                                  (b.has('I') || b.has('J') || b.has('K'))))) {
        // LinuxCNC's enhance_block: an arc without axis words ends where it starts, a full circle
        // (G2 I5), and a block of centre words alone ("I5") takes the modal arc.
        executeMotion(active, b, g53, motionCol);
    }
    // 10. Unused words.
    const std::uint32_t unused = b.mask & ~b.used;
    if (unused) {
        for (int k = 0; k < 26; ++k)
            if (unused & (1u << k)) {
                const char c = char('A' + k);
                if (c == 'D' || c == 'H' || c == 'P' || c == 'Q' || c == 'L' || c == 'R' ||
                    c == 'I' || c == 'J' || c == 'K')
                    warn(std::string("word ") + c + " has no effect in this block (ignored)",
                         std::string("unused ") + c, b.col[k]);
                else
                    warn(std::string("word ") + c + " ignored", std::string("unused ") + c, b.col[k]);
            }
    }
    // 11. Program flow M-codes.
    for (int k = 0; k < b.nm; ++k) {
        const int m = b.m[k];
        if (m == 2 || m == 30) return kEndProgram;
        if (m == 98) return callFanuc(b, pc);
        if (m == 99) return returnFanuc(f, pc);
    }
    return pc + 1;
}

char Interpreter::firstAxisLetter(const Block& b) {
    for (char c : {'X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'})
        if (b.has(c)) return c;
    return 'X';
}

std::string Interpreter::codeText(int code) {
    std::string s = std::to_string(code / 10);
    if (code % 10) s += "." + std::to_string(code % 10);
    return s;
}

int Interpreter::callFanuc(Block& b, int pc) {
    if (!b.has('P')) fail(b.mColumn(98), "M98 without P program number", "M98");
    const double p = b.get('P');
    long repeats = 1;
    if (b.has('L')) {
        chargeRepeats(b.get('L'), b.col['L' - 'A'], "M98 L");
        repeats = std::lround(b.get('L'));
    }
    if (repeats <= 0) return pc + 1;
    const long pn = std::lround(p);
    std::string label = std::to_string(pn);
    auto it = programs_.find(label);
    if (it == programs_.end() || it->second.file != curFile_)
        fail(b.col['P' - 'A'], "M98 calls a missing program O" + label, tokenAt(b.col['P' - 'A']));
    if (int(frames_.size()) >= opt_.maxCallDepth)
        fail(b.mColumn(98),
             "subprogram calls nested deeper than " + std::to_string(opt_.maxCallDepth) +
                 " (recursion without end?)",
             "M98");
    Frame fr;
    fr.file = curFile_;
    fr.returnLine = pc + 1;
    fr.subStart = it->second.start + 1;
    fr.repeatsLeft = repeats - 1;
    fr.fanuc = true;
    frames_.push_back(std::move(fr));
    ++flowEpoch_;
    return it->second.start + 1;
}

int Interpreter::returnFanuc(SourceFile&, int) {
    if (frames_.empty()) {
        diags_.note(where(), "M99 in the main program ends it");
        return kEndProgram;
    }
    Frame& fr = frames_.back();
    if (!fr.fanuc) fail(0, "M99 inside an O-word subroutine", "M99");
    if (fr.repeatsLeft > 0) {
        --fr.repeatsLeft;
        ++flowEpoch_;
        return fr.subStart;
    }
    return popFrame();
}

}  // namespace dexelmill::detail::gcode
