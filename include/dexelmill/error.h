/// @file error.h
/// @brief The one exception hierarchy of dexelmill. The library throws, never prints or exits;
/// the command-line tool catches once in main.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace dexelmill {

/// @brief Base of every exception the library throws: bad input, impossible tools, I/O failures.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// @brief The length of the well-formed UTF-8 sequence at `s[i]` (Unicode's table 3-7: no
/// overlong forms, surrogates or code points past U+10FFFF), 0 when there is none.
inline std::size_t utf8Sequence(const std::string& s, std::size_t i) {
    const auto at = [&](std::size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0u; };
    const unsigned c = at(i);
    std::size_t n = 0;
    unsigned lo = 0x80, hi = 0xbf;  // the second byte's range
    if (c >= 0xc2 && c <= 0xdf) n = 2;
    else if (c >= 0xe0 && c <= 0xef) n = 3, lo = c == 0xe0 ? 0xa0 : 0x80, hi = c == 0xed ? 0x9f : 0xbf;
    else if (c >= 0xf0 && c <= 0xf4) n = 4, lo = c == 0xf0 ? 0x90 : 0x80, hi = c == 0xf4 ? 0x8f : 0xbf;
    else return 0;
    if (at(i + 1) < lo || at(i + 1) > hi) return 0;
    for (std::size_t k = 2; k < n; ++k)
        if (at(i + k) < 0x80 || at(i + k) > 0xbf) return 0;
    return n;
}

/// @brief Text from an input file made safe to print: control bytes (below 0x20 but tab, and
/// 0x7f) and bytes that are not part of well-formed UTF-8 become \xNN, so that a NUL, an escape
/// sequence or a stray byte of another encoding neither cuts nor garbles a message.
inline std::string printable(const std::string& text) {
    static const char hex[] = "0123456789abcdef";
    std::string out;
    out.reserve(text.size());
    for (std::size_t i = 0; i < text.size();) {
        const auto c = static_cast<unsigned char>(text[i]);
        const std::size_t n = c < 0x80 ? 1 : utf8Sequence(text, i);
        if ((c < 0x20 && c != '\t') || c == 0x7f || n == 0) {
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
            ++i;
        } else {
            out.append(text, i, n);
            i += n;
        }
    }
    return out;
}

/// @brief A place in an input file. Lines and columns count from 1; 0 means "unknown".
struct SourceLocation {
    std::string file;
    int line = 0;
    int column = 0;

    /// @brief "file:line:col", dropping the parts that are unknown.
    std::string str() const {
        std::string s = file.empty() ? std::string("<input>") : file;
        if (line > 0) {
            s += ":" + std::to_string(line);
            if (column > 0) s += ":" + std::to_string(column);
        }
        return s;
    }
};

/// @brief An input error with its location and the offending text.
/// what() reads "file:line:col: error: message: 'text'".
class ParseError : public Error {
public:
    ParseError(SourceLocation where, const std::string& message, std::string offending = {})
        : Error(format(where, message, offending)),
          where_(std::move(where)),
          message_(message),
          offending_(std::move(offending)) {}

    const SourceLocation& where() const { return where_; }
    /// @brief The message without the location prefix.
    const std::string& message() const { return message_; }
    const std::string& offending() const { return offending_; }

private:
    static std::string format(const SourceLocation& where, const std::string& message,
                              const std::string& offending) {
        std::string s = where.str() + ": error: " + printable(message);
        if (!offending.empty()) s += ": '" + printable(offending) + "'";
        return s;
    }

    SourceLocation where_;
    std::string message_;
    std::string offending_;
};

}  // namespace dexelmill
