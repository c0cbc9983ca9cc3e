#pragma once
// Result tables of the verification cases: printed aligned to the terminal, written as Markdown,
// and recorded as JSON rows (one object per row, keyed by column name).

#include <string>
#include <variant>
#include <vector>

#include "json.hpp"

namespace liquid::verification {

class Table {
 public:
  using Cell = std::variant<std::monostate, long, double, std::string>;

  Table(std::string title, std::vector<std::string> columns);

  /// Appends a row; it must have one cell per column (monostate prints as "-").
  void add_row(std::vector<Cell> row);

  const std::string& title() const { return title_; }
  const std::vector<std::string>& columns() const { return columns_; }
  const std::vector<std::vector<Cell>>& rows() const { return rows_; }

  std::string to_text() const;
  std::string to_markdown() const;
  Json to_json() const;

 private:
  std::string title_;
  std::vector<std::string> columns_;
  std::vector<std::vector<Cell>> rows_;
};

/// Formats a cell: integers as is, doubles in 3 significant digits (scientific when small).
std::string format_cell(const Table::Cell& cell);

}  // namespace liquid::verification
