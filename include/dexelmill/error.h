/// @file error.h
/// @brief The one exception hierarchy of dexelmill. The library throws, never prints or exits;
/// the command-line tool catches once in main.
#pragma once

#include <stdexcept>
#include <string>

namespace dexelmill {

/// @brief Base of every exception the library throws: bad input, impossible tools, I/O failures.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// @brief Text from an input file made safe to print: control bytes (below 0x20 but tab, and 0x7f)
/// become \xNN, so that a NUL or an escape sequence neither cuts nor garbles a message.
inline std::string printable(const std::string& text) {
    static const char hex[] = "0123456789abcdef";
    std::string out;
    out.reserve(text.size());
    for (const char ch : text) {
        const auto c = static_cast<unsigned char>(ch);
        if ((c < 0x20 && c != '\t') || c == 0x7f) {
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        } else {
            out += ch;
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
