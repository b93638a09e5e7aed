// The job's memory budget and estimates: sizes as users write them, the estimates against what a
// fresh stock really holds, and jobs too big for their budget stopped before they start, with a
// spacing that then fits.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string>

#if defined(__linux__)
#include <sched.h>
#endif

#include "dexelmill/error.h"
#include "dexelmill/job/memory.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/path/gcode.h"
#include "dexelmill/tool/builders.h"
#include "support/slot_job.h"

using namespace dexelmill;

TEST_CASE("memory: sizes as users write them", "[job][memory]") {
    CHECK(parseMemorySize("4G") == 4ull << 30);
    CHECK(parseMemorySize("512M") == 512ull << 20);
    CHECK(parseMemorySize("1.5GiB") == (3ull << 30) / 2);
    CHECK(parseMemorySize("64k") == 64ull << 10);
    CHECK(parseMemorySize("800000000") == 800000000ull);
    CHECK(parseMemorySize("2e3K") == 2000ull << 10);
    // Decimal only, as every option: strtod reads "0x10" as 16 and "inf" as infinity.
    for (const char* bad : {"", "G", "4X", "-1G", "0", "nan", "1e30T", "0x10G", "0x10", "0X1p4M", "infG", "inf"}) {
        INFO(bad);
        CHECK_THROWS_AS(parseMemorySize(bad), Error);
    }
    const MemoryBudget given = memoryBudget(123456789);
    CHECK(given.bytes == 123456789);
    CHECK(given.source == "--max-memory");
    const MemoryBudget system = memoryBudget();
    CHECK(system.bytes > residentBytes());
}

TEST_CASE("memory: a --max-memory beyond what the system gives is named, and cut where it is enforced",
          "[job][memory]") {
    // 1e18 bytes is more than any machine's memory available: kept with a warning, or cut to the
    // address-space or cgroup limit (which this process may run under) with a warning.
    const std::size_t huge = std::size_t(1e18);
    const MemoryBudget b = memoryBudget(huge);
    CHECK(b.note.find("--max-memory") != std::string::npos);
    if (b.enforced) {
        CHECK(b.bytes < huge);
        CHECK(b.note.find("the job keeps to") != std::string::npos);
        CHECK(moreMemoryAdvice(b).empty());
    } else {
        CHECK(b.bytes == huge);
        CHECK(b.note.find("may run out of memory") != std::string::npos);
        CHECK(moreMemoryAdvice(b) == ", or a larger --max-memory");
    }
    // A budget well within what the system gives says nothing.
    CHECK(memoryBudget(std::size_t(64) << 20).note.empty());
    MemoryBudget soft{std::size_t(1) << 30, "the memory available (MemAvailable)", false, false, {}};
    CHECK(moreMemoryAdvice(soft) == ", or set --max-memory");
}

TEST_CASE("memory: a fresh stock's estimates against the stock itself", "[job][memory]") {
    for (const auto& [box, h, families] :
         {std::tuple<Box, double, const char*>{Box{Vec3(0.0), Vec3(40, 30, 10)}, 0.5, "xyz"},
          {Box{Vec3(-3, 2, 1), Vec3(17.3, 9.9, 4.4)}, 0.13, "xyz"},
          {Box{Vec3(0.0), Vec3(40, 30, 10)}, 0.25, "z"},
          {Box{Vec3(0.0), Vec3(100, 7, 3)}, 0.2, "xy"}}) {
        INFO(families << " at " << h);
        const FamilySet set = FamilySet::parse(families);
        const TriDexelStock stock = TriDexelStock::fromBox(box, h, set);
        // Every dexel of a fresh box holds one segment, whose two ends are the box's crossings;
        // when the box is not a whole number of cells, the last row of lattice lines may miss it.
        if (set.count() == 3) {
            const Lattice& l = stock.lattice();
            const double edgeRows = 2.0 / std::min({l.n[0], l.n[1], l.n[2]});
            CHECK(stockCrossings(stock) <= boxCrossings(l));
            CHECK(stockCrossings(stock) >= (1.0 - edgeRows) * boxCrossings(l));
        }
        // The estimate is what the tiles hold, within the rounding of partial tiles at the edges.
        const double est = stockBytes(stock.lattice(), set);
        CHECK(est >= 0.7 * double(stock.memoryBytes()));
        CHECK(est <= 1.3 * double(stock.memoryBytes()));
    }
}

TEST_CASE("memory: the spacing that fits", "[job][memory]") {
    for (const auto& [h, need, room] : {std::tuple<double, double, double>{0.01, 8e9, 4e9}, {0.5, 1e6, 1e9},
                                        {0.2947, 9.3e7, 2.4e7}, {1.0, 1e12, 3e9}}) {
        const double fit = spacingThatFits(h, need, room);
        INFO(h << " " << need << " " << room << " -> " << fit);
        // need grows as h^-2: at the spacing returned it fits, and at 1 % less than it, it would
        // not, unless the spacing given fitted already.
        CHECK(need * (h / fit) * (h / fit) <= room * (1 + 1e-12));
        if (need > room) CHECK(need * (h / (0.99 * fit * 0.95)) * (h / (0.99 * fit * 0.95)) > room);
        else CHECK(fit == Approx(h).epsilon(0.1));
    }
}

TEST_CASE("memory: a job too big for its budget stops before it starts, with a spacing that fits",
          "[job][memory][errors]") {
    SimulateOptions o = testing::slotJob(Vec3(2, 15, 8), Vec3(38, 15, 8), flatEndMill(6.0, {20.0, 30.0}),
                                         Box{Vec3(0.0), Vec3(40, 30, 10)});
    o.resolution = 0.02;
    o.maxMemoryBytes = residentBytes() + (200ull << 20);
    std::string message;
    try {
        runSimulation(o);
    } catch (const Error& e) {
        message = e.what();
    }
    INFO(message);
    REQUIRE_THAT(message, Catch::Matchers::Contains("more than the 200 MiB") ||
                              Catch::Matchers::Contains("this job may use (--max-memory)"));
    const std::string key = "a spacing of ";
    const std::size_t at = message.rfind(key);
    REQUIRE(at != std::string::npos);
    const double fits = std::stod(message.substr(at + key.size()));
    CHECK(fits > o.resolution);
    // At the spacing named, with the same room, the stock and the block's faces fit: the job
    // runs, or stops only later, if the cut part's surface does not fit (the check before the
    // rebuild, which knows the part's crossings).
    o.resolution = fits;
    o.maxMemoryBytes = residentBytes() + (200ull << 20);
    try {
        const SimulateReport r = runSimulation(o).report;
        CHECK(r.meshClosed);
    } catch (const Error& e) {
        INFO(e.what());
        CHECK_THAT(e.what(), Catch::Matchers::Contains("the cut part's surface crosses"));
    }
}

TEST_CASE("memory: a cut part whose surface will not fit stops before the rebuild", "[job][memory][errors]") {
    // Ten slots through a 10 mm block: their walls give the part about three times the crossings
    // of the block's faces, which alone fit in the budget.
    ToolPath path;
    path.files.push_back("slots.nc");
    for (int k = 0; k < 10; ++k) {
        Move m;
        m.start = Vec3(-2, 1.5 + 3.0 * k, -1);
        m.end = Vec3(42, 1.5 + 3.0 * k, -1);
        m.tool = 1;
        m.source = SourceRef{0, k + 1};
        path.moves.push_back(m);
    }
    Program program;
    program.path = path;
    SimulateOptions o;
    o.program = program;
    o.inputs = {"slots.nc"};
    o.defaultTool = flatEndMill(1.5, {20.0, 30.0});
    o.stockBox = Box{Vec3(0.0), Vec3(40, 30, 10)};
    o.resolution = 0.1;
    const Lattice lattice = Lattice::fromBox(*o.stockBox, o.resolution);
    o.maxMemoryBytes = residentBytes() + std::size_t(stockBytes(lattice, o.families) +
                                                     1.3 * kSurfaceBytesPerCrossing * boxCrossings(lattice));
    try {
        runSimulation(o);
        FAIL("no error");
    } catch (const Error& e) {
        INFO(e.what());
        CHECK_THAT(e.what(), Catch::Matchers::Contains("the cut part's surface crosses") &&
                                 Catch::Matchers::Contains("a spacing of 0.1 mm") &&
                                 Catch::Matchers::Contains("mm or more fits"));
    }
}

TEST_CASE("memory: a program whose moves will not fit stops in the reader, which says why", "[job][memory][errors]") {
    // A loop of 200,000 moves (G-code) and 60,000 GOTOs (APT), against a budget that leaves room
    // for some ten thousand moves (3 x sizeof(Move), over 400 bytes, each). The room is 8 MiB, more
    // than the job's threads take on starting (under a sanitizer too): the budget must not be spent
    // before the readers start, which is an error of its own.
    const std::map<std::string, std::string> files = {
        {"loop.ngc", "G21 G90\nG0 X0 Y0 Z5\no1 repeat [100000]\nG1 X1\nG1 X0\no1 endrepeat\nM2\n"},
        {"long.apt", [] {
             std::string t = "CUTTER/6\nFROM/0,0,5\n";
             for (int i = 0; i < 60000; ++i) t += "GOTO/" + std::to_string(i % 7) + ",0,-1\n";
             return t;
         }()},
    };
    for (const std::string input : {"loop.ngc", "long.apt"}) {
        INFO(input);
        SimulateOptions o;
        o.inputs = {input};
        o.files = [&](const std::string& path) -> std::optional<std::string> {
            const auto it = files.find(path);
            if (it == files.end()) return std::nullopt;
            return it->second;
        };
        o.stockBox = Box{Vec3(-10.0), Vec3(10.0)};
        o.resolution = 1.0;
        o.defaultTool = flatEndMill(6.0);
        o.maxMemoryBytes = residentBytes() + (std::size_t(8) << 20);
        CHECK_THROWS_WITH(runSimulation(o), Catch::Matchers::Contains(input + ":") &&
                                                Catch::Matchers::Contains("program makes more than") &&
                                                Catch::Matchers::Contains("would not fit in the memory this job may use") &&
                                                Catch::Matchers::Contains("(--max-memory)"));
    }
    // Without a budget that binds, the reader's own limit speaks, and says nothing of memory.
    GcodeOptions g;
    g.maxMoves = 3;
    CHECK_THROWS_WITH(parseGcode(files.at("loop.ngc"), "loop.ngc", g),
                      Catch::Matchers::Contains("more than 3 moves") && !Catch::Matchers::Contains("memory"));
}

TEST_CASE("threads: a request beyond what the machine runs is cut to it, and said", "[job][memory][errors]") {
    const int runnable = runnableThreads();
    REQUIRE(runnable >= 1);
#if defined(__linux__)
    // No more than the CPUs the process may run on.
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof set, &set) == 0) CHECK(runnable <= CPU_COUNT(&set));
#endif
    CHECK(arenaThreads(0) == runnable);
    CHECK(arenaThreads(1) == 1);
    CHECK(arenaThreads(runnable) == runnable);
    CHECK(arenaThreads(runnable + 1) == runnable);
    CHECK(arenaThreads(100000) == runnable);

    // A job asked for 100,000 threads runs as one on every runnable thread, with the same part,
    // and its report says what it did. (Each stage used to size its work by the arena: the mesh
    // check's star building scanned the triangles once per requested thread.)
    SimulateOptions o = testing::slotJob(Vec3(2, 15, 8), Vec3(38, 15, 8), flatEndMill(6.0, {20.0, 30.0}),
                                         Box{Vec3(0.0), Vec3(40, 30, 10)});
    o.resolution = 0.5;
    o.threads = runnable;
    const SimulateReport usual = runSimulation(o).report;
    o.threads = 100000;
    const SimulateReport asked = runSimulation(o).report;
    CHECK(asked.meshTriangles == usual.meshTriangles);
    CHECK(asked.removedVolumeMm3 == usual.removedVolumeMm3);
    const auto said = std::find_if(asked.warnings.begin(), asked.warnings.end(), [](const ReportWarning& w) {
        return w.message.find("--threads 100000") != std::string::npos;
    });
    REQUIRE(said != asked.warnings.end());
    CHECK_THAT(said->message, Catch::Matchers::Contains("the job uses " + std::to_string(runnable)));
    CHECK(std::none_of(usual.warnings.begin(), usual.warnings.end(), [](const ReportWarning& w) {
        return w.message.find("--threads") != std::string::npos;
    }));
}
