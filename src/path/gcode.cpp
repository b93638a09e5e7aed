/// @file gcode.cpp
/// @brief The G-code reader's entry points and the LinuxCNC tool table; the interpreter itself is
/// in path/gcode/.
#include "dexelmill/path/gcode.h"

#include <string>
#include <vector>

#include "dexelmill/error.h"
#include "path/detail/text.h"
#include "path/gcode/interpreter.h"
#include "path/gcode/texts.h"

namespace dexelmill {

using detail::upper;
using detail::gcode::Interpreter;
using detail::gcode::kInch;

std::vector<ToolTableEntry> parseLinuxCncToolTable(std::string_view text,
                                                   const std::string& fileName, bool inches) {
    std::vector<ToolTableEntry> out;
    const double scale = inches ? kInch : 1.0;
    std::size_t pos = 0;
    int lineNo = 0;
    while (pos <= text.size()) {
        std::size_t e = text.find('\n', pos);
        if (e == std::string_view::npos) e = text.size();
        std::string_view line = text.substr(pos, e - pos);
        ++lineNo;
        ToolTableEntry entry;
        entry.line = lineNo;
        bool any = false;
        std::size_t i = 0;
        while (i < line.size()) {
            const char c = upper(line[i]);
            if (c == ' ' || c == '\t' || c == '\r') { ++i; continue; }
            if (c == ';') {
                entry.comment = std::string(line.substr(i + 1));
                break;
            }
            const int col = int(i) + 1;
            if (c < 'A' || c > 'Z')
                throw ParseError({fileName, lineNo, col}, "unexpected character in tool table", std::string(1, line[i]));
            ++i;
            bool neg = false;
            if (i < line.size() && (line[i] == '-' || line[i] == '+')) neg = line[i++] == '-';
            double v;
            if (!detail::parseUnsignedDecimal(line, i, v))
                throw ParseError({fileName, lineNo, col}, "tool table word without a number", std::string(line.substr(std::size_t(col - 1), 12)));
            if (neg) v = -v;
            any = true;
            switch (c) {
            case 'T': entry.tool = int(v); break;
            case 'P': entry.pocket = int(v); break;
            case 'D': entry.diameter = v * scale; break;
            case 'Z': entry.zOffset = v * scale; break;
            default: break;  // other offsets and lathe data
            }
        }
        if (any) {
            if (entry.tool <= 0 && entry.pocket == 0)
                throw ParseError({fileName, lineNo, 1}, "tool table entry without T", std::string(line.substr(0, 40)));
            out.push_back(entry);
        }
        if (e == text.size()) break;
        pos = e + 1;
    }
    return out;
}

Program detail::gcode::runTexts(std::vector<NamedText> files, const GcodeOptions& options) {
    Program program;
    Interpreter interp(options, program);
    if (!options.toolTableFile.empty()) interp.loadToolTable(options.toolTableFile);
    for (NamedText& f : files) interp.run(std::move(f.name), std::move(f.text));
    interp.finish();
    return program;
}

Program parseGcode(std::string_view text, const std::string& fileName,
                   const GcodeOptions& options) {
    return detail::gcode::runTexts({{fileName, std::string(text)}}, options);
}

Program readGcode(const std::string& path, const GcodeOptions& options) {
    return readGcodeFiles({path}, options);
}

Program readGcodeFiles(const std::vector<std::string>& paths, const GcodeOptions& options) {
    std::vector<detail::gcode::NamedText> files;
    for (const std::string& p : paths) files.push_back({p, detail::readFile(options.files, p)});
    return detail::gcode::runTexts(std::move(files), options);
}

}  // namespace dexelmill
