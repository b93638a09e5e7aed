/// @file report_format.h
/// @brief The format number of the JSON reports of simulate and compare.
#pragma once

namespace dexelmill {

/// @brief The reports' key "format": it grows by one whenever a key is removed or renamed, or its
/// meaning or unit changes, so that a reader can refuse a report it was not written for. A new key
/// leaves it as it is. 1: the first numbered format.
inline constexpr int kReportFormat = 1;

}  // namespace dexelmill
