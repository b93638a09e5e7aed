/// @file atomic_file.h
/// @brief Every file the library writes goes through here: the content is written to a
/// temporary file in the target's directory and renamed over the target only once it is
/// complete, so a failed or interrupted run never leaves a half-written or clobbered file.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace dexelmill {

/// @brief Calls `write` with the path of a fresh temporary file beside `target` (created empty,
/// with the permissions a new file gets), then flushes it to disk and renames it to `target`.
/// If `write` throws, the temporary file is removed and the exception propagates; `target` is
/// untouched.
/// @throw Error if the temporary file cannot be created or the rename fails.
void writeFileAtomically(const std::string& target,
                         const std::function<void(const std::string& tempPath)>& write);

/// @brief Fails now, rather than after a long run, where writeFileAtomically(target) could not
/// start: it creates and removes a temporary file beside `target`, which must not be a folder.
/// @throw Error naming `target` and the reason.
void checkWritable(const std::string& target);

/// @brief writeFileAtomically with a binary std::ostream on the temporary file.
/// @throw Error if the stream fails at any point.
void writeStreamAtomically(const std::string& target,
                           const std::function<void(std::ostream& out)>& write);

}  // namespace dexelmill
