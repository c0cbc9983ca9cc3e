#pragma once
// Output paths checked before any work, and small text files written atomically: a run whose
// outputs cannot be written fails at once, naming the option, and never leaves a half-written file
// or a stray temporary behind.

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace liquid::io {

/// Throws liquid::Error naming `option` unless `path` can take a file: not empty, not a folder, and
/// its folder exists (or can be created) and is writable. Creates that folder.
void check_output_file(const std::string& option, const std::string& path);

/// Throws naming `option` unless `dir` is a writable folder or can be created as one (its nearest
/// existing ancestor is a writable folder). Creates nothing.
void check_output_folder(const std::string& option, const std::string& dir);

/// Throws when two of the (option, path) pairs name the same file (empty paths are skipped).
void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs);

/// Writes `text` to `path` through `path.part` and a rename (creating parent folders). Throws
/// liquid::Error naming the path; the temporary is removed on any failure.
void write_text_file(const std::string& path, const std::string& text);

/// Writes `bytes` to `path` (created or truncated) with the system's own calls. On failure removes `path` and
/// throws liquid::Error "WHO: cannot write PATH: REASON" (REASON the system's, e.g. "No space left on
/// device").
void write_file(const std::string& path, std::string_view bytes, std::string_view who);

}  // namespace liquid::io
