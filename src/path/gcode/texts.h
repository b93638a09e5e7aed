/// @file texts.h
/// @brief G-code files whose texts are read already: what readGcodeFiles runs, and what a CAMotics
/// project hands on after reading each program once to tell its kind.
#pragma once

#include <string>
#include <vector>

#include "dexelmill/path/gcode.h"

namespace dexelmill::detail::gcode {

/// A program file's name and its text.
struct NamedText {
    std::string name;
    std::string text;
};

/// @brief Runs the files one after the other on one machine (state such as position, tool and
/// offsets carries over), as readGcodeFiles does.
Program runTexts(std::vector<NamedText> files, const GcodeOptions& options);

}  // namespace dexelmill::detail::gcode
