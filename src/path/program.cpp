/// @file program.cpp
/// @brief Program::append: one program run after another.
#include <algorithm>
#include <map>

#include "dexelmill/path/toolpath.h"

namespace dexelmill {

namespace {

/// Whether two tools that share a number are one tool: the same description (which holds the
/// sizes a reader was given) and the same lengths.
bool sameTool(const Tool& a, const Tool& b) {
    return a.description() == b.description() && a.cuttingLength() == b.cuttingLength() &&
           a.totalLength() == b.totalLength();
}

}  // namespace

void Program::append(Program&& next) {
    // Numbers next defines as another tool than this program's get numbers neither uses.
    int largest = 0;
    for (const auto& [n, t] : tools) largest = std::max(largest, n);
    for (const auto& [n, t] : next.tools) largest = std::max(largest, n);
    for (const Move& m : path.moves) largest = std::max(largest, m.tool);
    for (const Move& m : next.path.moves) largest = std::max(largest, m.tool);
    std::map<int, int> renumbered;
    for (const auto& [n, t] : next.tools) {
        const auto here = tools.find(n);
        if (here == tools.end() || sameTool(here->second, t)) continue;
        renumbered[n] = ++largest;
        const std::string file = next.path.files.empty() ? std::string() : next.path.files.front();
        Diagnostic d;
        d.severity = Diagnostic::Severity::Note;
        d.where.file = file;
        d.message = "tool " + std::to_string(n) + " of this program (" + t.description() +
                    ") is another tool than the earlier programs' tool " + std::to_string(n) + " (" +
                    here->second.description() + "): its moves here are tool T" + std::to_string(largest);
        next.diagnostics.insert(next.diagnostics.begin(), std::move(d));
    }
    const auto number = [&renumbered](int n) {
        const auto it = renumbered.find(n);
        return it == renumbered.end() ? n : it->second;
    };

    const auto fileBase = std::uint32_t(path.files.size());
    const std::size_t moveBase = path.moves.size();
    for (std::string& f : next.path.files) path.files.push_back(std::move(f));
    for (Move m : next.path.moves) {
        m.source.file += fileBase;
        m.tool = number(m.tool);
        path.moves.push_back(m);
    }
    if (next.arcSag > arcSag) {
        arcSag = next.arcSag;
        arcSagSource = next.arcSagSource;
        arcSagSource.file += fileBase;
    }
    for (ToolChange c : next.path.toolChanges) {
        c.moveIndex += moveBase;
        c.source.file += fileBase;
        c.tool = number(c.tool);
        path.toolChanges.push_back(c);
    }
    for (auto& [n, t] : next.tools) tools.insert_or_assign(number(n), std::move(t));
    for (Diagnostic& d : next.diagnostics) diagnostics.push_back(std::move(d));
    if (next.statedStock) statedStock = std::move(next.statedStock);
    for (std::size_t a = 0; a < 3; ++a) rotaryRanges[a] = rotaryRanges[a].hull(next.rotaryRanges[a]);
    movesNotSimulated += next.movesNotSimulated;
}

}  // namespace dexelmill
