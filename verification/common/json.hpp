#pragma once
// A small JSON value for the verification records (write-only, keys kept in insertion order).

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace liquid::verification {

class Json {
 public:
  using Array = std::vector<Json>;
  using Object = std::vector<std::pair<std::string, Json>>;

  Json() : value_(nullptr) {}
  Json(std::nullptr_t) : value_(nullptr) {}
  Json(bool b) : value_(b) {}
  Json(int i) : value_(static_cast<double>(i)) {}
  Json(long i) : value_(static_cast<double>(i)) {}
  Json(double d) : value_(d) {}
  Json(const char* s) : value_(std::string(s)) {}
  Json(std::string s) : value_(std::move(s)) {}
  Json(Array a) : value_(std::move(a)) {}
  Json(Object o) : value_(std::move(o)) {}

  static Json object() { return Json(Object{}); }
  static Json array() { return Json(Array{}); }

  /// Sets (or replaces) a key of an object.
  Json& set(const std::string& key, Json value);
  /// Appends to an array.
  Json& push(Json value);
  /// The value at key of an object, or nullptr when absent.
  const Json* find(const std::string& key) const;

  /// The members of an object (nullptr for any other kind), in insertion order.
  const Object* items() const { return std::get_if<Object>(&value_); }

  bool is_number() const { return std::holds_alternative<double>(value_); }
  double number() const { return std::get<double>(value_); }

  /// Serialises with two-space indentation. Non-finite numbers become null.
  std::string dump(int indent = 0) const;

 private:
  std::variant<std::nullptr_t, bool, double, std::string, Array, Object> value_;
};

}  // namespace liquid::verification
