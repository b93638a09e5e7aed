/// @file diagnostics.h
/// @brief Collects reader warnings, aggregating repeats: the first occurrence of each kind is
/// kept with its place, and later ones are counted, so a long program does not produce one
/// warning per line and nothing is lost.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "dexelmill/path/toolpath.h"

namespace dexelmill::detail {

class DiagnosticCollector {
public:
    /// @brief Reports `message` at `where`. Reports with the same `key` after the first are
    /// counted; the key defaults to the message.
    /// @return the index of the entry, for repeat().
    std::size_t add(Diagnostic::Severity severity, const SourceLocation& where,
                    std::string message, const std::string& key = {}) {
        const std::string k = key.empty() ? message : key;
        auto it = index_.find(k);
        if (it != index_.end()) {
            ++entries_[it->second].count;
            return it->second;
        }
        index_.emplace(k, entries_.size());
        entries_.push_back({Diagnostic{severity, where, std::move(message)}, 1});
        return entries_.size() - 1;
    }
    std::size_t warn(const SourceLocation& where, std::string message,
                     const std::string& key = {}) {
        return add(Diagnostic::Severity::Warning, where, std::move(message), key);
    }
    std::size_t note(const SourceLocation& where, std::string message,
                     const std::string& key = {}) {
        return add(Diagnostic::Severity::Note, where, std::move(message), key);
    }
    /// @brief Counts one more occurrence of entry `index` (cheap path for hot warnings).
    void repeat(std::size_t index) { ++entries_[index].count; }

    /// @brief The diagnostics in order of first occurrence, with repeat counts in the message.
    void appendTo(std::vector<Diagnostic>& out) const {
        for (const Entry& e : entries_) {
            Diagnostic d = e.diagnostic;
            if (e.count > 1)
                d.message += " (" + std::to_string(e.count) + " occurrences, first shown)";
            out.push_back(std::move(d));
        }
    }

private:
    struct Entry {
        Diagnostic diagnostic;
        std::size_t count = 0;
    };
    std::vector<Entry> entries_;
    std::unordered_map<std::string, std::size_t> index_;
};

}  // namespace dexelmill::detail
