// dexelmill: the command-line tool. It parses options, calls the library and prints; nothing
// else. Exit codes: 0 success, 1 an input or processing error, 2 a usage error.
#include <algorithm>
#include <cstdio>
#include <iterator>
#include <iostream>
#include <new>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/job/memory.h"
#include "dexelmill/job/simulate.h"

namespace {

const char* kDescription =
    "dexelmill " DEXELMILL_VERSION
    " - predicts the part a CNC milling program cuts from a block of stock.\n"
    "The stock is a tri-dexel model (rays along x, y and z holding material intervals); every\n"
    "move's swept tool volume is subtracted exactly, then the result is rebuilt as an OpenVDB\n"
    "level set and written as a watertight mesh, a .vdb file, a picture and a JSON report.\n"
    "Lengths are in mm and angles in degrees everywhere.";

}  // namespace

int main(int argc, char** argv) {
    // Ctrl-C during a write leaves no hidden partial file beside the output.
    dexelmill::removeTemporariesOnSignals();
    CLI::App app{kDescription, "dexelmill"};
    app.set_version_flag("--version", std::string("dexelmill ") + DEXELMILL_VERSION);
    app.require_subcommand(1);
    app.footer(
        "Examples:\n"
        "  dexelmill simulate part.ngc --stock box:0,0,-20,100,80,0 --tool ball:d=6 -o part.stl\n"
        "  dexelmill simulate project.camotics --png part.png --report report.json\n"
        "  dexelmill simulate part.ngc --design part.stl --png deviation.png --gouge-csv gouges.csv\n"
        "  dexelmill compare machined.stl design.stl --ply deviation.ply\n"
        "  dexelmill info part.ngc\n"
        "  dexelmill study --case tilted-slot --resolutions 2,1,0.5 --families z,xyz --csv study.csv\n"
        "Run 'dexelmill COMMAND --help' for a command's options.");

    dexelmill::cli::SimulateArgs sim;
    CLI::App* simulate = dexelmill::cli::addSimulate(app, sim);
    dexelmill::cli::InfoArgs infoArgs;
    CLI::App* info = dexelmill::cli::addInfo(app, infoArgs);

    dexelmill::cli::StudyArgs study;
    CLI::App* studyCmd = dexelmill::cli::addStudy(app, study);
    dexelmill::cli::CompareArgs compare;
    CLI::App* compareCmd = dexelmill::cli::addCompare(app, compare);

    const CLI::App* commands[] = {simulate, info, studyCmd, compareCmd};
    // Every usage error, CLI11's (an option's value out of range, an unknown option) as the
    // commands' own, names the tool and points at the help of the command it was given to.
    const auto usage = [&](const std::string& message) {
        std::string command;
        for (const CLI::App* sub : commands)
            if (sub->parsed()) command = " " + sub->get_name();
        return "dexelmill: " + message + "\nRun 'dexelmill" + command + " --help' for usage.\n";
    };
    // An option that takes one value, given more often, CLI11 names with "At Most 1 required but
    // received 2": it is said in the user's terms instead. Only the option the error names is
    // meant: another's missing value is an ArgumentMismatch too.
    const auto repeated = [&](const CLI::Error& e) -> std::string {
        const std::string said = e.what();
        for (const CLI::App* sub : commands) {
            if (!sub->parsed()) continue;
            for (const CLI::Option* opt : sub->get_options())
                if (opt->get_multi_option_policy() == CLI::MultiOptionPolicy::Throw && opt->get_items_expected_max() == 1 &&
                    opt->count() > 1 && said.rfind(opt->get_name() + ":", 0) == 0)
                    return opt->get_name() + " is given " +
                           (opt->count() == 2 ? std::string("twice") : std::to_string(opt->count()) + " times") +
                           "; it takes one value";
        }
        return {};
    };
    app.failure_message([&](const CLI::App*, const CLI::Error& e) {
        const std::string twice = dynamic_cast<const CLI::ArgumentMismatch*>(&e) ? repeated(e) : std::string();
        return usage(twice.empty() ? std::string(e.what()) : twice);
    });

    // A first word that is neither an option nor a command is a command mistyped: CLI11 would
    // only say that one is required.
    if (argc > 1 && argv[1][0] != '-' && std::none_of(std::begin(commands), std::end(commands), [&](const CLI::App* sub) {
            return sub->check_name(argv[1]);
        })) {
        std::cerr << usage(std::string("unknown command '") + argv[1] + "': the commands are simulate, compare, info and study");
        return 2;
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    try {
        if (simulate->parsed()) return dexelmill::cli::runSimulate(sim);
        if (info->parsed()) return dexelmill::cli::runInfo(infoArgs);
        if (studyCmd->parsed()) return dexelmill::cli::runStudy(study);
        if (compareCmd->parsed()) return dexelmill::cli::runCompare(compare);
    } catch (const dexelmill::cli::UsageError& e) {
        std::cerr << usage(e.what());
        return 2;
    } catch (const dexelmill::Error& e) {
        // ParseErrors already read "file:line:col: error: ..."; others get a prefix.
        const std::string msg = e.what();
        if (dynamic_cast<const dexelmill::ParseError*>(&e)) std::cerr << msg << "\n";
        else std::cerr << "dexelmill: error: " << msg << "\n";
        return 1;
    } catch (const std::bad_alloc&) {
        // The job checks its big allocations beforehand; this is what slipped past the estimates.
        // Only the commands that build a stock have options that shrink it.
        const char* advice = simulate->parsed()   ? "; try a larger --resolution or fewer --families"
                             : studyCmd->parsed() ? "; try larger --resolutions or fewer --families"
                                                  : "";
        // The budget the job kept to: --max-memory's, as the job read it (it parsed before the
        // job began), or the system's.
        std::size_t budgetAsked = 0;
        if (simulate->parsed() && !sim.maxMemory.empty()) {
            try {
                budgetAsked = dexelmill::parseMemorySize(sim.maxMemory);
            } catch (const dexelmill::Error&) {
            }
        }
        std::cerr << "dexelmill: error: out of memory after a peak of " << dexelmill::formatBytes(dexelmill::peakMemoryMb() * 1024.0 * 1024.0)
                  << " (the budget: " << dexelmill::formatBytes(double(dexelmill::memoryBudget(budgetAsked).bytes)) << ")"
                  << advice << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "dexelmill: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
