/// @file slot_job.h
/// @brief Test support: a job of one straight cutting move, given as a program in memory (no
/// file to read), for tests of what the job does around the cut: budgets, threads, refusals.
#pragma once

#include <string>

#include "dexelmill/job/simulate.h"
#include "dexelmill/tool/tool.h"

namespace dexelmill::testing {

/// @brief A path of one move of tool 1 from `start` to `end`, from line 1 of `file`.
inline ToolPath slotPath(const Vec3& start, const Vec3& end, const std::string& file = "slot.nc") {
    ToolPath path;
    path.files.push_back(file);
    Move m;
    m.start = start;
    m.end = end;
    m.tool = 1;
    m.source = SourceRef{0, 1};
    path.moves.push_back(m);
    return path;
}

/// @brief Options for one move of `tool` (tool 1) from `start` to `end` through `stock`, from line 1
/// of "slot.nc". The spacing and the threads are left to the caller.
inline SimulateOptions slotJob(const Vec3& start, const Vec3& end, const Tool& tool, const Box& stock) {
    Program program;
    program.path = slotPath(start, end);
    SimulateOptions o;
    o.program = program;
    o.inputs = {"slot.nc"};
    o.defaultTool = tool;
    o.stockBox = stock;
    return o;
}

}  // namespace dexelmill::testing
