#include "liquid/io/series.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <regex>
#include <set>
#include <utility>

#include "liquid/core/error.hpp"
#include "liquid/io/hdf5_detail.hpp"

namespace liquid::io {

namespace {

constexpr const char* who = "SeriesWriter";

std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
}

std::string xml_escaped(const std::string& text) {
  std::string out;
  for (char ch : text) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += ch;
    }
  }
  return out;
}

/// `grid` trimmed and checked to be one <Grid ...>...</Grid> element; `where` names it in errors.
std::string checked_grid(const std::string& grid, const std::string& where) {
  std::string text = trimmed(grid);
  static const std::regex open(R"(^<Grid[\s>])");
  const std::string close = "</Grid>";
  LIQUID_VERIFY(std::regex_search(text, open) && text.size() >= close.size() &&
                    text.compare(text.size() - close.size(), close.size(), close) == 0,
                "SeriesWriter: {} is not one XDMF <Grid ...>...</Grid> element (it starts '{}')", where,
                text.substr(0, 40));
  return text;
}

/// Gives every grid of a frame a Name no other grid of the frame has: the second "cells" becomes
/// "cells_2", a grid without a Name gets "grid".
void name_uniquely(std::vector<std::string>& grids) {
  static const std::regex name(R"re(\sName="([^"]*)")re");
  std::set<std::string> used;
  for (std::string& grid : grids) {
    const std::size_t tag_end = grid.find('>');
    const std::string tag = grid.substr(0, tag_end);
    std::smatch m;
    const bool named = std::regex_search(tag, m, name);
    const std::string base = named && !m[1].str().empty() ? m[1].str() : "grid";
    std::string unique = base;
    for (int k = 2; used.count(unique); ++k) unique = fmt::format("{}_{}", base, k);
    used.insert(unique);
    if (named && unique == m[1].str()) continue;
    const std::string attribute = fmt::format(" Name=\"{}\"", unique);
    if (named)
      grid.replace(static_cast<std::size_t>(m.position(0)), static_cast<std::size_t>(m.length(0)), attribute);
    else
      grid.insert(std::string("<Grid").size(), attribute);
  }
}

}  // namespace

SeriesWriter::SeriesWriter(std::string path) : path_(std::move(path)) {}

SeriesWriter::SeriesWriter(std::string path, std::vector<SeriesFrame> frames) : path_(std::move(path)) {
  restore(std::move(frames));
}

void SeriesWriter::append(double time, std::vector<std::string> grids) {
  LIQUID_VERIFY(std::isfinite(time), "SeriesWriter: the time of a frame of {} must be finite, not {}", path_,
                time);
  LIQUID_VERIFY(
      frames_.empty() || time > frames_.back().time,
      "SeriesWriter: a frame at time {} cannot follow the frame at time {} in {} (times must increase)", time,
      frames_.empty() ? 0.0 : frames_.back().time, path_);
  LIQUID_VERIFY(!grids.empty(), "SeriesWriter: the frame at time {} of {} has no grid", time, path_);
  for (std::size_t g = 0; g < grids.size(); ++g)
    grids[g] = checked_grid(grids[g], fmt::format("grid {} of the frame at time {} of {}", g, time, path_));
  name_uniquely(grids);
  frames_.push_back({time, std::move(grids)});
}

void SeriesWriter::add(double time, std::vector<std::string> grids) {
  std::vector<SeriesFrame> old = frames_;
  append(time, std::move(grids));
  write_or_restore(std::move(old));
}

void SeriesWriter::truncate_after(double time) {
  LIQUID_VERIFY(!std::isnan(time), "SeriesWriter: truncate_after(NaN) on {}", path_);
  std::vector<SeriesFrame> old = frames_;
  while (!frames_.empty() && frames_.back().time > time) frames_.pop_back();
  write_or_restore(std::move(old));
}

void SeriesWriter::restore(std::vector<SeriesFrame> frames) {
  std::vector<SeriesFrame> old = std::exchange(frames_, {});
  try {
    for (SeriesFrame& f : frames) append(f.time, std::move(f.grids));
  } catch (...) {
    frames_ = std::move(old);
    throw;
  }
  write_or_restore(std::move(old));
}

void SeriesWriter::write_or_restore(std::vector<SeriesFrame> old) {
  try {
    write();
  } catch (...) {
    frames_ = std::move(old);
    throw;
  }
}

void SeriesWriter::write() const {
  const std::string name = std::filesystem::path(path_).stem().string();
  std::string series = fmt::format("<Grid Name=\"{}\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
                                   xml_escaped(name.empty() ? "series" : name));
  for (std::size_t i = 0; i < frames_.size(); ++i) {
    const SeriesFrame& f = frames_[i];
    series +=
        fmt::format("  <Grid Name=\"frame_{}\" GridType=\"Collection\" CollectionType=\"Spatial\">\n", i);
    series += fmt::format("    <Time Value=\"{}\"/>\n", f.time);
    for (const std::string& grid : f.grids) series += detail::indent(grid, 4) + "\n";
    series += "  </Grid>\n";
  }
  series += "</Grid>";
  const std::string tmp = path_ + ".tmp";
  write_file(tmp, detail::xdmf_document(series), who);
  detail::rename_file(tmp, path_, who);
}

}  // namespace liquid::io
