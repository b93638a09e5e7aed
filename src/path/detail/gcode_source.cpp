/// @file gcode_source.cpp
/// @brief The line table and O-word lines of a G-code file.
#include "path/detail/gcode_source.h"

#include <algorithm>
#include <cctype>
#include <limits>
#include <string>
#include <utility>

#include "dexelmill/error.h"
#include "path/detail/text.h"

namespace dexelmill::detail {

SourceFile::SourceFile(std::string name, std::string text) : name_(std::move(name)), text_(std::move(text)) {
    // Lines are counted in int, as everywhere in the reader: checked before the table is built.
    const auto newlines = std::size_t(std::count(text_.begin(), text_.end(), '\n'));
    if (newlines >= std::size_t(std::numeric_limits<int>::max()))
        throw Error("'" + name_ + "' has more than " + std::to_string(std::numeric_limits<int>::max()) + " lines");
    // The text always ends the last line, so that line k ends at starts_[k + 1] - 1.
    starts_.reserve(newlines + 2);
    starts_.push_back(0);
    for (std::size_t e = text_.find('\n'); e != std::string::npos; e = text_.find('\n', e + 1))
        starts_.push_back(e + 1);
    starts_.push_back(text_.size() + 1);
    hasOWord_.assign(starts_.size() - 1, false);
    bool seenContent = false;
    for (int k = 0; k < lineCount(); ++k) {
        const std::string_view s = line(k);
        const std::size_t i = skipSpaces(s, 0);
        if (i == s.size()) continue;
        if (!seenContent) startsWithPercent_ = s[i] == '%';
        seenContent = true;
        if (s[i] != '(' && s[i] != ';') ++contentLines_;
    }
    // O-words, N numbers and Fanuc WHILE/END.
    for (int k = 0; k < lineCount(); ++k) classify(k);
}

void SourceFile::classify(int k) {
    const std::string_view s = line(k);
    auto put = [&](OKind kind, std::string label, std::size_t argPos) {
        hasOWord_[std::size_t(k)] = true;
        OWord& w = owords_[k];
        w.kind = kind;
        w.label = std::move(label);
        w.argPos = argPos;
    };
    std::size_t i = skipSpaces(s, 0);
    if (i < s.size() && s[i] == '/') i = skipSpaces(s, i + 1);
    if (i < s.size() && upper(s[i]) == 'N') {
        std::size_t j = i + 1;
        long n = 0;
        bool digits = false;
        while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) {
            if (n < 100000000) n = n * 10 + (s[j] - '0');
            ++j;
            digits = true;
        }
        if (digits) {
            nLines_.emplace(n, k);
            i = skipSpaces(s, j);
        }
    }
    if (i >= s.size()) return;
    const char c = upper(s[i]);
    if (c == ':' || (c == 'O' && i + 1 < s.size() &&
                     (s[i + 1] == '<' || std::isdigit(static_cast<unsigned char>(s[i + 1]))))) {
        std::size_t j = i + 1;
        std::string label;
        if (s[j] == '<') {
            const std::size_t close = s.find('>', j);
            if (close == std::string_view::npos) return;  // reported when executed
            for (std::size_t t = j + 1; t < close; ++t)
                if (s[t] != ' ' && s[t] != '\t')
                    label += char(std::tolower(static_cast<unsigned char>(s[t])));
            j = close + 1;
        } else {
            while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) ++j;
            // Numbers: "O0097" and "O97" are the same program.
            std::size_t t = i + 1;
            while (t + 1 < j && s[t] == '0') ++t;
            label = std::string(s.substr(t, j - t));
            if (label.empty()) label = "0";
        }
        j = skipSpaces(s, j);
        std::size_t kwEnd = j;
        while (kwEnd < s.size() && std::isalpha(static_cast<unsigned char>(s[kwEnd]))) ++kwEnd;
        std::string kw;
        for (std::size_t t = j; t < kwEnd; ++t)
            kw += char(std::tolower(static_cast<unsigned char>(s[t])));
        static const std::pair<const char*, OKind> kws[] = {
            {"sub", OKind::Sub},         {"endsub", OKind::EndSub},
            {"call", OKind::Call},       {"do", OKind::Do},
            {"while", OKind::While},     {"endwhile", OKind::EndWhile},
            {"if", OKind::If},           {"elseif", OKind::ElseIf},
            {"else", OKind::Else},       {"endif", OKind::EndIf},
            {"repeat", OKind::Repeat},   {"endrepeat", OKind::EndRepeat},
            {"break", OKind::Break},     {"continue", OKind::Continue},
            {"return", OKind::Return}};
        for (const auto& [name, kind] : kws)
            if (kw == name) {
                put(kind, std::move(label), kwEnd);
                return;
            }
        put(OKind::Label, std::move(label), j);
        return;
    }
    // Fanuc macro loops: WHILE [..] DOn / ENDn.
    auto startsWith = [&](const char* w) {
        std::size_t t = i;
        for (; *w; ++w, ++t)
            if (t >= s.size() || upper(s[t]) != *w) return false;
        return true;
    };
    if (startsWith("WHILE")) {
        // The loop number follows "DO" at the end.
        std::string label;
        std::size_t d = s.size();
        while (d > 0 && !(upper(s[d - 1]) == 'O' && d >= 2 && upper(s[d - 2]) == 'D')) --d;
        if (d > 0) {
            std::size_t t = skipSpaces(s, d);
            std::size_t u = t;
            while (u < s.size() && std::isdigit(static_cast<unsigned char>(s[u]))) ++u;
            label = std::string(s.substr(t, u - t));
        }
        put(OKind::FanucWhile, std::move(label), i + 5);
    } else if (startsWith("END") && i + 3 < s.size() &&
               std::isdigit(static_cast<unsigned char>(s[i + 3]))) {
        std::size_t u = i + 3;
        while (u < s.size() && std::isdigit(static_cast<unsigned char>(s[u]))) ++u;
        put(OKind::FanucEnd, std::string(s.substr(i + 3, u - i - 3)), 0);
    }
}


}  // namespace dexelmill::detail
