/// @file span.h
/// @brief A read-only view of elements lying one after another in memory (C++17 has no
/// std::span): a dexel's segments, a run of dexel stretches.
#pragma once

#include <cstddef>

namespace dexelmill {

/// @brief `size` elements of type T from `data` on; the view does not own them.
template <class T>
struct Span {
    const T* data = nullptr;
    std::size_t size = 0;

    const T* begin() const { return data; }
    const T* end() const { return data + size; }
    bool empty() const { return size == 0; }
    const T& operator[](std::size_t i) const { return data[i]; }
};

}  // namespace dexelmill
