// The subcommands of the dexelmill tool: option declarations and the code that runs them.
#pragma once

#include <cstdio>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "dexelmill/error.h"
#include "dexelmill/geometry/affine.h"
#include "dexelmill/sweep/turning.h"

namespace dexelmill {
struct SimulateOptions;
struct Deviation;
}

namespace dexelmill::cli {

/// @brief A malformed invocation: exit code 2.
class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// @brief `dexelmill simulate` options as typed.
struct SimulateArgs {
    std::vector<std::string> inputs;
    std::string stock;
    std::vector<std::string> tools;
    std::string toolTable, toolTableUnits = "mm";
    double resolution = 0.0;
    std::string families = "xyz";
    std::string output, vdb, png, report;
    std::string design, designTransform, gougeCsv, deviationPly;
    double gougeTolerance = 0.01;
    double excessTolerance = 0.05;
    double chordTolerance = 0.001;
    double turnTolerance = kDefaultTurnTolerance;
    std::string machine;
    std::string start;
    double adaptivity = 0.0;
    int refineRounds = 0;
    double refineTolerance = 0.002;
    std::string mesher = "dexel";
    bool sharpEdges = false;
    int threads = 0;
    std::string maxMemory;
    bool quiet = false;
    /// The options the command line gave, by their long names ("--gouge-tolerance"): an option's
    /// value alone cannot say whether it is the default or was typed.
    std::set<std::string> given;
};

/// @brief `dexelmill study` options as typed.
struct StudyArgs {
    SimulateArgs job;  ///< inputs, stock and tools (its output options are unused)
    std::string caseName;
    std::string resolutions = "2,1,0.5";
    std::string familySets = "z,xyz";
    std::string csv, plot, plyDir;
    std::size_t surfacePoints = 20000;
    std::size_t samples = 100000;
};

CLI::App* addSimulate(CLI::App& app, SimulateArgs& args);
int runSimulate(const SimulateArgs& args);
/// @brief `dexelmill compare` options as typed.
struct CompareArgs {
    std::string machined, design, designTransform;
    double gougeTolerance = 0.01;
    double excessTolerance = 0.05;
    std::string ply, png, report;
    int threads = 0;
};

CLI::App* addStudy(CLI::App& app, StudyArgs& args);
int runStudy(const StudyArgs& args);
/// @brief `dexelmill info` options as typed.
struct InfoArgs {
    std::string file;
    std::string machine;
    std::string start;
};

CLI::App* addInfo(CLI::App& app, InfoArgs& args);
int runInfo(const InfoArgs& args);
/// @brief The fields of a comma-separated option value, empty ones included: "1,,2," has four, ""
/// none.
std::vector<std::string> splitAtCommas(const std::string& text);
/// @brief --start X,Y,Z (mm), as simulate and info take it: none where `text` is empty.
/// @throw UsageError unless three numbers within the 1e9 mm a program may reach.
std::optional<Vec3> parseStart(const std::string& text);
/// @brief --start's help, the same for simulate and info.
extern const char* const kStartHelp;
CLI::App* addCompare(CLI::App& app, CompareArgs& args);
int runCompare(const CompareArgs& args);

/// @brief --design-transform: TX,TY,TZ, or the rows of a 3 x 4 matrix [M | T] (12 numbers).
/// @throw UsageError for anything else.
Affine parseTransform(const std::string& text);

/// @brief Warns on stderr when --threads asks for more threads than the machine runs at once: the
/// job's arena is cut to that (job/memory.h, arenaThreads). Simulate's report carries the same
/// warning; compare and study call this.
void warnThreads(int requested);

/// @brief Where a command prints its summary: stdout, unless one of `outputs` is the file or pipe
/// stdout writes (`--report /dev/stdout | jq`, `-o part.stl > part.stl`), where it would follow or
/// cut into that output: then stderr. A terminal or /dev/null keeps it. Called before the run,
/// while the outputs are as the command found them.
std::FILE* summaryStream(const std::vector<std::string>& outputs);

/// @brief Prints a deviation's summary line on stderr.
void printDeviation(const Deviation& deviation);

/// @brief A CLI11 check that the value is a decimal number (parseDecimal), positive or (with
/// zeroAllowed) zero.
CLI::Validator numberCheck(bool zeroAllowed);

/// @brief The library's options for a typed simulate command.
/// @throw UsageError for malformed values.
SimulateOptions toOptions(const SimulateArgs& args);

/// @brief Adds simulate's input, stock and tool options to a command.
void addJobOptions(CLI::App& cmd, SimulateArgs& args, bool inputsRequired);

}  // namespace dexelmill::cli
