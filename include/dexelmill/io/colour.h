/// @file colour.h
/// @brief The colour type shared by pictures and coloured meshes.
#pragma once

#include <array>
#include <cstdint>

namespace dexelmill {

/// @brief An 8-bit sRGB colour: red, green, blue.
using Rgb = std::array<std::uint8_t, 3>;

}  // namespace dexelmill
