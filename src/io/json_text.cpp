#include "dexelmill/io/json_text.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <set>
#include <utility>
#include <vector>

namespace dexelmill {

namespace {

/// Where the comment starting at text[i] ends (its last character), npos when it does not end;
/// i itself when no comment starts there.
std::size_t commentEnd(std::string_view text, std::size_t i) {
    if (text[i] != '/' || i + 1 >= text.size() || (text[i + 1] != '/' && text[i + 1] != '*')) return i;
    const bool line = text[i + 1] == '/';
    const std::size_t end = text.find(line ? "\n" : "*/", i + 2);
    if (end == std::string_view::npos) return end;
    return end + (line ? 0 : 1);
}

/// The closing quote of the string whose opening quote is text[i], npos when it does not close.
std::size_t stringEnd(std::string_view text, std::size_t i) {
    std::size_t end = i + 1;
    while (end < text.size() && text[end] != '"') end += text[end] == '\\' ? 2 : 1;
    return end < text.size() ? end : std::string_view::npos;
}

/// The four hex digits at s[i], if there are four.
std::optional<unsigned> hex4(std::string_view s, std::size_t i) {
    if (i + 4 > s.size()) return std::nullopt;
    unsigned v = 0;
    for (std::size_t k = i; k < i + 4; ++k) {
        const char c = char(std::tolower(static_cast<unsigned char>(s[k])));
        const std::size_t d = std::string_view("0123456789abcdef").find(c);
        if (d == std::string_view::npos) return std::nullopt;
        v = v * 16 + unsigned(d);
    }
    return v;
}

/// Code point `cp` in UTF-8, appended to `out`.
void appendUtf8(std::string& out, unsigned cp) {
    if (cp < 0x80) {
        out += char(cp);
    } else if (cp < 0x800) {
        out += char(0xc0 | (cp >> 6));
        out += char(0x80 | (cp & 0x3f));
    } else if (cp < 0x10000) {
        out += char(0xe0 | (cp >> 12));
        out += char(0x80 | ((cp >> 6) & 0x3f));
        out += char(0x80 | (cp & 0x3f));
    } else {
        out += char(0xf0 | (cp >> 18));
        out += char(0x80 | ((cp >> 12) & 0x3f));
        out += char(0x80 | ((cp >> 6) & 0x3f));
        out += char(0x80 | (cp & 0x3f));
    }
}

/// A string's text between its quotes with its escapes decoded, as the library reads it; a pair of
/// \u escapes of UTF-16 surrogates is one character.
std::string decoded(std::string_view s) {
    std::string out;
    for (std::size_t i = 0; i < s.size(); ++i) {
        if (s[i] != '\\' || i + 1 == s.size()) {
            out += s[i];
            continue;
        }
        const char e = s[++i];
        const std::optional<unsigned> unit = e == 'u' ? hex4(s, i + 1) : std::nullopt;
        if (!unit) {
            const std::string_view from = "bfnrt", to = "\b\f\n\r\t";
            const std::size_t k = from.find(e);
            out += k == std::string_view::npos ? e : to[k];
            continue;
        }
        unsigned cp = *unit;
        i += 4;
        if (cp >= 0xd800 && cp <= 0xdbff && s.substr(i + 1, 2) == "\\u") {
            const std::optional<unsigned> low = hex4(s, i + 3);
            if (low && *low >= 0xdc00 && *low <= 0xdfff) {
                cp = 0x10000 + ((cp - 0xd800) << 10) + (*low - 0xdc00);
                i += 6;
            }
        }
        appendUtf8(out, cp);
    }
    return out;
}

}  // namespace

std::optional<JsonTextFault> jsonTextFault(std::string_view text, bool comments) {
    // One frame per open array or object: an object's keys so far, and whether a key comes next.
    struct Frame {
        bool object = false;
        bool keyNext = false;
        std::set<std::string_view> keys;
    };
    std::vector<Frame> open;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (comments && commentEnd(text, i) != i) {
            i = commentEnd(text, i);
            if (i == std::string_view::npos) return std::nullopt;
            continue;
        }
        if (c == '"') {
            const std::size_t end = stringEnd(text, i);
            if (end == std::string_view::npos) return std::nullopt;
            if (!open.empty() && open.back().object && open.back().keyNext) {
                const std::string_view key = text.substr(i + 1, end - i - 1);
                if (!open.back().keys.insert(key).second)
                    return JsonTextFault{i, "the key \"" + std::string(key) + "\" is given twice in one object"};
                open.back().keyNext = false;
            }
            i = end;
            continue;
        }
        if (c == '-' || (c >= '0' && c <= '9')) {
            // A number: the library refuses one beyond double's range but cannot say where it is.
            const std::size_t end = std::min(text.find_first_not_of("0123456789+-.eE", i), text.size());
            const std::string number(text.substr(i, end - i));
            if (std::isinf(std::strtod(number.c_str(), nullptr)))
                return JsonTextFault{i, "the number " + number + " is beyond the range of a double"};
            i = end - 1;
            continue;
        }
        if (c == '[' || c == '{') {
            if (int(open.size()) == kMaxJsonDepth)
                return JsonTextFault{i, "arrays and objects are nested deeper than " + std::to_string(kMaxJsonDepth) +
                                            " levels"};
            open.push_back(Frame{c == '{', c == '{', {}});
        } else if ((c == ']' || c == '}') && !open.empty()) {
            open.pop_back();
        } else if (c == ',' && !open.empty() && open.back().object) {
            open.back().keyNext = true;
        }
    }
    return std::nullopt;
}

std::string jsonPointerToken(std::string_view key) {
    std::string token;
    for (const char c : key) token += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
    return token;
}

JsonPositions::JsonPositions(std::string_view text, bool comments) {
    // One frame per open array or object: its pointer, and the index of an array's current element.
    struct Frame {
        std::string pointer;
        bool object = false;
        std::size_t index = 0;
    };
    std::vector<Frame> open;
    // What the text holds next: a value (named `pointer`), an object's first key or its closing
    // brace, an array's first value or its closing bracket, a key, or what follows a value.
    enum class Next { Value, KeyOrEnd, ValueOrEnd, Key, AfterValue } next = Next::Value;
    std::string pointer;
    std::size_t i = text.substr(0, 3) == "\xef\xbb\xbf" ? 3 : 0;
    const auto skipBlanks = [&] {
        while (i < text.size()) {
            const char c = text[i];
            if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
                ++i;
            } else if (comments && commentEnd(text, i) != i) {
                i = commentEnd(text, i);
                if (i != std::string_view::npos) ++i;
            } else {
                return;
            }
        }
    };
    for (skipBlanks(); i < text.size(); skipBlanks()) {
        const char c = text[i];
        if ((next == Next::KeyOrEnd && c == '}') || (next == Next::ValueOrEnd && c == ']')) {
            next = Next::AfterValue;
        } else if (next == Next::KeyOrEnd) {
            next = Next::Key;
        } else if (next == Next::ValueOrEnd) {
            next = Next::Value;
            pointer = open.back().pointer + "/0";
        } else if (next == Next::AfterValue && c == ',' && !open.empty()) {
            ++i;
            Frame& f = open.back();
            next = f.object ? Next::Key : Next::Value;
            if (!f.object) pointer = f.pointer + "/" + std::to_string(++f.index);
            continue;
        }
        if (next == Next::Key) {
            const std::size_t end = c == '"' ? stringEnd(text, i) : std::string_view::npos;
            if (end == std::string_view::npos) return;
            pointer = open.back().pointer + "/" + jsonPointerToken(decoded(text.substr(i + 1, end - i - 1)));
            keys_[pointer] = i;
            i = end + 1;
            skipBlanks();
            if (i >= text.size() || text[i] != ':') return;
            ++i;
            next = Next::Value;
        } else if (next == Next::Value) {
            if (c == '{' || c == '[') {
                values_[pointer] = i;
                open.push_back(Frame{pointer, c == '{', 0});
                next = c == '{' ? Next::KeyOrEnd : Next::ValueOrEnd;
                ++i;
            } else if (c == '"') {
                values_[pointer] = i;
                i = stringEnd(text, i);
                if (i == std::string_view::npos) return;
                ++i;
                next = Next::AfterValue;
            } else {
                // A number, true, false or null runs to the next blank, comma or bracket.
                const std::size_t end = text.find_first_of(" \t\n\r,]}/", i);
                if (end == i) return;
                values_[pointer] = i;
                i = end == std::string_view::npos ? text.size() : end;
                next = Next::AfterValue;
            }
        } else {  // after a value: only the closing of the open array or object may follow
            if (open.empty() || c != (open.back().object ? '}' : ']')) return;
            open.pop_back();
            ++i;
        }
    }
}

std::optional<std::size_t> JsonPositions::byteOf(const std::string& pointer) const {
    const auto it = values_.find(pointer);
    if (it == values_.end()) return std::nullopt;
    return it->second;
}

std::optional<std::size_t> JsonPositions::keyByteOf(const std::string& pointer) const {
    const auto it = keys_.find(pointer);
    if (it == keys_.end()) return std::nullopt;
    return it->second;
}

SourceLocation locateByte(std::string_view text, std::size_t byte, const std::string& file) {
    SourceLocation at{file, 1, 1};
    for (std::size_t i = 0; i < byte && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++at.line;
            at.column = 1;
        } else {
            ++at.column;
        }
    }
    return at;
}

JsonPlaces::JsonPlaces(std::string_view text, std::string file, bool comments)
    : text_(text), file_(std::move(file)), positions_(text, comments) {}

SourceLocation JsonPlaces::value(const std::string& pointer) const { return place(positions_.byteOf(pointer)); }

SourceLocation JsonPlaces::key(const std::string& pointer) const { return place(positions_.keyByteOf(pointer)); }

SourceLocation JsonPlaces::place(std::optional<std::size_t> byte) const {
    return byte ? locateByte(text_, *byte, file_) : SourceLocation{file_, 0, 0};
}

}  // namespace dexelmill
