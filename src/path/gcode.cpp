/// @file gcode.cpp
/// @brief The G-code reader's entry points; the interpreter itself is in path/gcode/.
#include "dexelmill/path/gcode.h"

#include <string>
#include <vector>

#include "dexelmill/error.h"
#include "path/detail/text.h"
#include "path/gcode/interpreter.h"
#include "path/gcode/texts.h"

namespace dexelmill {

using detail::gcode::Interpreter;

Program detail::gcode::runTexts(std::vector<NamedText> files, const GcodeOptions& options) {
    Program program;
    Interpreter interp(options, program);
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
