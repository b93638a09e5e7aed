/// @file gcode.cpp
/// @brief The RS274/NGC interpreter. Semantics follow LinuxCNC's interpreter (the RS274/NGC
/// interpreter of NIST, Kramer et al. 2000, and LinuxCNC's G-code documentation); Fanuc macro
/// forms (IF ... THEN/GOTO, WHILE ... DOn/ENDn, M98/M99) follow the Fanuc programming manuals.
///
/// Each file's text is split into lines once (detail::SourceFile, which also finds the O-word
/// lines); the O-word structures (sub, loops, if chains) and Fanuc program numbers are paired
/// before the file runs, so that flow jumps are table lookups. Each executed line is parsed
/// into a Block (one value per letter, the G and M codes, parameter assignments) and executed in
/// the RS274/NGC order of execution.
#include "dexelmill/path/gcode.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <unordered_map>

#include "dexelmill/error.h"
#include "dexelmill/tool/builders.h"
#include "path/detail/arc.h"
#include "path/detail/diagnostics.h"
#include "path/detail/gcode_source.h"
#include "path/detail/text.h"

namespace dexelmill {

namespace {

using detail::upper;

constexpr double kInch = 25.4;
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
/// LinuxCNC parameters #1..#5602 (and Fanuc system variables below #10000).
constexpr int kNumParams = 10000;
/// An arc's radius to its end may differ from its radius to its start by this much (mm) and
/// this fraction before the arc is rejected (LinuxCNC uses similar limits).
constexpr double kArcRadiusAbsTol = 0.02;
constexpr double kArcRadiusRelTol = 0.001;
/// An R-form arc whose chord exceeds the diameter by less than this (mm) is a half circle.
constexpr double kArcRadiusFit = 0.002;
/// Peck clearances of G83 and G73 (LinuxCNC: 0.010 inch and 0.002 inch).
constexpr double kG83RapidDelta = 0.010 * kInch;
constexpr double kG73Clearance = 0.002 * kInch;

/// The deepest nesting of an expression: brackets, unary signs, function arguments and the
/// right-associative ** each add a level. LinuxCNC's own parser stops far sooner; the limit keeps
/// the recursive reader within a few hundred kilobytes of stack.
constexpr int kMaxExpressionDepth = 1000;

/// Hot warning kinds, counted without building strings.
enum HotKind { kHotFeed, kHotSpeed, kHotCount };

// ---------------------------------------------------------------------------------------------
// Subprograms.

using detail::OKind;
using detail::OWord;
using detail::SourceFile;
using detail::skipSpaces;

struct Sub {
    int file = 0;
    int start = 0;  ///< line index of `sub` or of the Fanuc program number
    int end = -1;   ///< line index of `endsub`; -1 for Fanuc programs (end at M99)
};

// ---------------------------------------------------------------------------------------------
// Blocks.

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
};

struct ParamRef {
    int index = 0;     ///< numbered parameter, when name is empty
    std::string name;  ///< named parameter, lower case
    int col = 0;
};

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

struct Mat3 {
    Vec3 c0{1, 0, 0}, c1{0, 1, 0}, c2{0, 0, 1};  ///< columns
    Vec3 operator*(const Vec3& p) const { return c0 * p.x + c1 * p.y + c2 * p.z; }
    Vec3 transposeTimes(const Vec3& p) const {
        return {glm::dot(c0, p), glm::dot(c1, p), glm::dot(c2, p)};
    }
    Mat3 operator*(const Mat3& o) const { return {(*this) * o.c0, (*this) * o.c1, (*this) * o.c2}; }
};

Mat3 rotation(int axis, double angle) {
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

// ---------------------------------------------------------------------------------------------

class Interpreter {
public:
    Interpreter(const GcodeOptions& options, Program& out) : opt_(options), out_(out) {
        params_.assign(kNumParams, 0.0);
        units_ = options.initialInches ? kInch : 1.0;
        const double len = glm::length(options.initialToolAxis);
        if (!(len > 0.0) || !std::isfinite(len))
            throw Error("GcodeOptions::initialToolAxis must be a non-zero finite vector");
        baseAxis_ = options.initialToolAxis / len;
        axis_ = baseAxis_;
        if (!(options.chordTolerance > 0.0))
            throw Error("GcodeOptions::chordTolerance must be positive");
        hot_.fill(kNone);
        if (options.startPosition) {
            mpos_ = *options.startPosition;
            known_[0] = known_[1] = known_[2] = positionKnown_ = true;
        }
    }

    void loadToolTable(const std::string& path) {
        const std::string text = detail::readFile(opt_.files, path);
        for (const ToolTableEntry& e : parseLinuxCncToolTable(text, path, opt_.toolTableInches)) {
            SourceLocation where{path, e.line, 0};
            if (e.diameter > 0.0) {
                out_.tools.insert_or_assign(e.tool, flatEndMill(e.diameter));
                diags_.note(where,
                            "tool table: T" + std::to_string(e.tool) +
                                " taken as a flat end mill of its diameter",
                            "tool table shape");
            } else {
                diags_.warn(where, "tool table: T" + std::to_string(e.tool) +
                                       " has no diameter; no tool shape defined");
            }
        }
    }

    void run(std::string name, std::string text) {
        files_.push_back(std::make_unique<SourceFile>(std::move(name), std::move(text)));
        SourceFile& f = *files_.back();
        const int index = int(files_.size() - 1);
        out_.path.files.push_back(f.name());
        f.pathIndex = std::uint32_t(out_.path.files.size() - 1);
        matchStructures(f);
        // One move per line that may make one, as a first guess: growing a list of millions of
        // moves by doubling costs a fifth of the reading time.
        const std::size_t room = opt_.maxMoves - std::min(opt_.maxMoves, out_.path.moves.size());
        out_.path.moves.reserve(out_.path.moves.size() + std::min(f.contentLines(), room));
        execute(index);
    }

    void finish() { diags_.appendTo(out_.diagnostics); }

private:
    static constexpr std::size_t kNone = std::size_t(-1);

    // ---- errors and diagnostics ----
    [[noreturn]] void fail(int col, const std::string& message, std::string offending = {}) const {
        throw ParseError(where(col), message, std::move(offending));
    }
    SourceLocation where(int col = 0) const {
        SourceLocation loc;
        if (curFile_ >= 0) {
            loc.file = files_[curFile_]->name();
            loc.line = curLineNo_;
        }
        loc.column = col;
        return loc;
    }
    /// The text of a token starting at column col (1-based) of the current line.
    std::string tokenAt(int col, std::size_t maxLen = 24) const {
        if (col <= 0 || std::size_t(col) > line_.size()) return std::string(line_.substr(0, maxLen));
        const std::size_t b = std::size_t(col - 1);
        const bool grouped = line_[b] == '[' || line_[b] == '#' || line_[b] == '(';
        std::size_t e = b + 1;
        while (e < line_.size() && e - b < maxLen) {
            const char ch = line_[e];
            if (ch == ' ' || ch == '\t') break;
            if (!grouped && std::isalpha(static_cast<unsigned char>(ch)) &&
                !std::isalpha(static_cast<unsigned char>(line_[e - 1])))
                break;
            ++e;
        }
        return std::string(line_.substr(b, e - b));
    }
    void warn(const std::string& message, const std::string& key = {}, int col = 0) {
        diags_.warn(where(col), message, key);
    }
    void hot(HotKind kind, const char* message) {
        if (hot_[kind] == kNone)
            hot_[kind] = diags_.warn(where(), message);
        else
            diags_.repeat(hot_[kind]);
    }

    // ---- structure ----
    [[noreturn]] void failAt(const SourceFile& f, int k, const std::string& message) {
        SourceLocation loc{f.name(), SourceFile::lineNumber(k), 1};
        throw ParseError(loc, message, std::string(f.line(k).substr(0, 40)));
    }

    int findForward(const SourceFile& f, int from, const std::string& label,
                    std::initializer_list<OKind> kinds, int stopAt = -1) {
        const int n = stopAt < 0 ? f.lineCount() : stopAt;
        for (auto it = f.owords().upper_bound(from); it != f.owords().end() && it->first < n; ++it) {
            if (it->second.label != label) continue;
            for (OKind kind : kinds)
                if (it->second.kind == kind) return it->first;
        }
        return -1;
    }

    void matchStructures(SourceFile& f) {
        for (auto& [k, li] : f.owords()) {
            switch (li.kind) {
            case OKind::Sub: {
                const int e = findForward(f, k, li.label, {OKind::EndSub});
                if (e < 0) failAt(f, k, "subroutine without endsub (unterminated subroutine)");
                li.match = e;
                if (subs_.count(li.label) && subs_[li.label].file == int(files_.size() - 1))
                    failAt(f, k, "subroutine defined twice");
                subs_[li.label] = Sub{int(files_.size() - 1), k, e};
                break;
            }
            case OKind::Label:
                if (!programs_.count(li.label))
                    programs_[li.label] = Sub{int(files_.size() - 1), k, -1};
                break;
            case OKind::Do: {
                const int e = findForward(f, k, li.label, {OKind::While});
                if (e < 0) failAt(f, k, "do without its while (unterminated loop)");
                li.match = e;
                f.owords().at(e).whileIsTail = true;
                f.owords().at(e).match = k;
                break;
            }
            case OKind::While:
                if (li.whileIsTail) break;
                {
                    const int e = findForward(f, k, li.label, {OKind::EndWhile});
                    if (e < 0) failAt(f, k, "while without endwhile (unterminated loop)");
                    li.match = e;
                    f.owords().at(e).match = k;
                }
                break;
            case OKind::Repeat: {
                const int e = findForward(f, k, li.label, {OKind::EndRepeat});
                if (e < 0) failAt(f, k, "repeat without endrepeat (unterminated loop)");
                li.match = e;
                f.owords().at(e).match = k;
                break;
            }
            case OKind::If: {
                const int endif = findForward(f, k, li.label, {OKind::EndIf});
                if (endif < 0) failAt(f, k, "if without endif (unterminated if)");
                int cur = k;
                while (true) {
                    OWord& c = f.owords().at(cur);
                    c.endIf = endif;
                    const int next =
                        findForward(f, cur, li.label, {OKind::ElseIf, OKind::Else}, endif);
                    c.match = next < 0 ? endif : next;
                    if (next < 0) break;
                    cur = next;
                }
                break;
            }
            case OKind::ElseIf:
            case OKind::Else:
            case OKind::EndIf:
                if (li.endIf < 0 && li.kind != OKind::EndIf)
                    failAt(f, k, "else/elseif without if");
                break;
            case OKind::EndWhile:
            case OKind::EndRepeat:
                if (li.match < 0) failAt(f, k, "loop end without its start");
                break;
            case OKind::EndSub:
                break;
            case OKind::FanucWhile: {
                const int e = findForward(f, k, li.label, {OKind::FanucEnd});
                if (e < 0) failAt(f, k, "WHILE ... DO without END (unterminated loop)");
                li.match = e;
                f.owords().at(e).match = k;
                break;
            }
            default:
                break;
            }
        }
    }

    // ---- execution loop ----
    void execute(int file) {
        curFile_ = file;
        int pc = 0;
        bool sawPercent = false;
        bool ended = false;
        while (true) {
            // Subroutine calls may switch to a subroutine file and back.
            SourceFile& f = *files_[std::size_t(curFile_)];
            if (pc >= f.lineCount()) break;
            if (++blocks_ > opt_.maxBlocks) {
                curLineNo_ = SourceFile::lineNumber(pc);
                fail(1, "program does not terminate: more than " +
                            std::to_string(opt_.maxBlocks) + " blocks executed",
                     std::string(f.line(pc).substr(0, 40)));
            }
            curLineNo_ = SourceFile::lineNumber(pc);
            line_ = f.line(pc);
            // '%' lines: the first opens the program, a later one ends it.
            {
                const std::size_t i = skipSpaces(line_, 0);
                if (i < line_.size() && line_[i] == '%') {
                    if (curFile_ != file) {
                        ++pc;
                        continue;
                    }
                    if (!sawPercent && f.startsWithPercent()) {
                        sawPercent = true;
                        ++pc;
                        continue;
                    }
                    ended = true;
                    break;
                }
            }
            const int next = executeLine(f, pc);
            if (next == kEndProgram) {
                ended = true;
                break;
            }
            pc = next;
        }
        if (!ended) {
            const SourceFile& f = *files_[std::size_t(curFile_)];
            // Report at the last line that holds anything.
            int last = f.lineCount();
            while (last > 0 && skipSpaces(f.line(last - 1), 0) >= f.line(last - 1).size()) --last;
            const std::string lastText = last ? std::string(f.line(last - 1).substr(0, 40)) : std::string();
            curLineNo_ = last ? SourceFile::lineNumber(last - 1) : 0;
            line_ = {};
            if (!frames_.empty())
                fail(1, "file ends inside a subroutine (missing M99 or endsub)", lastText);
            if (f.startsWithPercent())
                fail(1, "file ends without its closing '%' (truncated file?)", lastText);
        }
        frames_.clear();
    }

    static constexpr int kEndProgram = -2;

    int executeLine(SourceFile& f, int pc) {
        std::size_t i = skipSpaces(line_, 0);
        if (i < line_.size() && line_[i] == '/') {
            if (!opt_.runDeletedBlocks) return pc + 1;
            warn("block delete '/': the block runs (block delete switch off)", "block delete", int(i) + 1);
        }
        if (f.oword(pc)) return executeOWord(f, pc);
        Block b;
        pending_.clear();
        int fanucJump = -1;
        if (!parseBlock(b, fanucJump, f, pc)) return pc + 1;  // IF false / comment-only
        if (fanucJump != -1) {
            if (fanucJump <= pc) backEdge(pc);
            return fanucJump;
        }
        return executeBlock(b, f, pc);
    }

    // ---- O-words ----
    int executeOWord(SourceFile& f, int pc) {
        const OWord& li = *f.oword(pc);
        std::size_t pos = li.argPos;
        auto condition = [&]() {
            pos = skipSpaces(line_, pos);
            if (pos >= line_.size() || line_[pos] != '[')
                fail(int(pos) + 1, "expected a [condition]", tokenAt(int(pos) + 1));
            const double v = readRealValue(pos);
            checkRestIsComment(pos);
            return v != 0.0;
        };
        switch (li.kind) {
        case OKind::Label:
            checkRestIsComment(pos);
            return pc + 1;
        case OKind::Sub:
            return li.match + 1;  // definition: skip the body
        case OKind::EndSub:
        case OKind::Return: {
            if (frames_.empty() || frames_.back().fanuc)
                fail(1, "endsub/return outside a subroutine call", std::string(line_.substr(0, 40)));
            pos = skipSpaces(line_, pos);
            if (pos < line_.size() && line_[pos] == '[') storeNamed(named_, "_value", readRealValue(pos));
            return popFrame();
        }
        case OKind::Call:
            return callSub(li, pc, pos);
        case OKind::Do:
            return pc + 1;
        case OKind::While:
            if (li.whileIsTail) {
                if (!condition()) return pc + 1;
                backEdge(pc);
                return li.match + 1;
            }
            return condition() ? pc + 1 : li.match + 1;
        case OKind::EndWhile:
            backEdge(pc);
            return li.match;  // back to the head, which tests again
        case OKind::If: {
            if (condition()) return pc + 1;
            return nextBranch(f, li.match);
        }
        case OKind::ElseIf:
        case OKind::Else:
            // Reached by falling out of the branch above: skip to endif.
            return li.endIf + 1;
        case OKind::EndIf:
            return pc + 1;
        case OKind::Repeat: {
            pos = skipSpaces(line_, pos);
            const int countCol = int(pos) + 1;
            const double v = readRealValue(pos);
            chargeRepeats(v, countCol, "repeat");
            const long count = std::lround(v);
            if (count <= 0) return li.match + 1;
            frameCounters()[pc] = count;
            return pc + 1;
        }
        case OKind::EndRepeat: {
            long& c = frameCounters()[li.match];
            if (--c > 0) return li.match + 1;
            return pc + 1;
        }
        case OKind::Break:
        case OKind::Continue: {
            // The innermost loop with this label around pc.
            const auto& owords = f.owords();
            for (auto it = std::make_reverse_iterator(owords.lower_bound(pc)); it != owords.rend(); ++it) {
                const auto& [k, h] = *it;
                if (h.label != li.label) continue;
                if (h.kind == OKind::Do || (h.kind == OKind::While && !h.whileIsTail) ||
                    h.kind == OKind::Repeat) {
                    const int end = h.match;
                    if (li.kind == OKind::Break) return end + 1;
                    if (h.kind == OKind::Do) return end;  // test the condition
                    if (h.kind == OKind::While) {
                        backEdge(pc);
                        return k;
                    }
                    long& c = frameCounters()[k];
                    return --c > 0 ? k + 1 : end + 1;
                }
            }
            fail(1, "break/continue outside a loop with its label", std::string(line_.substr(0, 40)));
        }
        case OKind::FanucWhile: {
            pos = skipSpaces(line_, pos);
            const double v = readRealValue(pos);
            return v != 0.0 ? pc + 1 : li.match + 1;
        }
        case OKind::FanucEnd:
            if (li.match < 0) fail(1, "END without WHILE", std::string(line_.substr(0, 40)));
            backEdge(pc);
            return li.match;
        default:
            return pc + 1;
        }
    }

    int nextBranch(SourceFile& f, int k) {
        while (true) {
            const OWord& b = f.owords().at(k);
            curLineNo_ = SourceFile::lineNumber(k);
            line_ = f.line(k);
            if (b.kind == OKind::EndIf) return k + 1;
            if (b.kind == OKind::Else) return k + 1;
            // elseif
            std::size_t pos = skipSpaces(line_, b.argPos);
            if (pos >= line_.size() || line_[pos] != '[')
                fail(int(pos) + 1, "expected a [condition]", tokenAt(int(pos) + 1));
            if (readRealValue(pos) != 0.0) return k + 1;
            k = b.match;
        }
    }

    /// A loop about to run `count` times executes at least one block per pass (its end line): a
    /// count the block limit cannot cover stops here, before any pass runs, rather than after
    /// the passes have filled memory with moves.
    void chargeRepeats(double count, int col, const char* what) {
        if (!std::isfinite(count)) fail(col, std::string(what) + " count is not finite", tokenAt(col));
        if (count > double(opt_.maxBlocks - std::min(blocks_, opt_.maxBlocks)))
            fail(col,
                 std::string(what) + " count " + tokenAt(col) + " exceeds the " + std::to_string(opt_.maxBlocks) +
                     " blocks a program may execute",
                 tokenAt(col));
    }

    std::unordered_map<int, long>& frameCounters() {
        return frames_.empty() ? topCounters_ : frames_.back().repeatCounters;
    }

    void checkRestIsComment(std::size_t pos) {
        pos = skipSpaces(line_, pos);
        while (pos < line_.size()) {
            if (line_[pos] == ';') return;
            if (line_[pos] == '(') {
                const std::size_t e = line_.find(')', pos);
                if (e == std::string_view::npos)
                    fail(int(pos) + 1, "unterminated comment", std::string(line_.substr(pos, 40)));
                pos = skipSpaces(line_, e + 1);
                continue;
            }
            fail(int(pos) + 1, "unexpected text after O-word", tokenAt(int(pos) + 1));
        }
    }

    int callSub(const OWord& li, int pc, std::size_t pos) {
        auto it = subs_.find(li.label);
        if (it == subs_.end()) {
            loadSubroutineFile(li.label);
            it = subs_.find(li.label);
        }
        if (it == subs_.end())
            fail(1, "call of an undefined subroutine o<" + li.label + ">", std::string(line_.substr(0, 40)));
        std::array<double, 31> args{};
        int nargs = 0;
        pos = skipSpaces(line_, pos);
        while (pos < line_.size() && line_[pos] == '[') {
            if (nargs >= 30) fail(int(pos) + 1, "more than 30 subroutine arguments", tokenAt(int(pos) + 1));
            args[std::size_t(++nargs)] = readRealValue(pos);
            pos = skipSpaces(line_, pos);
        }
        checkRestIsComment(pos);
        if (int(frames_.size()) >= opt_.maxCallDepth)
            fail(1, "subroutine calls nested deeper than " + std::to_string(opt_.maxCallDepth) +
                        " (recursion without end?)",
                 std::string(line_.substr(0, 40)));
        Frame fr;
        fr.file = curFile_;
        fr.returnLine = pc + 1;
        fr.savedNumbered = true;
        for (int k = 1; k <= 30; ++k) {
            fr.saved[std::size_t(k)] = params_[std::size_t(k)];
            store(params_[std::size_t(k)], args[std::size_t(k)]);
        }
        frames_.push_back(std::move(fr));
        ++flowEpoch_;
        const Sub& s = it->second;
        curFile_ = s.file;
        return s.start + 1;
    }

    /// LinuxCNC looks for an undefined subroutine `o<name>` in the file `name.ngc` of the
    /// subroutine path; here: the folder of the calling file.
    void loadSubroutineFile(const std::string& label) {
        const std::string dir = detail::directoryOf(files_[std::size_t(curFile_)]->name());
        const std::string path = detail::joinPath(dir, label + ".ngc");
        std::optional<std::string> text = detail::readFileIfAny(opt_.files, path);
        if (!text) return;
        const int saved = curFile_;
        const int savedLine = curLineNo_;
        const std::string_view savedText = line_;
        files_.push_back(std::make_unique<SourceFile>(path, std::move(*text)));
        SourceFile& f = *files_.back();
        out_.path.files.push_back(f.name());
        f.pathIndex = std::uint32_t(out_.path.files.size() - 1);
        curFile_ = int(files_.size() - 1);
        matchStructures(f);
        curFile_ = saved;
        curLineNo_ = savedLine;
        line_ = savedText;
        diags_.note(where(), "subroutine o<" + label + "> read from " + path);
    }

    int popFrame() {
        Frame fr = std::move(frames_.back());
        frames_.pop_back();
        ++flowEpoch_;
        curFile_ = fr.file;
        if (fr.savedNumbered)
            for (int k = 1; k <= 30; ++k) store(params_[std::size_t(k)], fr.saved[std::size_t(k)]);
        return fr.returnLine;
    }

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

    FrameMap frameMap() const {
        FrameMap m;
        m[0] = toProgram(Vec3(0.0)) / units_;
        for (int a = 0; a < 3; ++a) {
            Vec3 e(0.0);
            e[a] = 1.0;
            m[std::size_t(a) + 1] = toProgram(e) / units_;
        }
        return m;
    }

    /// At the jump from line pc back to its loop's head. The interpreter is deterministic, and
    /// the path a pass takes through the loop depends only on what LoopState and the frame hold.
    /// If two passes in a row change none of it, whatever else they changed (a modal code, an
    /// offset taken from a parameter) the next pass sets again to the same value, so the whole
    /// state repeats and the loop would run until the block limit: it stops here instead.
    void backEdge(int pc) {
        const LoopState now{paramWrites_, flowEpoch_, toolInSpindle_, mpos_};
        const std::uint64_t key = (std::uint64_t(std::uint32_t(curFile_)) << 32) | std::uint32_t(pc);
        // The innermost loop takes most back edges: its watch is kept at hand (references to
        // an unordered_map's elements survive rehashing).
        if (key != lastLoopKey_ || !lastLoop_) {
            const auto [it, first] = loops_.try_emplace(key, LoopWatch{now, std::nullopt, 0});
            lastLoopKey_ = key;
            lastLoop_ = &it->second;
            if (first) return;
        }
        LoopWatch& w = *lastLoop_;
        if (!(w.last == now)) {
            // The common case, a loop that counts: no need to look at the frame.
            w.last = now;
            w.frame.reset();
            w.unchangedPasses = 0;
            return;
        }
        const FrameMap frame = frameMap();
        // A pass whose frame was not taken counts as one that changed it.
        w.unchangedPasses = w.frame && *w.frame == frame ? w.unchangedPasses + 1 : 0;
        w.frame = frame;
        if (w.unchangedPasses >= 2)
            fail(1, "program does not terminate: this loop ran twice without changing a parameter, the "
                    "position or the tool, so it would run forever",
                 std::string(line_.substr(0, 40)));
    }

    /// Writes a parameter, counting the writes that change it (LoopState).
    void store(double& slot, double v) {
        if (!(slot == v)) ++paramWrites_;
        slot = v;
    }
    void storeNamed(std::unordered_map<std::string, double>& table, const std::string& name, double v) {
        const auto [it, created] = table.try_emplace(name, v);
        if (created) ++paramWrites_;
        else store(it->second, v);
    }

    // ---- parameters ----
    double getParam(const ParamRef& r) {
        if (r.name.empty()) {
            switch (r.index) {
            case 5400: return double(toolInSpindle_);
            case 5420: case 5421: case 5422: {
                const Vec3 p = toProgram(mpos_);
                return p[r.index - 5420] / units_;
            }
            default: return params_[std::size_t(r.index)];
            }
        }
        if (!frames_.empty() && r.name[0] != '_') {
            auto it = frames_.back().locals.find(r.name);
            if (it != frames_.back().locals.end()) return it->second;
        }
        auto it = named_.find(r.name);
        if (it == named_.end()) fail(r.col, "named parameter not defined", "#<" + r.name + ">");
        return it->second;
    }
    void setParam(const ParamRef& r, double v) {
        if (!r.name.empty()) {
            if (!frames_.empty() && !frames_.back().fanuc && r.name[0] != '_')
                storeNamed(frames_.back().locals, r.name, v);
            else
                storeNamed(named_, r.name, v);
            return;
        }
        if (r.index == 3000)
            fail(r.col, "the program raises alarm #3000 = " + std::to_string(v), "#3000");
        store(params_[std::size_t(r.index)], v);
    }

    ParamRef readParamRef(std::size_t& i) {
        // at '#'
        ParamRef r;
        r.col = int(i) + 1;
        ++i;
        i = skipSpaces(line_, i);
        if (i < line_.size() && line_[i] == '<') {
            const std::size_t close = line_.find('>', i);
            if (close == std::string_view::npos)
                fail(int(i) + 1, "unterminated parameter name", std::string(line_.substr(i, 40)));
            for (std::size_t t = i + 1; t < close; ++t)
                if (line_[t] != ' ' && line_[t] != '\t')
                    r.name += char(std::tolower(static_cast<unsigned char>(line_[t])));
            if (r.name.empty()) fail(int(i) + 1, "empty parameter name", "#<>");
            i = close + 1;
            return r;
        }
        const double v = readRealValue(i);
        const double rounded = std::nearbyint(v);
        if (std::abs(v - rounded) > 1e-4 || rounded < 1 || rounded >= kNumParams)
            fail(r.col, "parameter number out of range (1.." + std::to_string(kNumParams - 1) + ")",
                 tokenAt(r.col));
        r.index = int(rounded);
        return r;
    }

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

    double readRealValue(std::size_t& i) {
        const Nesting nesting(*this, depth_, i);
        i = skipSpaces(line_, i);
        if (i >= line_.size()) fail(int(i) + 1, "missing value at end of line", tokenAt(int(i)));
        const char c = line_[i];
        if (c == '[') {
            const int col = int(i) + 1;
            ++i;
            const double v = parseExpression(i, 0);
            i = skipSpaces(line_, i);
            if (i >= line_.size() || line_[i] != ']')
                fail(col, "unclosed '[' in expression", std::string(line_.substr(std::size_t(col - 1), 40)));
            ++i;
            return v;
        }
        if (c == '#') {
            ParamRef r = readParamRef(i);
            return getParam(r);
        }
        if (c == '-' || c == '+') {
            ++i;
            const double v = readRealValue(i);
            return c == '-' ? -v : v;
        }
        if ((c >= '0' && c <= '9') || c == '.') {
            double v;
            const std::size_t start = i;
            if (!detail::parseUnsignedDecimal(line_, i, v))
                fail(int(start) + 1, "bad number", tokenAt(int(start) + 1));
            if (i < line_.size() && (line_[i] == '.' ))
                fail(int(start) + 1, "bad number", tokenAt(int(start) + 1));
            return v;
        }
        if (std::isalpha(static_cast<unsigned char>(c))) return readFunction(i);
        fail(int(i) + 1, "expected a number, parameter or [expression]", tokenAt(int(i) + 1));
    }

    double readFunction(std::size_t& i) {
        const std::size_t start = i;
        std::string name;
        while (i < line_.size() && std::isalpha(static_cast<unsigned char>(line_[i])))
            name += upper(line_[i++]);
        const int col = int(start) + 1;
        i = skipSpaces(line_, i);
        if (i >= line_.size() || line_[i] != '[')
            fail(col, "expected a number (unknown word or function)", tokenAt(col));
        if (name == "EXISTS") {
            ++i;
            i = skipSpaces(line_, i);
            bool exists = false;
            if (i < line_.size() && line_[i] == '#') {
                ParamRef r = readParamRef(i);
                if (r.name.empty())
                    exists = true;
                else
                    exists = named_.count(r.name) ||
                             (!frames_.empty() && frames_.back().locals.count(r.name));
            }
            i = skipSpaces(line_, i);
            if (i >= line_.size() || line_[i] != ']') fail(col, "unclosed EXISTS[", tokenAt(col));
            ++i;
            return exists ? 1.0 : 0.0;
        }
        const double a = readRealValue(i);
        auto domain = [&](bool ok) {
            if (!ok) fail(col, "argument of " + name + " out of its domain", tokenAt(col, 40));
        };
        if (name == "ATAN") {
            i = skipSpaces(line_, i);
            if (i >= line_.size() || line_[i] != '/')
                fail(col, "ATAN needs the form ATAN[y]/[x]", tokenAt(col, 40));
            ++i;
            i = skipSpaces(line_, i);
            if (i >= line_.size() || line_[i] != '[')
                fail(col, "ATAN needs the form ATAN[y]/[x]", tokenAt(col, 40));
            const double x = readRealValue(i);
            return std::atan2(a, x) / kDeg;
        }
        if (name == "ABS") return std::abs(a);
        if (name == "ACOS") return domain(a >= -1 && a <= 1), std::acos(a) / kDeg;
        if (name == "ASIN") return domain(a >= -1 && a <= 1), std::asin(a) / kDeg;
        if (name == "COS") return std::cos(a * kDeg);
        if (name == "SIN") return std::sin(a * kDeg);
        if (name == "TAN") return std::tan(a * kDeg);
        if (name == "EXP") return std::exp(a);
        if (name == "FIX") return std::floor(a);
        if (name == "FUP") return std::ceil(a);
        if (name == "ROUND") return std::round(a);
        if (name == "LN") return domain(a > 0), std::log(a);
        if (name == "SQRT") return domain(a >= 0), std::sqrt(a);
        fail(col, "unknown function " + name, tokenAt(col));
    }

    /// Binary operator at i: returns precedence (1 lowest .. 5 highest) and code, 0 if none.
    int peekOperator(std::size_t i, int& code, std::size_t& len) {
        i = skipSpaces(line_, i);
        if (i >= line_.size()) return 0;
        const char c = line_[i];
        len = 1;
        if (c == '*' && i + 1 < line_.size() && line_[i + 1] == '*') { len = 2; code = 'P'; return 5; }
        if (c == '*') { code = '*'; return 4; }
        if (c == '/') { code = '/'; return 4; }
        if (c == '+') { code = '+'; return 3; }
        if (c == '-') { code = '-'; return 3; }
        if (!std::isalpha(static_cast<unsigned char>(c))) return 0;
        char w[4] = {0, 0, 0, 0};
        std::size_t n = 0;
        while (n < 3 && i + n < line_.size() && std::isalpha(static_cast<unsigned char>(line_[i + n])))
            w[n] = upper(line_[i + n]), ++n;
        const std::string_view word(w, n);
        len = n;
        struct Op { const char* name; int code; int prec; };
        static const Op ops[] = {{"MOD", 'M', 4}, {"EQ", 'e', 2}, {"NE", 'n', 2}, {"GT", 'g', 2},
                                 {"GE", 'G', 2},  {"LT", 'l', 2}, {"LE", 'L', 2}, {"AND", '&', 1},
                                 {"OR", '|', 1},  {"XOR", '^', 1}};
        for (const Op& op : ops) {
            const std::string_view name(op.name);
            if (word.substr(0, name.size()) == name) {
                len = name.size();
                code = op.code;
                return op.prec;
            }
        }
        return 0;
    }

    double parseExpression(std::size_t& i, int minPrec) {
        const Nesting nesting(*this, depth_, i);
        double lhs = readRealValue(i);
        while (true) {
            int code = 0;
            std::size_t len = 0;
            const int prec = peekOperator(i, code, len);
            if (prec == 0 || prec <= minPrec) {
                if (prec == 0) {
                    const std::size_t j = skipSpaces(line_, i);
                    if (j < line_.size() && line_[j] != ']')
                        fail(int(j) + 1, "expected an operator or ']'", tokenAt(int(j) + 1));
                }
                return lhs;
            }
            i = skipSpaces(line_, i);
            const int opCol = int(i) + 1;
            i += len;
            // ** is right-associative; others left.
            const double rhs = parseExpression(i, code == 'P' ? prec - 1 : prec);
            switch (code) {
            case 'P': lhs = std::pow(lhs, rhs); break;
            case '*': lhs *= rhs; break;
            case '/':
                if (rhs == 0.0) fail(opCol, "division by zero", std::string(line_.substr(std::size_t(opCol - 1), 24)));
                lhs /= rhs;
                break;
            case 'M':
                if (rhs == 0.0) fail(opCol, "MOD by zero", std::string(line_.substr(std::size_t(opCol - 1), 24)));
                lhs = lhs - std::floor(lhs / rhs) * rhs;
                break;
            case '+': lhs += rhs; break;
            case '-': lhs -= rhs; break;
            case 'e': lhs = lhs == rhs; break;
            case 'n': lhs = lhs != rhs; break;
            case 'g': lhs = lhs > rhs; break;
            case 'G': lhs = lhs >= rhs; break;
            case 'l': lhs = lhs < rhs; break;
            case 'L': lhs = lhs <= rhs; break;
            case '&': lhs = (lhs != 0.0) && (rhs != 0.0); break;
            case '|': lhs = (lhs != 0.0) || (rhs != 0.0); break;
            case '^': lhs = (lhs != 0.0) != (rhs != 0.0); break;
            }
            if (!std::isfinite(lhs)) fail(opCol, "expression overflows", std::string(line_.substr(std::size_t(opCol - 1), 24)));
        }
    }

    // ---- block parsing ----
    /// @return false when the line has nothing to execute (e.g. a Fanuc IF that is false).
    bool parseBlock(Block& b, int& fanucJump, SourceFile& f, int pc) {
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

    // ---- modal groups ----
    static int gGroup(int code) {
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
        case 430: case 431: case 432: case 490: return 8;
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

    int executeBlock(Block& b, SourceFile& f, int pc) {
        // Modal group checks.
        int groupCode[20];
        std::fill(std::begin(groupCode), std::end(groupCode), -1);
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
            if (groupCode[grp] >= 0 && !(grp == 0 && (code == 530 || groupCode[grp] == 530)))
                fail(b.gcol[k], "two G-codes from one modal group (group " + std::to_string(grp) + ")",
                     tokenAt(b.gcol[k]));
            if (groupCode[grp] < 0 || code != 530) groupCode[grp] = code;
            if (grp == 1) motion = code, motionCol = b.gcol[k];
            if (grp == 0 && code != 530) nonModal = code, nonModalCol = b.gcol[k];
        }
        (void)nonModalCol;
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
            if (groupCode[5] == 930) warn("G93 inverse-time feed: feeds are not simulated", "G93");
            else if (groupCode[5] == 950) warn("G95 feed per revolution: feeds are not simulated", "G95");
        }
        if (b.has('F')) { b.use('F'); hot(kHotFeed, "feed rate F is not simulated (ignored)"); }
        if (b.has('S')) { b.use('S'); hot(kHotSpeed, "spindle speed S is not simulated (ignored)"); }
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
            default:
                warn("unknown M-code M" + std::to_string(m) + " ignored", "M" + std::to_string(m), col);
            }
        }
        // 4. Dwell.
        if (nonModal == 40) {
            if (b.has('P')) b.use('P');
            warn("dwell G4 ignored (time is not simulated)", "dwell");
        }
        // 5. Plane, units, cutter compensation, tool length offsets.
        if (groupCode[2] >= 0) {
            const int p = groupCode[2];
            if (p != 170 && p != 180 && p != 190) fail(0, "UVW planes are not supported", "G" + codeText(p));
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
        if (groupCode[8] >= 0) {
            if (b.has('H')) b.use('H');
            if (groupCode[8] == 431 || groupCode[8] == 432)
                for (char c : {'X', 'Y', 'Z', 'I', 'J', 'K'})
                    if (b.has(c) && groupCode[1] < 0 && motion < 0) b.use(c);
            if (groupCode[8] != 490)
                diags_.note(where(), "tool length offset: the simulated tip follows the programmed "
                                     "point",
                            "tlo");
        }
        // 6. Coordinate system, path control, distance modes, retract mode.
        if (groupCode[12] >= 0) setCoordSystem(groupCode[12]);
        if (groupCode[13] >= 0) {
            if (b.has('P')) b.use('P');
            if (b.has('Q')) b.use('Q');
            warn("path control G61/G64 ignored (exact path is simulated)", "path control");
        }
        if (groupCode[3] >= 0) absolute_ = groupCode[3] == 900;
        if (groupCode[4] >= 0) arcAbsolute_ = groupCode[4] == 901;
        if (groupCode[10] >= 0) retract_ = groupCode[10];
        // 7. Tilted work plane.
        bool axisConsumed = false;
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
            axisConsumed = executeNonModal(nonModal, b, motion);
        }
        // 9. Motion.
        if (motion >= 0) {
            if (motion != motion_ && motion >= 730 && motion <= 890) {
                // new cycle: R and Z are required
            }
            if (motion == 800) {
                motion_ = 800;
                cycleIlFlag_ = false;
            }
        }
        const bool anyAxis = b.has('X') || b.has('Y') || b.has('Z') || b.has('A') || b.has('B') ||
                             b.has('C') || b.has('U') || b.has('V') || b.has('W');
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
        } else if (!axisConsumed && (motion == 20 || motion == 30)) {
            fail(motionCol, "arc without end point (no axis words)", tokenAt(motionCol));
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

    static char firstAxisLetter(const Block& b) {
        for (char c : {'X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'})
            if (b.has(c)) return c;
        return 'X';
    }

    static std::string codeText(int code) {
        std::string s = std::to_string(code / 10);
        if (code % 10) s += "." + std::to_string(code % 10);
        return s;
    }

    int callFanuc(Block& b, int pc) {
        if (!b.has('P')) fail(0, "M98 without P program number", "M98");
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
            fail(0, "subprogram calls nested deeper than " + std::to_string(opt_.maxCallDepth) +
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

    int returnFanuc(SourceFile&, int) {
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

    // ---- coordinates ----
    Vec3 offset() const { return g5x_[std::size_t(coordSys_)] + g92_; }
    Vec3 toMachine(const Vec3& p) const {
        return offset() + (twp_ ? twpOrigin_ + twpRot_ * p : p);
    }
    Vec3 toProgram(const Vec3& m) const {
        const Vec3 w = m - offset();
        return twp_ ? twpRot_.transposeTimes(w - twpOrigin_) : w;
    }

    void setCoordSystem(int code) {
        static const int codes[] = {540, 550, 560, 570, 580, 590, 591, 592, 593};
        for (int k = 0; k < 9; ++k)
            if (codes[k] == code) coordSys_ = k;
        store(params_[5220], coordSys_ + 1);
    }

    void changeTool(int tool) {
        if (tool == toolInSpindle_ && haveChanged_) return;
        haveChanged_ = true;
        toolInSpindle_ = tool;
        ToolChange tc;
        tc.moveIndex = out_.path.moves.size();
        tc.tool = tool;
        tc.source = {files_[std::size_t(curFile_)]->pathIndex, curLineNo_};
        out_.path.toolChanges.push_back(tc);
    }

    void emit(const Vec3& target, bool rapid) {
        if (!std::isfinite(target.x) || !std::isfinite(target.y) || !std::isfinite(target.z))
            fail(0, "move to a non-finite position", std::string(line_.substr(0, 40)));
        if (!withinReach(target))
            fail(0, "move to " + detail::formatPoint(target) + " mm, beyond the 1e9 mm a program may reach",
                 std::string(line_.substr(0, 40)));
        if (out_.path.moves.size() >= opt_.maxMoves)
            fail(0, detail::tooManyMoves(opt_.maxMoves, opt_.maxMovesReason), std::string(line_.substr(0, 40)));
        for (int a = 0; a < 3; ++a) known_[a] = known_[a] || target[a] != mpos_[a];
        if (!positionKnown_) {
            // Where the machine starts is not in the program: moves until X, Y and Z have all
            // been given only establish the position, rather than sweep from a guessed origin.
            positionKnown_ = known_[0] && known_[1] && known_[2];
            warn("the start position is unknown until X, Y and Z are all programmed: this move only sets "
                 "the position and is not simulated",
                 "unknown start");
            mpos_ = target;
            return;
        }
        Move m;
        m.start = mpos_;
        m.end = target;
        m.axis = axis_;
        m.tool = toolInSpindle_;
        m.rapid = rapid;
        m.source = {files_[std::size_t(curFile_)]->pathIndex, curLineNo_};
        out_.path.moves.push_back(m);
        mpos_ = target;
    }

    /// The program-frame target of the axis words (unspecified axes keep their place).
    Vec3 targetOf(Block& b, const Vec3& from, bool incremental) {
        Vec3 t = from;
        static const char letters[3] = {'X', 'Y', 'Z'};
        for (int a = 0; a < 3; ++a)
            if (b.has(letters[a])) {
                const double v = b.get(letters[a]) * units_;
                t[a] = incremental ? from[a] + v : v;
                known_[a] = true;
            }
        checkRotary(b, incremental);
        return t;
    }

    void checkRotary(Block& b, bool incremental) {
        for (int a = 0; a < 3; ++a) {
            const char c = char('A' + a);
            if (!b.has(c)) continue;
            const double v = b.get(c);
            const double target = incremental ? rotary_[a] + v : v;
            if (std::abs(target - rotary_[a]) > 1e-9)
                fail(b.col[a], "A/B/C rotary axes are not supported yet (rotary motion)", tokenAt(b.col[a]));
        }
        for (char c : {'U', 'V', 'W'})
            if (b.has(c)) fail(b.col[c - 'A'], "U/V/W axes are not supported", tokenAt(b.col[c - 'A']));
    }

    // ---- non-modal codes ----
    bool executeNonModal(int code, Block& b, int motion) {
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
            if (!b.has('L')) fail(0, "G10 without L", "G10");
            const int l = int(std::lround(b.get('L')));
            if (l == 1 || l == 10 || l == 11) {
                for (char c : {'P', 'X', 'Y', 'Z', 'R', 'I', 'J', 'Q', 'D'})
                    if (b.has(c)) b.use(c);
                warn("G10 L" + std::to_string(l) + " (tool table edit) ignored", "G10 L1");
                return true;
            }
            if (l != 2 && l != 20) fail(b.col['L' - 'A'], "unsupported G10 L" + std::to_string(l), tokenAt(b.col['L' - 'A']));
            if (!b.has('P')) fail(0, "G10 L" + std::to_string(l) + " without P", "G10");
            const int p = int(std::lround(b.get('P')));
            if (p < 0 || p > 9) fail(b.col['P' - 'A'], "G10 P out of range 0..9", tokenAt(b.col['P' - 'A']));
            const int cs = p == 0 ? coordSys_ : p - 1;
            if (b.has('R') && b.get('R') != 0.0)
                fail(b.col['R' - 'A'], "G10 R (XY rotation of a coordinate system) is not supported", tokenAt(b.col['R' - 'A']));
            checkRotary(b, false);
            static const char letters[3] = {'X', 'Y', 'Z'};
            if (l == 20 && twp_) fail(0, "G10 L20 with an active G68.2 is not supported", "G10");
            for (int a = 0; a < 3; ++a) {
                if (!b.has(letters[a])) continue;
                const double v = b.get(letters[a]) * units_;
                if (l == 2)
                    g5x_[std::size_t(cs)][a] = v;
                else
                    g5x_[std::size_t(cs)][a] = mpos_[a] - g92_[a] - v;
                store(params_[std::size_t(5221 + 20 * cs + a)], g5x_[std::size_t(cs)][a] / units_);
            }
            return true;
        }
        case 280: case 300: {  // G28, G30: via the given point to the stored position
            axisConflict();
            const int base = code == 280 ? 5161 : 5181;
            Vec3 home(params_[std::size_t(base)], params_[std::size_t(base + 1)], params_[std::size_t(base + 2)]);
            home *= units_;
            const Vec3 pp = toProgram(mpos_);
            if (anyXYZ) {
                const Vec3 via = targetOf(b, pp, !absolute_);
                emit(toMachine(via), true);
                Vec3 end = mpos_;
                for (int a = 0; a < 3; ++a)
                    if (b.has(char('X' + a))) end[a] = home[a];
                emit(end, true);
            } else {
                checkRotary(b, !absolute_);
                emit(home, true);
            }
            return true;
        }
        case 281: case 301: {
            const int base = code == 281 ? 5161 : 5181;
            for (int a = 0; a < 3; ++a) store(params_[std::size_t(base + a)], mpos_[a] / units_);
            return false;
        }
        case 520: case 920: {  // G52, G92
            axisConflict();
            checkRotary(b, false);
            static const char letters[3] = {'X', 'Y', 'Z'};
            const Vec3 before = g92_;
            for (int a = 0; a < 3; ++a) {
                if (!b.has(letters[a])) continue;
                const double v = b.get(letters[a]) * units_;
                if (code == 920)
                    g92_[a] = mpos_[a] - g5x_[std::size_t(coordSys_)][a] - v;
                else
                    g92_[a] = v;
                store(params_[std::size_t(5211 + a)], g92_[a] / units_);
            }
            // Offsets that change under a tilted plane would need the plane's frame.
            if (twp_ && g92_ != before)
                fail(0, "G52/G92 changing the offset under an active G68.2 is not supported",
                     "G" + codeText(code));
            return true;
        }
        case 921: case 922:
            g92_ = Vec3(0.0);
            if (code == 921)
                for (int a = 0; a < 3; ++a) store(params_[std::size_t(5211 + a)], 0.0);
            return false;
        case 923:
            for (int a = 0; a < 3; ++a) g92_[a] = params_[std::size_t(5211 + a)] * units_;
            return false;
        default:
            return false;
        }
    }

    // ---- tilted work plane (G68.2 / G53.x / G69) ----
    void defineTwp(Block& b) {
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
        if (twp_) fail(0, "G68.2 while a tilted plane is active: cancel it with G69 first", "G68.2");
        twp_ = true;
        twpRot_ = r;
        twpOrigin_ = origin;
        diags_.note(where(), "G68.2 tilted work plane: coordinates are rotated; the tool axis "
                             "follows on G53.1/G53.3/G53.6",
                    "twp");
    }

    void orientTool(int code, Block& b) {
        if (!twp_) fail(0, "G" + codeText(code) + " without an active G68.2 plane", "G" + codeText(code));
        if (b.has('P')) b.use('P');
        axis_ = glm::normalize(twpRot_ * Vec3(0, 0, 1));
        if (code == 533) {
            const Vec3 pp = toProgram(mpos_);
            const Vec3 t = targetOf(b, pp, false);
            emit(toMachine(t), true);
        }
    }

    void cancelTwp() {
        twp_ = false;
        twpRot_ = Mat3{};
        twpOrigin_ = Vec3(0.0);
        axis_ = baseAxis_;
        coordSys_ = 0;
    }

    // ---- motion ----
    void executeMotion(int mode, Block& b, bool g53, int motionCol) {
        switch (mode) {
        case 0: case 10: {
            Vec3 target;
            if (g53) {
                if (!absolute_ && (b.has('X') || b.has('Y') || b.has('Z')))
                    fail(0, "G53 in incremental mode (G91)", "G53");
                target = mpos_;
                static const char letters[3] = {'X', 'Y', 'Z'};
                for (int a = 0; a < 3; ++a)
                    if (b.has(letters[a])) target[a] = b.get(letters[a]) * units_;
                checkRotary(b, false);
            } else {
                target = toMachine(targetOf(b, toProgram(mpos_), !absolute_));
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

    void arc(bool clockwise, Block& b, int motionCol) {
        int p0, p1, p2;
        char o0, o1;
        if (plane_ == 17) { p0 = 0; p1 = 1; p2 = 2; o0 = 'I'; o1 = 'J'; }
        else if (plane_ == 18) { p0 = 2; p1 = 0; p2 = 1; o0 = 'K'; o1 = 'I'; }
        else { p0 = 1; p1 = 2; p2 = 0; o0 = 'J'; o1 = 'K'; }
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
        if (rForm) {
            if (b.has(o0) || b.has(o1)) fail(b.col['R' - 'A'], "arc with both R and I/J/K", tokenAt(b.col['R' - 'A']));
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
            if (!b.has(o0) && !b.has(o1))
                fail(arcCol, std::string("arc without ") + o0 + "/" + o1 + " or R", tokenAt(motionCol));
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
        if (std::abs(rs - re) > kArcRadiusAbsTol && std::abs(rs - re) > kArcRadiusRelTol * rs)
            fail(rForm ? b.col['R' - 'A'] : motionCol,
                 "radius to end of arc differs from radius to start (" + std::to_string(re) + " vs " +
                     std::to_string(rs) + " mm)",
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
        for (const Vec3& p : arcPts_) emit(toMachine(p), false);
    }

    static bool samePlanePoint(const Vec3& a, const Vec3& b, int p0, int p1) {
        return std::abs(a[p0] - b[p0]) < 1e-9 && std::abs(a[p1] - b[p1]) < 1e-9;
    }

    // ---- canned cycles ----
    void cycle(int mode, Block& b) {
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
        else fail(0, std::string("canned cycle without ") + cl + " depth", "G" + codeText(mode));
        double rWord;
        if (b.has('R')) rWord = b.get('R') * units_;
        else if (!newCycle) rWord = cycleR_;
        else fail(0, "canned cycle without R plane", "G" + codeText(mode));
        double q = cycleQ_;
        if (mode == 730 || mode == 830) {
            if (b.has('Q')) q = b.get('Q') * units_;
            else if (newCycle) fail(0, "G73/G83 without Q peck depth", "G" + codeText(mode));
            if (!(q > 0)) fail(b.col['Q' - 'A'], "Q peck depth must be positive", tokenAt(b.col['Q' - 'A']));
        }
        if (mode == 820 || mode == 890) {
            if (b.has('P')) b.use('P');
            else if (newCycle) fail(0, "G82/G89 without P dwell", "G" + codeText(mode));
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
            cycleIlFlag_ = true;
        }
        double oldcc = cycleIl_;
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
        if (oldcc < r) {
            emit(at(pp[ia], pp[ib], r), true);
            oldcc = r;
        }
        const double clear = retract_ == 990 ? r : oldcc;
        for (long rep = 0; rep < repeats; ++rep) {
            aa += da;
            bb += db;
            emit(at(aa, bb, oldcc), true);
            if (oldcc != r) emit(at(aa, bb, r), true);
            switch (mode) {
            case 810: case 820:
                emit(at(aa, bb, cc), false);
                emit(at(aa, bb, clear), true);
                break;
            case 850: case 890:
                emit(at(aa, bb, cc), false);
                emit(at(aa, bb, r), false);
                if (clear != r) emit(at(aa, bb, clear), true);
                break;
            case 830: {
                double depth = r - q;
                std::size_t guard = 0;
                for (; depth > cc; depth -= q) {
                    if (++guard > opt_.maxArcSegments) fail(0, "too many pecks", "Q");
                    emit(at(aa, bb, depth), false);
                    emit(at(aa, bb, r), true);
                    emit(at(aa, bb, depth + kG83RapidDelta), true);
                }
                emit(at(aa, bb, cc), false);
                emit(at(aa, bb, clear), true);
                break;
            }
            case 730: {
                double depth = r - q;
                std::size_t guard = 0;
                for (; depth > cc; depth -= q) {
                    if (++guard > opt_.maxArcSegments) fail(0, "too many pecks", "Q");
                    emit(at(aa, bb, depth), false);
                    emit(at(aa, bb, depth + kG73Clearance), true);
                }
                emit(at(aa, bb, cc), false);
                emit(at(aa, bb, clear), true);
                break;
            }
            }
            oldcc = clear;
        }
        cycleActive_ = true;
        cycleCc_ = ccWord;
        cycleR_ = rWord;
        cycleQ_ = q;
    }

    const GcodeOptions& opt_;
    Program& out_;
    detail::DiagnosticCollector diags_;
    std::array<std::size_t, kHotCount> hot_;
    std::vector<std::unique_ptr<SourceFile>> files_;
    std::unordered_map<std::string, Sub> subs_;
    std::unordered_map<std::string, Sub> programs_;
    std::vector<Frame> frames_;
    std::unordered_map<int, long> topCounters_;
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
    Vec3 g92_{0.0};
    Vec3 mpos_{0.0};
    /// Which coordinates of the position the program has set, and whether all three are.
    bool known_[3] = {false, false, false};
    bool positionKnown_ = false;
    double rotary_[3] = {0, 0, 0};
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
};

}  // namespace

std::vector<ToolTableEntry> parseLinuxCncToolTable(std::string_view text,
                                                   const std::string& fileName, bool inches) {
    std::vector<ToolTableEntry> out;
    const double scale = inches ? kInch : 1.0;
    std::size_t pos = 0;
    int lineNo = 0;
    while (pos <= text.size()) {
        std::size_t e = text.find('\n', pos);
        if (e == std::string_view::npos) e = text.size();
        std::string_view line = text.substr(pos, e - pos);
        ++lineNo;
        ToolTableEntry entry;
        entry.line = lineNo;
        bool any = false;
        std::size_t i = 0;
        while (i < line.size()) {
            const char c = upper(line[i]);
            if (c == ' ' || c == '\t' || c == '\r') { ++i; continue; }
            if (c == ';') {
                entry.comment = std::string(line.substr(i + 1));
                break;
            }
            const int col = int(i) + 1;
            if (c < 'A' || c > 'Z')
                throw ParseError({fileName, lineNo, col}, "unexpected character in tool table", std::string(1, line[i]));
            ++i;
            bool neg = false;
            if (i < line.size() && (line[i] == '-' || line[i] == '+')) neg = line[i++] == '-';
            double v;
            if (!detail::parseUnsignedDecimal(line, i, v))
                throw ParseError({fileName, lineNo, col}, "tool table word without a number", std::string(line.substr(std::size_t(col - 1), 12)));
            if (neg) v = -v;
            any = true;
            switch (c) {
            case 'T': entry.tool = int(v); break;
            case 'P': entry.pocket = int(v); break;
            case 'D': entry.diameter = v * scale; break;
            case 'Z': entry.zOffset = v * scale; break;
            default: break;  // other offsets and lathe data
            }
        }
        if (any) {
            if (entry.tool <= 0 && entry.pocket == 0)
                throw ParseError({fileName, lineNo, 1}, "tool table entry without T", std::string(line.substr(0, 40)));
            out.push_back(entry);
        }
        if (e == text.size()) break;
        pos = e + 1;
    }
    return out;
}

Program parseGcode(std::string_view text, const std::string& fileName,
                   const GcodeOptions& options) {
    Program program;
    Interpreter interp(options, program);
    if (!options.toolTableFile.empty()) interp.loadToolTable(options.toolTableFile);
    interp.run(fileName, std::string(text));
    interp.finish();
    return program;
}

Program readGcode(const std::string& path, const GcodeOptions& options) {
    Program program;
    Interpreter interp(options, program);
    if (!options.toolTableFile.empty()) interp.loadToolTable(options.toolTableFile);
    interp.run(path, detail::readFile(options.files, path));
    interp.finish();
    return program;
}

Program readGcodeFiles(const std::vector<std::string>& paths, const GcodeOptions& options) {
    Program program;
    Interpreter interp(options, program);
    if (!options.toolTableFile.empty()) interp.loadToolTable(options.toolTableFile);
    for (const std::string& p : paths) interp.run(p, detail::readFile(options.files, p));
    interp.finish();
    return program;
}

}  // namespace dexelmill
