/// @file tools.h
/// @brief The tools a job cuts with, by number: the command line's over the program's.
#pragma once

#include "dexelmill/job/simulate.h"

namespace dexelmill::detail {

/// @brief The tools the cutting loop uses: the command line's over the program's, then the tool
/// table's (SimulateOptions::toolTable) for the numbers those leave undefined; the numbers still
/// undefined get the default tool, or standInTool's (with a warning). Adds its notes and warnings
/// to the program's diagnostics.
/// @throw ParseError at the first move of a tool number nothing defines, when nothing stands in,
/// or at a tool table's word that is wrong or a used entry that cannot be a tool.
ToolTable resolveTools(const SimulateOptions& o, Program& program);

}  // namespace dexelmill::detail
