#include "job/detail/tools.h"

#include <map>
#include <set>
#include <sstream>

#include "dexelmill/error.h"
#include "dexelmill/path/tool_table.h"
#include "dexelmill/tool/builders.h"

namespace dexelmill {

namespace {

/// A tool table's entry as a tool: a flat end mill of its diameter (`unit` mm per table unit),
/// with warnings for what the table says that the job does not honour.
Tool tableTool(const ToolTableEntry& e, double unit, std::vector<Diagnostic>& notes) {
    const std::string t = "T" + std::to_string(e.number), spec = "--tool " + std::to_string(e.number) + "=SPEC";
    if (!e.diameter) throw ParseError(e.where, t + " has no diameter (D) in the tool table; give one, or " + spec);
    if (*e.diameter == 0.0)
        throw ParseError(e.where, t + " has diameter 0 in the tool table, so it cannot cut; give one, or " + spec);
    std::optional<Tool> tool;
    try {
        tool.emplace(flatEndMill(*e.diameter * unit));
    } catch (const Error& err) {
        throw ParseError(e.where, t + " in the tool table: " + err.what());
    }
    notes.push_back({Diagnostic::Severity::Warning, e.where,
                     t + " is cut as a " + tool->description() + ": a tool table gives no shape; " + spec +
                         " gives it"});
    const auto words = [](const char* what, const std::string& letters) {
        const bool one = letters.size() == 1;
        return std::string(what) + (one ? " " : "s ") + letters + (one ? " is" : " are");
    };
    if (!e.offsets.empty())
        notes.push_back({Diagnostic::Severity::Warning, e.where,
                         t + "'s " + words("offset", e.offsets) +
                             " not simulated: the program's positions are taken as the tool tip's"});
    if (!e.latheWords.empty())
        notes.push_back({Diagnostic::Severity::Warning, e.where,
                         t + "'s " + words("lathe word", e.latheWords) + " not simulated (a milling tool has none)"});
    return *tool;
}

}  // namespace

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
    std::map<int, ToolTableEntry> fromTable;
    if (!o.toolTable.empty())
        for (ToolTableEntry& e : readToolTable(o.toolTable)) fromTable.emplace(e.number, std::move(e));
    bool tableUsed = false;
    for (int n : used) {
        if (table.count(n)) continue;
        const SourceLocation at = program.path.where(firstUse[n]);
        // T0 selects no tool, so a table does not serve the moves before a tool is selected.
        if (const auto entry = fromTable.find(n); n != 0 && entry != fromTable.end()) {
            table.insert_or_assign(n, tableTool(entry->second, o.toolTableUnit, program.diagnostics));
            tableUsed = true;
            continue;
        }
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
    // These warnings are about options, not a place in a file. (A named location rather than a
    // braced temporary also keeps GCC 12 from a false -Wmaybe-uninitialized on its string.)
    const SourceLocation options;
    // A --tool N that cut in place of the undefined numbers is used, under another number.
    for (const auto& [n, t] : o.tools)
        if (!used.count(n) && standInUsed != n && !program.path.moves.empty())
            program.diagnostics.push_back({Diagnostic::Severity::Warning, options,
                                           "--tool " + std::to_string(n) + "=... (" + t.description() +
                                               ") is not used: no move cuts with tool " + std::to_string(n)});
    if (!o.toolTable.empty() && !tableUsed && !program.path.moves.empty())
        program.diagnostics.push_back({Diagnostic::Severity::Warning, options,
                                       "--tool-table " + o.toolTable +
                                           " is not used: no tool the program calls is taken from it"});
    if (o.defaultTool && !defaultUsed && !program.path.moves.empty())
        program.diagnostics.push_back({Diagnostic::Severity::Warning, options,
                                       "--tool without a number (" + o.defaultTool->description() +
                                           ") is not used: it serves only tool numbers nothing else defines, and "
                                           "the program defines every tool it calls; --tool N=SPEC replaces tool N"});
    return table;
}

}  // namespace detail

}  // namespace dexelmill
