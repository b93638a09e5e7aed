/// @file gcode_source.h
/// @brief The text of one G-code file as the interpreter walks it: a table of where each line
/// starts, and the O-word (or Fanuc WHILE/END) facts of the few lines that have one. A plain line
/// (a move, a comment, a blank line) costs one offset and one bit, so a file of millions of blank
/// or comment lines stays cheap.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace dexelmill::detail {

/// @brief What an O-word line does (LinuxCNC O-codes, Fanuc program numbers, Fanuc WHILE/END).
enum class OKind {
    Label, Sub, EndSub, Call, Do, While, EndWhile, If, ElseIf, Else, EndIf, Repeat,
    EndRepeat, Break, Continue, Return,
    FanucWhile, FanucEnd
};

/// @brief The structure of one O-word line. `match` and `endIf` are line indexes, filled in when
/// the interpreter pairs the file's structures.
struct OWord {
    OKind kind = OKind::Label;
    std::string label;       ///< normalised: lower-case name, or number without leading zeros
    std::size_t argPos = 0;  ///< where the O-word's arguments start in the line
    int match = -1;  ///< sub: endsub; do: while; while: endwhile; if/elseif/else: next branch;
                     ///< repeat: endrepeat; endwhile/endrepeat/while-tail: the head
    int endIf = -1;  ///< if-chain members: the endif
    bool whileIsTail = false;
};

/// @brief One file's text, its line table and its O-word lines.
class SourceFile {
public:
    /// @brief Splits `text` into lines (LF or CRLF) and finds the O-word lines and N numbers.
    SourceFile(std::string name, std::string text);

    const std::string& name() const { return name_; }
    int lineCount() const { return int(starts_.size()) - 1; }
    /// @brief Line k (0-based) without its line end.
    std::string_view line(int k) const {
        const std::size_t b = starts_[std::size_t(k)];
        std::size_t e = starts_[std::size_t(k) + 1] - 1;
        if (e > b && text_[e - 1] == '\r') --e;
        return std::string_view(text_).substr(b, e - b);
    }
    /// @brief The 1-based line number of line k.
    static int lineNumber(int k) { return k + 1; }

    /// @brief The O-word of line k, or nullptr for a plain line.
    const OWord* oword(int k) const { return hasOWord_[std::size_t(k)] ? &owords_.at(k) : nullptr; }
    OWord* oword(int k) { return hasOWord_[std::size_t(k)] ? &owords_.at(k) : nullptr; }
    /// @brief All O-word lines by line index, for searches along the file.
    const std::map<int, OWord>& owords() const { return owords_; }
    std::map<int, OWord>& owords() { return owords_; }

    /// @brief The line that carries N number `n`, or -1.
    int lineOfN(long n) const {
        const auto it = nLines_.find(n);
        return it == nLines_.end() ? -1 : it->second;
    }
    /// @brief The first line with content is '%' (the program is wrapped in '%' lines).
    bool startsWithPercent() const { return startsWithPercent_; }
    /// @brief Lines that hold more than spaces and a comment: a first guess at the moves the file
    /// makes, which blank and comment lines do not inflate.
    std::size_t contentLines() const { return contentLines_; }

    std::uint32_t pathIndex = 0;  ///< index in ToolPath::files

private:
    void classify(int k);

    std::string name_;
    std::string text_;
    /// Start of each line, and one past the end of the text plus one: line k is
    /// [starts_[k], starts_[k + 1] - 1).
    std::vector<std::size_t> starts_;
    std::vector<bool> hasOWord_;
    std::map<int, OWord> owords_;
    std::unordered_map<long, int> nLines_;  ///< N number -> line index (Fanuc GOTO)
    bool startsWithPercent_ = false;
    std::size_t contentLines_ = 0;
};

/// @brief Index of the first character at or after i that is not a space or a tab.
inline std::size_t skipSpaces(std::string_view s, std::size_t i) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    return i;
}

}  // namespace dexelmill::detail
