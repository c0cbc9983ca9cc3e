#include "json.hpp"

#include <cmath>

#include <fmt/format.h>

namespace liquid::verification {

Json& Json::set(const std::string& key, Json value) {
  auto& obj = std::get<Object>(value_);
  for (auto& [k, v] : obj)
    if (k == key) {
      v = std::move(value);
      return *this;
    }
  obj.emplace_back(key, std::move(value));
  return *this;
}

Json& Json::push(Json value) {
  std::get<Array>(value_).push_back(std::move(value));
  return *this;
}

const Json* Json::find(const std::string& key) const {
  if (const auto* obj = std::get_if<Object>(&value_))
    for (const auto& [k, v] : *obj)
      if (k == key) return &v;
  return nullptr;
}

namespace {
std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20)
          out += fmt::format("\\u{:04x}", c);
        else
          out += c;
    }
  }
  return out + "\"";
}
}  // namespace

std::string Json::dump(int indent) const {
  const std::string pad(indent + 2, ' '), end_pad(indent, ' ');
  if (std::holds_alternative<std::nullptr_t>(value_)) return "null";
  if (const bool* b = std::get_if<bool>(&value_)) return *b ? "true" : "false";
  if (const double* d = std::get_if<double>(&value_)) {
    if (!std::isfinite(*d)) return "null";
    if (*d == std::floor(*d) && std::abs(*d) < 1e15) return fmt::format("{:.0f}", *d);
    return fmt::format("{:.17g}", *d);
  }
  if (const auto* s = std::get_if<std::string>(&value_)) return quote(*s);
  if (const auto* a = std::get_if<Array>(&value_)) {
    if (a->empty()) return "[]";
    std::string out = "[\n";
    for (std::size_t i = 0; i < a->size(); ++i)
      out += pad + (*a)[i].dump(indent + 2) + (i + 1 < a->size() ? ",\n" : "\n");
    return out + end_pad + "]";
  }
  const auto& o = std::get<Object>(value_);
  if (o.empty()) return "{}";
  std::string out = "{\n";
  for (std::size_t i = 0; i < o.size(); ++i)
    out += pad + quote(o[i].first) + ": " + o[i].second.dump(indent + 2) + (i + 1 < o.size() ? ",\n" : "\n");
  return out + end_pad + "}";
}

}  // namespace liquid::verification
