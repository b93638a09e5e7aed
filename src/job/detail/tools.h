/// @file tools.h
/// @brief The tools a job cuts with, by number: the command line's over the program's.
#pragma once

#include "dexelmill/job/simulate.h"

namespace dexelmill::detail {

/// @brief The tools the cutting loop uses: the command line's over the program's; tool numbers
/// nobody defines get the default tool, or standInTool's (with a warning). Adds its notes and
/// warnings to the program's diagnostics.
/// @throw ParseError at the first move of a tool number nothing defines, when nothing stands in.
ToolTable resolveTools(const SimulateOptions& o, Program& program);

}  // namespace dexelmill::detail
