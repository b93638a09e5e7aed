/// @file binary.h
/// @brief Little-endian encoding of 32-bit words for the binary file formats, whatever the host.
#pragma once

#include <cstdint>
#include <cstring>

namespace dexelmill::binary {

/// @brief Writes v as 4 little-endian bytes at p; returns p + 4.
inline char* putU32(char* p, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) p[i] = char((v >> (8 * i)) & 0xffu);
    return p + 4;
}

/// @brief Writes an IEEE 754 single as 4 little-endian bytes at p; returns p + 4.
inline char* putF32(char* p, float f) {
    std::uint32_t v;
    std::memcpy(&v, &f, 4);
    return putU32(p, v);
}

/// @brief Reads 4 little-endian bytes.
inline std::uint32_t getU32(const char* p) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= std::uint32_t(static_cast<unsigned char>(p[i])) << (8 * i);
    return v;
}

/// @brief Reads a little-endian IEEE 754 single.
inline float getF32(const char* p) {
    const std::uint32_t v = getU32(p);
    float f;
    std::memcpy(&f, &v, 4);
    return f;
}

}  // namespace dexelmill::binary
