#include "table.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "liquid/core/error.hpp"

namespace liquid::verification {

Table::Table(std::string title, std::vector<std::string> columns)
    : title_(std::move(title)), columns_(std::move(columns)) {}

void Table::add_row(std::vector<Cell> row) {
  LIQUID_VERIFY(row.size() == columns_.size(), "table '{}' has {} columns, row has {}", title_,
                columns_.size(), row.size());
  rows_.push_back(std::move(row));
}

std::string format_cell(const Table::Cell& cell) {
  if (std::holds_alternative<std::monostate>(cell)) return "-";
  if (const long* i = std::get_if<long>(&cell)) return fmt::format("{}", *i);
  if (const auto* s = std::get_if<std::string>(&cell)) return *s;
  const double d = std::get<double>(cell);
  if (!std::isfinite(d)) return fmt::format("{}", d);
  const double a = std::abs(d);
  if (a != 0.0 && (a < 1e-2 || a >= 1e5)) return fmt::format("{:.3e}", d);
  return fmt::format("{:.3f}", d);
}

std::string Table::to_text() const {
  std::vector<std::size_t> width(columns_.size());
  for (std::size_t c = 0; c < columns_.size(); ++c) width[c] = columns_[c].size();
  for (const auto& row : rows_)
    for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], format_cell(row[c]).size());
  std::string out = title_ + "\n";
  auto line = [&](auto cell_text) {
    std::string l;
    for (std::size_t c = 0; c < columns_.size(); ++c) l += fmt::format("  {:>{}}", cell_text(c), width[c]);
    return l + "\n";
  };
  out += line([&](std::size_t c) { return columns_[c]; });
  out += line([&](std::size_t c) { return std::string(width[c], '-'); });
  for (const auto& row : rows_) out += line([&](std::size_t c) { return format_cell(row[c]); });
  return out;
}

std::string Table::to_markdown() const {
  std::string out = "**" + title_ + "**\n\n|";
  for (const auto& c : columns_) out += " " + c + " |";
  out += "\n|";
  for (std::size_t c = 0; c < columns_.size(); ++c) out += " ---: |";
  out += "\n";
  for (const auto& row : rows_) {
    out += "|";
    for (const auto& cell : row) out += " " + format_cell(cell) + " |";
    out += "\n";
  }
  return out;
}

Json Table::to_json() const {
  Json rows = Json::array();
  for (const auto& row : rows_) {
    Json r = Json::object();
    for (std::size_t c = 0; c < columns_.size(); ++c) {
      const Table::Cell& cell = row[c];
      if (std::holds_alternative<std::monostate>(cell))
        r.set(columns_[c], nullptr);
      else if (const long* i = std::get_if<long>(&cell))
        r.set(columns_[c], *i);
      else if (const double* d = std::get_if<double>(&cell))
        r.set(columns_[c], *d);
      else
        r.set(columns_[c], std::get<std::string>(cell));
    }
    rows.push(std::move(r));
  }
  return rows;
}

}  // namespace liquid::verification
