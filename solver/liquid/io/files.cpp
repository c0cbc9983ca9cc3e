#include "liquid/io/files.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "liquid/core/error.hpp"

namespace liquid::io {

namespace fs = std::filesystem;

namespace {

/// Creates `folder` if needed and checks that this process may add files to it (access(2): also
/// a read-only file system).
void writable_folder(const std::string& option, const fs::path& folder, const std::string& what) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  LIQUID_VERIFY(!ec && fs::is_directory(folder), "{}: cannot create the folder '{}'{}: {}", option,
                folder.string(), what, ec ? ec.message() : "a file of that name is in the way");
  LIQUID_VERIFY(::access(folder.c_str(), W_OK | X_OK) == 0, "{}: the folder '{}'{} is not writable: {}",
                option, folder.string(), what, std::strerror(errno));
}

}  // namespace

void check_output_file(const std::string& option, const std::string& path) {
  LIQUID_VERIFY(!path.empty(), "{}: the path is empty", option);
  const fs::path target(path);
  LIQUID_VERIFY(!fs::is_directory(target), "{}: '{}' is a folder, not a file", option, path);
  LIQUID_VERIFY(target.has_filename(), "{}: '{}' names no file", option, path);
  writable_folder(option, target.has_parent_path() ? target.parent_path() : fs::path("."),
                  " of '" + path + "'");
  if (fs::exists(target))
    LIQUID_VERIFY(::access(target.c_str(), W_OK) == 0, "{}: '{}' is not writable: {}", option, path,
                  std::strerror(errno));
}

void check_output_folder(const std::string& option, const std::string& dir) {
  LIQUID_VERIFY(!dir.empty(), "{}: the folder name is empty", option);
  LIQUID_VERIFY(!fs::exists(dir) || fs::is_directory(dir), "{}: '{}' is a file, not a folder", option, dir);
  // Nothing is created here (a run refused later leaves no folder): the nearest folder that exists
  // must take the new ones.
  fs::path existing = fs::absolute(fs::path(dir));
  while (!fs::exists(existing) && existing.has_parent_path() && existing != existing.parent_path())
    existing = existing.parent_path();
  LIQUID_VERIFY(fs::is_directory(existing), "{}: cannot make the folder '{}': '{}' is a file", option, dir,
                existing.string());
  LIQUID_VERIFY(::access(existing.c_str(), W_OK | X_OK) == 0, "{}: cannot write in '{}'{}: {}", option,
                existing.string(), existing == fs::absolute(fs::path(dir)) ? "" : " (to make '" + dir + "')",
                std::strerror(errno));
}

void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i)
    for (std::size_t j = i + 1; j < outputs.size(); ++j) {
      if (outputs[i].second.empty() || outputs[j].second.empty()) continue;
      std::error_code ea, eb;
      const fs::path a = fs::weakly_canonical(outputs[i].second, ea);
      const fs::path b = fs::weakly_canonical(outputs[j].second, eb);
      LIQUID_VERIFY((ea || eb) ? outputs[i].second != outputs[j].second : a != b,
                    "{} and {} name the same file '{}': one would overwrite the other", outputs[i].first,
                    outputs[j].first, outputs[i].second);
    }
}

void write_file(const std::string& path, std::string_view bytes, std::string_view who) {
  const auto fail = [&](int error, int fd) {
    if (fd >= 0) ::close(fd);
    std::error_code ignored;
    fs::remove(path, ignored);
    throw Error(fmt::format("{}: cannot write {}: {}", who, path, std::strerror(error)));
  };
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) fail(errno, -1);
  const char* at = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, at, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(n < 0 ? errno : ENOSPC, fd);
    at += n;
    left -= static_cast<std::size_t>(n);
  }
  // Not synced to the device (a killed process loses nothing the kernel holds); a file system
  // that reports a full disk only at close is heard here.
  if (::close(fd) != 0) fail(errno, -1);
}

void write_text_file(const std::string& path, const std::string& text) {
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  LIQUID_VERIFY(!ec, "cannot create the folder of '{}': {}", path, ec.message());
  const fs::path tmp = target.string() + ".part";
  write_file(tmp.string(), text, "write");
  fs::rename(tmp, target, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
  }
  LIQUID_VERIFY(!ec, "cannot move '{}' to '{}': {}", tmp.string(), path, ec.message());
}

}  // namespace liquid::io
