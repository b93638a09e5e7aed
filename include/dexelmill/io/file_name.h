/// @file file_name.h
/// @brief What a file's name says about its format.
#pragma once

#include <algorithm>
#include <cctype>
#include <string>

namespace dexelmill {

/// @brief The extension of the last component of `path`, dot included and in lower case ("" when
/// there is none): the readers and writers choose formats by it.
inline std::string lowerExtension(const std::string& path) {
    const std::size_t dot = path.find_last_of('.');
    const std::size_t slash = path.find_last_of('/');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string e = path.substr(dot);
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}

}  // namespace dexelmill
