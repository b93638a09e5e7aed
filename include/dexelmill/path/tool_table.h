/// @file tool_table.h
/// @brief LinuxCNC tool tables (`tool.tbl`): the tools a G-code program calls by T word, each a line
///
///     T4 P4 Z+30.5 D10 ;end mill
///
/// of words, a letter and a number each, in any order, then an optional comment after ';'. T is the
/// tool number, P its pocket, D its diameter; X Y Z A B C U V W are its offsets (Z the tool
/// length), and I J Q a lathe tool's angles and orientation. The table holds no shape.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dexelmill/error.h"

namespace dexelmill {

/// @brief One line of a tool table, in the table's units.
struct ToolTableEntry {
    int number = 0;
    std::optional<double> diameter;  ///< D; none where the line does not give it
    /// The letters of the offsets other than Z given non-zero, in the order written ("X, Y"):
    /// they shift the point the program moves, which the reader takes as the tip.
    std::string offsets;
    /// The lathe words given (I, J, Q), as `offsets`.
    std::string latheWords;
    std::string comment;   ///< after ';', trimmed
    SourceLocation where;  ///< the T word
};

/// @brief The entries of a tool table's text, in the order written. Blank lines and lines that are
/// only a comment are skipped.
/// @throw ParseError at the word that is wrong: a letter the table does not use, a word without
/// its number, a line without T, a T or P that is not a whole number of 0 or more, a word given twice
/// on a line, a negative D, or a T given on two lines.
std::vector<ToolTableEntry> parseToolTable(const std::string& text, const std::string& name);

/// @brief parseToolTable on a file's text.
/// @throw Error naming the file when it cannot be read.
std::vector<ToolTableEntry> readToolTable(const std::string& path);

}  // namespace dexelmill
