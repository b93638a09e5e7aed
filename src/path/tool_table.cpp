#include "dexelmill/path/tool_table.h"

#include <cmath>
#include <map>
#include <string_view>

#include "detail/text.h"

namespace dexelmill {

namespace {

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r'; }

/// Appends `letter` to a list written "X, Y".
void list(std::string& to, char letter) {
    if (!to.empty()) to += ", ";
    to += letter;
}

}  // namespace

std::vector<ToolTableEntry> parseToolTable(const std::string& text, const std::string& name) {
    std::vector<ToolTableEntry> out;
    std::map<int, int> lineOf;  // tool number -> the line that gives it
    std::size_t start = 0;
    for (int line = 1; start <= text.size(); ++line) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        const std::string_view row(text.data() + start, end - start);
        start = end + 1;
        const std::size_t semicolon = row.find(';');
        const std::string_view words = row.substr(0, semicolon);
        ToolTableEntry e;
        e.where = {name, line, 0};
        if (semicolon != std::string_view::npos) {
            std::string_view c = row.substr(semicolon + 1);
            while (!c.empty() && isSpace(c.front())) c.remove_prefix(1);
            while (!c.empty() && isSpace(c.back())) c.remove_suffix(1);
            e.comment = std::string(c);
        }
        std::map<char, double> seen;
        std::size_t i = 0;
        while (true) {
            while (i < words.size() && isSpace(words[i])) ++i;
            if (i == words.size()) break;
            const SourceLocation at{name, line, int(i) + 1};
            const char letter = detail::upper(words[i]);
            if (std::string_view("TPXYZABCUVWDIJQ").find(letter) == std::string_view::npos)
                throw ParseError(at, "a tool table has no word '" + std::string(1, words[i]) +
                                         "' (T, P, D, X, Y, Z, A, B, C, U, V, W, I, J, Q)");
            ++i;
            double sign = 1.0;
            if (i < words.size() && (words[i] == '+' || words[i] == '-')) sign = words[i++] == '-' ? -1.0 : 1.0;
            double value = 0.0;
            if (!detail::parseUnsignedDecimal(words, i, value) || (i < words.size() && !isSpace(words[i])))
                throw ParseError(at, std::string("the tool table's ") + letter + " word needs a number");
            value *= sign;
            if (!seen.emplace(letter, value).second)
                throw ParseError(at, std::string("the tool table gives ") + letter + " twice on one line");
            if ((letter == 'T' || letter == 'P') && !(value >= 0.0 && value == std::floor(value) && value <= 99999.0))
                throw ParseError(at, std::string("the tool table's ") + letter +
                                         " must be a whole number from 0 to 99999");
            if (letter == 'T') {
                e.number = int(value);
                e.where = at;
            } else if (letter == 'D') {
                if (value < 0.0) throw ParseError(at, "the tool table's diameter D must not be negative");
                e.diameter = value;
            } else if (letter == 'I' || letter == 'J' || letter == 'Q') {
                list(e.latheWords, letter);
            } else if (letter != 'P' && letter != 'Z' && value != 0.0) {
                list(e.offsets, letter);
            }
        }
        if (seen.empty()) continue;
        if (!seen.count('T')) throw ParseError({name, line, 1}, "this tool table line has no tool number (T)");
        const auto [earlier, fresh] = lineOf.emplace(e.number, line);
        if (!fresh)
            throw ParseError(e.where, "the tool table gives T" + std::to_string(e.number) + " again (first on line " +
                                          std::to_string(earlier->second) + ")");
        out.push_back(std::move(e));
    }
    return out;
}

std::vector<ToolTableEntry> readToolTable(const std::string& path) {
    return parseToolTable(detail::readTextFile(path), path);
}

}  // namespace dexelmill
