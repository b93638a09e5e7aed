/// @file json_text.h
/// @brief JSON text as written, for what the JSON library does not keep: what a file a user gives
/// (a machine description, a CAMotics project) must not hold, which the library takes without a
/// word or cannot take safely, and where each of its values stands, for errors about their meaning.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "dexelmill/error.h"

namespace dexelmill {

/// The deepest nesting of arrays and objects a user's JSON may have. Our files need 5. The JSON
/// library prints and frees nested values recursively, so a machine file nested 60,000 deep
/// overflowed the stack.
constexpr int kMaxJsonDepth = 64;

/// @brief A fault in JSON text: where (a byte offset into it) and what.
struct JsonTextFault {
    std::size_t byte = 0;
    std::string message;
};

/// @brief The first of these in `text`, in reading order: an array or object nested deeper than
/// kMaxJsonDepth, a key given twice in one object (the library keeps the last silently), or a
/// number beyond the range of a double, as 1e999 (which the library refuses without saying where).
/// Keys are compared as written, so "a" and "\u0061" count as two. Strings are skipped, and with
/// `comments` so are // and /* */ comments, as the library's parser skips them. Text that is not
/// JSON is the library's to refuse: this only reads brackets, strings, commas and numbers.
std::optional<JsonTextFault> jsonTextFault(std::string_view text, bool comments);

/// @brief `key` as one reference token of a JSON pointer (RFC 6901): "~" written "~0", "/" "~1".
std::string jsonPointerToken(std::string_view key);

/// @brief Where each value and each object key of JSON text begins, as a byte offset into the
/// text, named by JSON pointer (RFC 6901): "" is the root, "/axes/0/direction" the member
/// "direction" of the first element of the root's member "axes". A value's offset is that of its
/// first character (the quote, bracket, brace, digit, sign or letter); a key's that of its opening
/// quote. Keys are named as the library reads them, escapes decoded ("\u0061" is "a"), and of a
/// key given twice the last counts, as in the library. With `comments`, // and /* */ comments are
/// skipped as blanks, as the library's parser skips them; a UTF-8 byte order mark before the root
/// is skipped too. Meant for text the library has accepted: of other text it holds what stands
/// before the first fault.
class JsonPositions {
public:
    JsonPositions(std::string_view text, bool comments);

    /// @brief The offset of the value at `pointer`; none when the text has no such value.
    std::optional<std::size_t> byteOf(const std::string& pointer) const;
    /// @brief The offset of the key that names the object member at `pointer`; none when
    /// `pointer` names no object member.
    std::optional<std::size_t> keyByteOf(const std::string& pointer) const;

private:
    std::map<std::string, std::size_t> values_;
    std::map<std::string, std::size_t> keys_;
};

/// @brief The place of byte `byte` of `text`, read from `file`: lines and columns from 1, a
/// column a byte; an offset past the end is the place after the last byte.
SourceLocation locateByte(std::string_view text, std::size_t byte, const std::string& file);

/// @brief Where the values and keys of a user's JSON file stand, as places in that file, by JSON
/// pointer (JsonPositions): errors about what a value means name its line and column, though the
/// JSON library keeps no positions. Holds a view of `text`, which must outlive it.
class JsonPlaces {
public:
    JsonPlaces(std::string_view text, std::string file, bool comments);

    /// @brief The place of the value at `pointer`; the file alone where the text has none.
    SourceLocation value(const std::string& pointer) const;
    /// @brief The place of the key naming the object member at `pointer`; the file alone where
    /// `pointer` names no object member.
    SourceLocation key(const std::string& pointer) const;

private:
    SourceLocation place(std::optional<std::size_t> byte) const;

    std::string_view text_;
    std::string file_;
    JsonPositions positions_;
};

}  // namespace dexelmill
