/// @file heap_tunable.h
/// @brief glibc's tunable that has malloc ask the kernel for transparent huge pages for its heap
/// (glibc.malloc.hugetlb, glibc 2.35 and later), read from GLIBC_TUNABLES only when a process
/// starts. The launcher (src/launch) sets it; the report says whether it is in effect.
#pragma once

#include <cstdio>
#include <cstring>

#if defined(__GLIBC__)
#include <gnu/libc-version.h>
#endif

// Sanitizers bring their own malloc, which glibc's tunables do not reach.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define DEXELMILL_OWN_MALLOC 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define DEXELMILL_OWN_MALLOC 1
#endif
#endif

namespace dexelmill::detail {

constexpr const char* kHugeHeapTunable = "glibc.malloc.hugetlb";

/// The value a GLIBC_TUNABLES string ("name=value" entries joined by ':') gives the tunable
/// `name`, or null when it gives none (or `tunables` is null).
inline const char* tunableValue(const char* tunables, const char* name) {
    const std::size_t n = std::strlen(name);
    for (const char* at = tunables; at && *at;) {
        if (std::strncmp(at, name, n) == 0 && at[n] == '=') return at + n + 1;
        at = std::strchr(at, ':');
        if (at) ++at;
    }
    return nullptr;
}

/// Whether this process's malloc is glibc's and reads glibc.malloc.hugetlb (2.35 and later).
inline bool mallocReadsHugeHeapTunable() {
#if defined(__GLIBC__) && !defined(DEXELMILL_OWN_MALLOC)
    int major = 0, minor = 0;
    return std::sscanf(gnu_get_libc_version(), "%d.%d", &major, &minor) == 2 &&
           (major > 2 || (major == 2 && minor >= 35));
#else
    return false;
#endif
}

/// Whether a GLIBC_TUNABLES string asks for the heap on huge pages (hugetlb 1 or 2).
inline bool asksHugeHeap(const char* tunables) {
    const char* value = tunableValue(tunables, kHugeHeapTunable);
    return value && (value[0] == '1' || value[0] == '2') && (value[1] == '\0' || value[1] == ':');
}

}  // namespace dexelmill::detail
