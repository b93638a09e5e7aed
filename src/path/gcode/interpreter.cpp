/// @file interpreter.cpp
/// @brief Setting up the interpreter, running files, and its errors and warnings.
#include "path/gcode/interpreter.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "dexelmill/error.h"

namespace dexelmill::detail::gcode {

Interpreter::Interpreter(const GcodeOptions& options, Program& out) : opt_(options), out_(out) {
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
    if (options.machine) tcp_ = options.machine->tcpAtStart;
    if (options.startPosition) {
        mpos_ = *options.startPosition;
        known_[0] = known_[1] = known_[2] = positionKnown_ = everKnown_ = true;
    }
}

void Interpreter::run(std::string name, std::string text) {
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

void Interpreter::finish() {
    // LinuxCNC keeps a subroutine in a file of its own, which the program that calls it finds.
    // Run alone, such a file makes no moves; the user learns why where the subroutine stands.
    if (out_.path.moves.empty()) {
        std::vector<std::pair<const std::string*, const Sub*>> uncalled;
        for (const auto& [label, sub] : subs_)
            if (!sub.called) uncalled.emplace_back(&label, &sub);
        std::sort(uncalled.begin(), uncalled.end(), [](const auto& a, const auto& b) {
            return std::pair(a.second->file, a.second->start) < std::pair(b.second->file, b.second->start);
        });
        for (const auto& [label, sub] : uncalled)
            diags_.warn({files_[std::size_t(sub->file)]->name(), SourceFile::lineNumber(sub->start), 1},
                        "subroutine o<" + *label +
                            "> is defined but never called; a file of subroutines makes no moves on its "
                            "own: run the program that calls it");
    }
    diags_.appendTo(out_.diagnostics);
}

void Interpreter::fail(int col, const std::string& message, std::string offending) const {
    throw ParseError(where(col), message, std::move(offending));
}

SourceLocation Interpreter::where(int col) const {
    SourceLocation loc;
    if (curFile_ >= 0) {
        loc.file = files_[curFile_]->name();
        loc.line = curLineNo_;
    }
    loc.column = col;
    return loc;
}

std::string Interpreter::tokenAt(int col, std::size_t maxLen) const {
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

void Interpreter::warn(const std::string& message, const std::string& key, int col) {
    diags_.warn(where(col), message, key);
}

void Interpreter::hot(HotKind kind, const char* message, int col) {
    if (hot_[kind] == kNone)
        hot_[kind] = diags_.warn(where(col), message);
    else
        diags_.repeat(hot_[kind]);
}

}  // namespace dexelmill::detail::gcode
