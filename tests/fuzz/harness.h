// What the fuzz targets share: the command line's reading options for a process that may use
// kMemory, and programs that name other files (subroutines, a project's programs, a machine) read
// from the input itself rather than from disk.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <string_view>

#include "dexelmill/job/memory.h"
#include "dexelmill/job/simulate.h"
#include "dexelmill/path/gcode.h"

namespace fuzz {

/// The memory a target may use, as `--max-memory 1G` would give the command line. libFuzzer's
/// -rss_limit_mb (2048 in smoke.sh and in campaigns) leaves the rest to the sanitizers.
constexpr std::size_t kMemory = std::size_t(1) << 30;

/// The command line's G-code options for kMemory, taken once: the move limit then does not shrink
/// as the fuzzer's own memory grows.
inline const dexelmill::GcodeOptions& gcodeOptions() {
    static const dexelmill::GcodeOptions options =
        dexelmill::jobGcodeOptions(dexelmill::SimulateOptions().chordTolerance, dexelmill::memoryBudget(kMemory));
    return options;
}

/// An input as files: the text before the first line "//@file NAME" is the file `mainName`, and
/// each such line starts the file NAME.
inline std::map<std::string, std::string> splitFiles(std::string_view input, const std::string& mainName) {
    static constexpr std::string_view kMarker = "//@file ";
    std::map<std::string, std::string> files;
    std::string name = mainName;
    std::size_t start = 0;
    std::size_t lineStart = 0;
    while (lineStart <= input.size()) {
        std::size_t end = input.find('\n', lineStart);
        if (end == std::string_view::npos) end = input.size();
        if (input.compare(lineStart, kMarker.size(), kMarker) == 0) {
            files[name] = std::string(input.substr(start, lineStart - start));
            name = std::string(input.substr(lineStart + kMarker.size(), end - lineStart - kMarker.size()));
            start = std::min(end + 1, input.size());
        }
        lineStart = end + 1;
    }
    files[name] = std::string(input.substr(start));
    return files;
}

/// The readers' FileSource over `files` (which must outlive it).
inline dexelmill::FileSource sourceOf(const std::map<std::string, std::string>& files) {
    return [&files](const std::string& path) -> std::optional<std::string> {
        const auto it = files.find(path);
        if (it == files.end()) return std::nullopt;
        return it->second;
    };
}

/// The --machine an input asks for: the text of its file "machine" ("//@file machine"), spaces
/// and line ends trimmed, naming a built-in machine or another file of the input that describes
/// one. Empty where it has none, as a command line without --machine.
inline std::string machineOf(const std::map<std::string, std::string>& files) {
    const auto it = files.find("machine");
    if (it == files.end()) return {};
    const std::string& text = it->second;
    const std::size_t first = text.find_first_not_of(" \t\r\n");
    if (first == std::string::npos) return {};
    return text.substr(first, text.find_last_not_of(" \t\r\n") + 1 - first);
}

}  // namespace fuzz
