// The deviation's JSON, shared by the simulate and compare reports.
#pragma once

#include <nlohmann/json.hpp>

#include "dexelmill/compare/deviation.h"

namespace dexelmill {

/// @brief The deviation's tolerances, areas, extremes and histogram (not its per-vertex distances),
/// snake_case with units in the names.
nlohmann::json deviationJson(const Deviation& deviation);

}  // namespace dexelmill
