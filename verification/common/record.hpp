#pragma once
// Turning a case's result into the terminal text, Markdown and JSON records, and writing files
// without ever leaving a truncated one behind (write to a temporary name, then rename).

#include <string>

#include "case.hpp"

namespace liquid::verification {

/// {"case", "passed", "seconds", "rows" (first table), "tables", "failures", "notes", ...fields}.
Json result_json(const std::string& name, const CaseResult& result, double seconds);
std::string result_text(const std::string& name, const CaseResult& result, double seconds);
std::string result_markdown(const std::string& name, const std::string& summary, const CaseResult& result,
                            double seconds);

/// "passed", "FAILED", or for a case that asserted nothing, a sentence saying so.
std::string status_word(const CaseResult& result);

/// Checks, before any work, that `path` can be written: not empty, not a folder, its folder creatable.
/// Throws liquid::Error naming `flag` and the path.
void check_output_path(const std::string& flag, const std::string& path);

/// Writes `text` to `path` atomically (creating parent folders). Throws liquid::Error naming the path.
void write_file(const std::string& path, const std::string& text);

}  // namespace liquid::verification
