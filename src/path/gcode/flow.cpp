/// @file flow.cpp
/// @brief Program flow: pairing O-word structures, the execution loop, O-words, subroutine calls
/// and returns, and stopping endless loops.
#include "path/gcode/interpreter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <optional>
#include <string>

#include "dexelmill/error.h"
#include "path/detail/text.h"

namespace dexelmill::detail::gcode {

void Interpreter::failAt(const SourceFile& f, int k, const std::string& message) {
    SourceLocation loc{f.name(), SourceFile::lineNumber(k), 1};
    throw ParseError(loc, message, std::string(f.line(k).substr(0, 40)));
}

int Interpreter::findForward(const SourceFile& f, int from, const std::string& label,
                             std::initializer_list<OKind> kinds, int stopAt) {
    const int n = stopAt < 0 ? f.lineCount() : stopAt;
    for (auto it = f.owords().upper_bound(from); it != f.owords().end() && it->first < n; ++it) {
        if (it->second.label != label) continue;
        for (OKind kind : kinds)
            if (it->second.kind == kind) return it->first;
    }
    return -1;
}

void Interpreter::matchStructures(SourceFile& f) {
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

void Interpreter::execute(int file) {
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

int Interpreter::executeLine(SourceFile& f, int pc) {
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

int Interpreter::executeOWord(SourceFile& f, int pc) {
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
        checkRestIsComment(pos);
        return li.match + 1;  // definition: skip the body
    case OKind::EndSub:
    case OKind::Return: {
        if (frames_.empty() || frames_.back().fanuc)
            fail(1, "endsub/return outside a subroutine call", std::string(line_.substr(0, 40)));
        pos = skipSpaces(line_, pos);
        if (pos < line_.size() && line_[pos] == '[') storeNamed(named_, "_value", readRealValue(pos));
        checkRestIsComment(pos);
        return popFrame();
    }
    case OKind::Call:
        return callSub(li, pc, pos);
    case OKind::Do:
        checkRestIsComment(pos);
        return pc + 1;
    case OKind::While:
        if (li.whileIsTail) {
            if (!condition()) return pc + 1;
            backEdge(pc);
            return li.match + 1;
        }
        return condition() ? pc + 1 : li.match + 1;
    case OKind::EndWhile:
        checkRestIsComment(pos);
        backEdge(pc);
        return li.match;  // back to the head, which tests again
    case OKind::If: {
        if (condition()) return pc + 1;
        return nextBranch(f, li.match);
    }
    case OKind::ElseIf:
        // Reached by falling out of the branch above: skip to endif. As in LinuxCNC, the condition
        // of a branch not taken is not read, and neither is what follows it.
        return li.endIf + 1;
    case OKind::Else:
        checkRestIsComment(pos);
        return li.endIf + 1;
    case OKind::EndIf:
        checkRestIsComment(pos);
        return pc + 1;
    case OKind::Repeat: {
        pos = skipSpaces(line_, pos);
        const int countCol = int(pos) + 1;
        const double v = readRealValue(pos);
        chargeRepeats(v, countCol, "repeat");
        checkRestIsComment(pos);
        const long count = std::lround(v);
        if (count <= 0) return li.match + 1;
        frameCounters()[pc] = count;
        return pc + 1;
    }
    case OKind::EndRepeat: {
        checkRestIsComment(pos);
        long& c = frameCounters()[li.match];
        if (--c > 0) return li.match + 1;
        return pc + 1;
    }
    case OKind::Break:
    case OKind::Continue: {
        checkRestIsComment(pos);
        // The innermost loop with this label around pc.
        const auto& owords = f.owords();
        for (auto it = std::make_reverse_iterator(owords.lower_bound(pc)); it != owords.rend(); ++it) {
            const auto& [k, h] = *it;
            // A loop of that label that ended before pc does not hold it: a break there would
            // jump to just after that loop's end, which may be the break itself.
            if (h.label != li.label || h.match < pc) continue;
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

int Interpreter::nextBranch(SourceFile& f, int k) {
    while (true) {
        const OWord& b = f.owords().at(k);
        curLineNo_ = SourceFile::lineNumber(k);
        line_ = f.line(k);
        std::size_t pos = skipSpaces(line_, b.argPos);
        if (b.kind == OKind::EndIf || b.kind == OKind::Else) {
            checkRestIsComment(pos);
            return k + 1;
        }
        // elseif
        if (pos >= line_.size() || line_[pos] != '[')
            fail(int(pos) + 1, "expected a [condition]", tokenAt(int(pos) + 1));
        const bool taken = readRealValue(pos) != 0.0;
        checkRestIsComment(pos);
        if (taken) return k + 1;
        k = b.match;
    }
}

void Interpreter::chargeRepeats(double count, int col, const char* what) {
    if (!std::isfinite(count)) fail(col, std::string(what) + " count is not finite", tokenAt(col));
    if (count > double(opt_.maxBlocks - std::min(blocks_, opt_.maxBlocks)))
        fail(col,
             std::string(what) + " count " + tokenAt(col) + " exceeds the " + std::to_string(opt_.maxBlocks) +
                 " blocks a program may execute",
             tokenAt(col));
}

std::unordered_map<int, long>& Interpreter::frameCounters() {
    return frames_.empty() ? topCounters_ : frames_.back().repeatCounters;
}

void Interpreter::checkRestIsComment(std::size_t pos) {
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

int Interpreter::callSub(const OWord& li, int pc, std::size_t pos) {
    auto it = subs_.find(li.label);
    if (it == subs_.end()) {
        // Where it was looked for: a user whose sub lives in LinuxCNC's SUBROUTINE_PATH learns
        // to put the file beside the program.
        const std::size_t known = files_.size();
        const std::string path = loadSubroutineFile(li.label);
        it = subs_.find(li.label);
        if (it == subs_.end())
            fail(1,
                 "call of an undefined subroutine o<" + li.label + ">: the program does not define it" +
                     (files_.size() > known ? ", nor does " + path : ", and there is no file " + path),
                 std::string(line_.substr(0, 40)));
    }
    it->second.called = true;
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

std::string Interpreter::loadSubroutineFile(const std::string& label) {
    const std::string dir = detail::directoryOf(files_[std::size_t(curFile_)]->name());
    const std::string path = detail::joinPath(dir, label + ".ngc");
    std::optional<std::string> text = detail::readFileIfAny(opt_.files, path);
    if (!text) return path;
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
    return path;
}

int Interpreter::popFrame() {
    Frame fr = std::move(frames_.back());
    frames_.pop_back();
    ++flowEpoch_;
    curFile_ = fr.file;
    if (fr.savedNumbered)
        for (int k = 1; k <= 30; ++k) store(params_[std::size_t(k)], fr.saved[std::size_t(k)]);
    return fr.returnLine;
}

Interpreter::FrameMap Interpreter::frameMap() const {
    FrameMap m;
    m[0] = toProgram(Vec3(0.0)) / units_;
    for (int a = 0; a < 3; ++a) {
        Vec3 e(0.0);
        e[a] = 1.0;
        m[std::size_t(a) + 1] = toProgram(e) / units_;
    }
    return m;
}

void Interpreter::backEdge(int pc) {
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

void Interpreter::store(double& slot, double v) {
    if (!(slot == v)) ++paramWrites_;
    slot = v;
}

void Interpreter::storeNamed(std::unordered_map<std::string, double>& table, const std::string& name, double v) {
    const auto [it, created] = table.try_emplace(name, v);
    if (created) ++paramWrites_;
    else store(it->second, v);
}

}  // namespace dexelmill::detail::gcode
