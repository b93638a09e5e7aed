/// @file json_text.h
/// @brief What a JSON file a user gives (a machine description, a CAMotics project) must not hold,
/// which the JSON library takes without a word or cannot take safely.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

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
/// kMaxJsonDepth, or a key given twice in one object (the library keeps the last silently). Keys
/// are compared as written, so "a" and "\u0061" count as two. Strings are skipped, and with
/// `comments` so are // and /* */ comments, as the library's parser skips them. Text that is not
/// JSON is the library's to refuse: this only reads brackets, strings and commas.
std::optional<JsonTextFault> jsonTextFault(std::string_view text, bool comments);

}  // namespace dexelmill
