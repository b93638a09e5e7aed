/// @file text.h
/// @brief Small text helpers shared by the readers.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "dexelmill/geometry/types.h"
#include "dexelmill/path/toolpath.h"

namespace dexelmill::detail {

/// @brief The whole file as a string.
/// @throw Error naming the file when it cannot be read.
std::string readTextFile(const std::string& path);

/// @brief The text as the readers take it: without a UTF-8 byte-order mark, and with lone CR
/// line ends made LF.
std::string normaliseText(std::string text);

/// @brief A named file's text from `files` (the file system when it is empty), normalised;
/// std::nullopt when there is no such file.
/// @throw Error naming the file when it exists but cannot be read.
std::optional<std::string> readFileIfAny(const FileSource& files, const std::string& path);

/// @brief As readFileIfAny, and a missing file is an Error that names it.
std::string readFile(const FileSource& files, const std::string& path);

/// @brief Parses an unsigned decimal number without exponent ("12", "1.5", ".5", "3.") starting
/// at s[pos]; advances pos. Correctly rounded for up to 19 significant digits (the value is an
/// exact integer divided by an exact power of ten), strtod otherwise.
/// @return false when there is no digit at all.
bool parseUnsignedDecimal(std::string_view s, std::size_t& pos, double& value);

/// @brief ASCII upper case of c.
inline char upper(char c) { return (c >= 'a' && c <= 'z') ? char(c - 'a' + 'A') : c; }

/// @brief The directory part of a path ("" for none), and a path joined to a directory.
std::string directoryOf(const std::string& path);
std::string joinPath(const std::string& dir, const std::string& name);

/// @brief The message for a program that makes more than `limit` moves; `reason` says what set
/// the limit (empty: the reader's own).
std::string tooManyMoves(std::size_t limit, const std::string& reason);

/// @brief A number to six significant digits.
std::string formatNumber(double v);

/// @brief A point as "(x, y, z)", six significant digits each.
std::string formatPoint(const Vec3& p);

}  // namespace dexelmill::detail
