#include "dexelmill/io/json_text.h"

#include <set>
#include <vector>

namespace dexelmill {

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
        if (comments && c == '/' && i + 1 < text.size() && (text[i + 1] == '/' || text[i + 1] == '*')) {
            const bool line = text[i + 1] == '/';
            const std::size_t end = text.find(line ? "\n" : "*/", i + 2);
            if (end == std::string_view::npos) return std::nullopt;
            i = end + (line ? 0 : 1);
            continue;
        }
        if (c == '"') {
            std::size_t end = i + 1;
            while (end < text.size() && text[end] != '"') end += text[end] == '\\' ? 2 : 1;
            if (end >= text.size()) return std::nullopt;
            if (!open.empty() && open.back().object && open.back().keyNext) {
                const std::string_view key = text.substr(i + 1, end - i - 1);
                if (!open.back().keys.insert(key).second)
                    return JsonTextFault{i, "the key \"" + std::string(key) + "\" is given twice in one object"};
                open.back().keyNext = false;
            }
            i = end;
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

}  // namespace dexelmill
