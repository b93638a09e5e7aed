#include "job/detail/tools.h"

#include <map>
#include <set>
#include <sstream>

#include "dexelmill/error.h"

namespace dexelmill {

std::optional<int> standInTool(const ToolTable& defined) {
    if (defined.size() != 1) return std::nullopt;
    return defined.begin()->first;
}

namespace detail {

ToolTable resolveTools(const SimulateOptions& o, Program& program) {
    ToolTable table = program.tools;
    std::set<int> used;
    std::map<int, SourceRef> firstUse;
    for (const Move& m : program.path.moves) {
        if (used.insert(m.tool).second) firstUse[m.tool] = m.source;
    }
    for (const auto& [n, t] : o.tools) {
        const auto defined = table.find(n);
        if (defined != table.end() && used.count(n))
            program.diagnostics.push_back({Diagnostic::Severity::Note, program.path.where(firstUse[n]),
                                           "--tool " + std::to_string(n) + "=... (" + t.description() +
                                               ") replaces the program's tool " + std::to_string(n) + " (" +
                                               defined->second.description() + ")"});
        table.insert_or_assign(n, t);
    }
    bool defaultUsed = false;
    // The stand-in is chosen among the tools defined, before any undefined number takes it.
    const std::optional<int> only = standInTool(table);
    std::optional<int> standInUsed;  // the tool that cut the undefined numbers, if one did
    for (int n : used) {
        if (table.count(n)) continue;
        const SourceLocation at = program.path.where(firstUse[n]);
        if (o.defaultTool) {
            table.insert_or_assign(n, *o.defaultTool);
            defaultUsed = true;
            continue;
        }
        if (only) {
            const Tool stand = table.at(*only);
            std::ostringstream msg;
            msg << (n == 0 ? std::string("moves before any tool is selected") : "tool T" + std::to_string(n) + " is not defined")
                << "; using the only tool defined, T" << *only << " (" << stand.description() << ")";
            program.diagnostics.push_back({Diagnostic::Severity::Warning, at, msg.str()});
            table.insert_or_assign(n, stand);
            standInUsed = only;
            continue;
        }
        throw ParseError(at,
                         n == 0 ? "the program moves before selecting a tool and no default tool is given; "
                                  "use --tool SPEC"
                                : "the program uses tool T" + std::to_string(n) +
                                      " but no tool of that number is defined; use --tool " + std::to_string(n) +
                                      "=SPEC");
    }
    // A --tool N that cut in place of the undefined numbers is used, under another number.
    for (const auto& [n, t] : o.tools)
        if (!used.count(n) && standInUsed != n && !program.path.moves.empty())
            program.diagnostics.push_back({Diagnostic::Severity::Warning, {},
                                           "--tool " + std::to_string(n) + "=... (" + t.description() +
                                               ") is not used: no move cuts with tool " + std::to_string(n)});
    if (o.defaultTool && !defaultUsed && !program.path.moves.empty())
        program.diagnostics.push_back({Diagnostic::Severity::Warning, {},
                                       "--tool without a number (" + o.defaultTool->description() +
                                           ") is not used: it serves only tool numbers nothing else defines, and "
                                           "the program defines every tool it calls; --tool N=SPEC replaces tool N"});
    return table;
}

}  // namespace detail

}  // namespace dexelmill
