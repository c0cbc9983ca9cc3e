#pragma once
// Phase timers: every step of a solver is a list of named phases; each phase accumulates its wall
// time under a stable name so reports can show the paper's Table 1 columns.

#include <chrono>
#include <map>
#include <string>

namespace liquid {

/// Wall-clock stopwatch in seconds.
class Stopwatch {
 public:
  Stopwatch() : start_(clock::now()) {}
  void restart() { start_ = clock::now(); }
  double seconds() const { return std::chrono::duration<double>(clock::now() - start_).count(); }

 private:
  using clock = std::chrono::steady_clock;
  clock::time_point start_;
};

/// Accumulated seconds and call counts per phase name.
class PhaseTimer {
 public:
  struct Entry {
    double seconds = 0.0;
    long calls = 0;
  };

  /// Times the enclosing scope under `name`.
  class Scope {
   public:
    Scope(PhaseTimer& timer, std::string name) : timer_(timer), name_(std::move(name)) {}
    ~Scope() { timer_.add(name_, watch_.seconds()); }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    PhaseTimer& timer_;
    std::string name_;
    Stopwatch watch_;
  };

  Scope scope(std::string name) { return Scope(*this, std::move(name)); }
  void add(const std::string& name, double seconds) {
    auto& e = entries_[name];
    e.seconds += seconds;
    ++e.calls;
  }
  const std::map<std::string, Entry>& entries() const { return entries_; }
  double seconds(const std::string& name) const {
    auto it = entries_.find(name);
    return it == entries_.end() ? 0.0 : it->second.seconds;
  }
  void clear() { entries_.clear(); }

 private:
  std::map<std::string, Entry> entries_;
};

}  // namespace liquid
