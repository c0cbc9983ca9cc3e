#include "studies/flow_measures.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/fit.hpp"
#include "liquid/core/error.hpp"
#include "liquid/transfer/patches.hpp"
#include "liquid/transfer/regular.hpp"

namespace liquid::verification {

std::string band_note(int band) {
  return fmt::format(
      "adaptive runs: cells within {} face hop{} of a surface cell at the finest level "
      "(--band; the default and the paper's: {}; a reference run keeps the default)",
      band, band == 1 ? "" : "s", pic::PicOptions<3>{}.band);
}

std::vector<FlowMethod> chosen_methods(std::span<const FlowMethod> all, const std::vector<std::string>& names,
                                       const char* flag) {
  if (names.empty()) return {all.begin(), all.end()};
  std::vector<FlowMethod> out;
  std::vector<std::string> known;
  for (const FlowMethod& m : all) known.emplace_back(m.name);
  for (const std::string& name : names) {
    const auto it = std::find(known.begin(), known.end(), name);
    if (it == known.end())
      throw Error(fmt::format("{}: '{}' is not a method of this case (its methods: {})", flag, name,
                              fmt::join(known, ", ")));
    out.push_back(all[static_cast<std::size_t>(it - known.begin())]);
  }
  return out;
}

template <int Dim>
std::vector<double> particle_volumes(const tree::CellGraph<Dim>& graph, std::span<const Vec<Dim>> x,
                                     double volume, double* filled) {
  std::vector<tree::CellId> cell(x.size());
  std::vector<int> count(graph.cell_capacity(), 0);
  tree::CellId hint = tree::no_cell;
  for (std::size_t i = 0; i < x.size(); ++i) {
    hint = hint == tree::no_cell ? graph.locate(x[i]) : graph.locate(x[i], hint);
    cell[i] = hint;
    ++count[hint];
  }
  const int full = 1 << Dim;  // particles a full cell is seeded with
  std::vector<double> out(x.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    out[i] = graph.cell_size(cell[i]).prod() / std::max(count[cell[i]], full);
    sum += out[i];
  }
  if (filled) *filled = sum;
  if (sum > 0.0)
    for (double& v : out) v *= volume / sum;
  return out;
}

template <int Dim>
double affine_energy(const pic::AdaptivePic<Dim>& sim, std::span<const double> w) {
  const particles::Particles<Dim>& p = sim.particles();
  const int c = p.find_field("apic");
  if (c < 0) return 0.0;
  if (sim.options().transfer == pic::PicTransfer::apic)
    return transfer::particle_affine_energy<Dim>(transfer::RegularLattice<Dim>(sim.graph()), p, p.field(c),
                                                 w);
  // Adaptive RBF with uniform patches: each particle's C in the lattice of its cell's level.
  const std::span<const double> affine = p.field(c);
  double total = 0.0;
  tree::CellId hint = tree::no_cell;
  for (int i = 0; i < p.size(); ++i) {
    hint = hint == tree::no_cell ? sim.graph().locate(p.x[i]) : sim.graph().locate(p.x[i], hint);
    if (sim.graph().level(hint) < 1) continue;
    for (int k = 0; k < Dim; ++k) {
      const Vec<Dim> ck = Eigen::Map<const Vec<Dim>>(affine.data() + (i * Dim + k) * Dim);
      total += 0.5 * (w.empty() ? 1.0 : w[i]) *
               ck.dot(transfer::patch_inertia<Dim>(sim.graph(), hint, k, p.x[i]) * ck);
    }
  }
  return total;
}

template <int Dim>
double twice_kinetic_energy(const pic::AdaptivePic<Dim>& sim, double volume) {
  const particles::Particles<Dim>& p = sim.particles();
  const std::vector<double> w = particle_volumes<Dim>(sim.graph(), p.x, volume);
  double sum = 0.0;
  for (int i = 0; i < p.size(); ++i) sum += w[i] * p.v[i].squaredNorm();
  return sum + 2.0 * affine_energy<Dim>(sim, w);
}

template std::vector<double> particle_volumes<2>(const tree::CellGraph<2>&, std::span<const Vec<2>>, double,
                                                 double*);
template std::vector<double> particle_volumes<3>(const tree::CellGraph<3>&, std::span<const Vec<3>>, double,
                                                 double*);
template double affine_energy<2>(const pic::AdaptivePic<2>&, std::span<const double>);
template double affine_energy<3>(const pic::AdaptivePic<3>&, std::span<const double>);
template double twice_kinetic_energy<2>(const pic::AdaptivePic<2>&, double);
template double twice_kinetic_energy<3>(const pic::AdaptivePic<3>&, double);

namespace {

/// A method's runs as (log error, log seconds), by error; runs without a positive error and time left out.
std::vector<std::pair<double, double>> log_points(const std::vector<double>& errors,
                                                  const std::vector<double>& seconds) {
  std::vector<std::pair<double, double>> pts;
  for (std::size_t i = 0; i < errors.size() && i < seconds.size(); ++i)
    if (errors[i] > 0.0 && seconds[i] > 0.0) pts.emplace_back(std::log(errors[i]), std::log(seconds[i]));
  std::sort(pts.begin(), pts.end());
  return pts;
}

/// Log seconds at log error x between the two points that bracket it; NaN when none do.
double between(const std::vector<std::pair<double, double>>& pts, double x) {
  for (std::size_t i = 0; i + 1 < pts.size(); ++i)
    if (pts[i].first <= x && x <= pts[i + 1].first && pts[i + 1].first > pts[i].first) {
      const double f = (x - pts[i].first) / (pts[i + 1].first - pts[i].first);
      return pts[i].second + f * (pts[i + 1].second - pts[i].second);
    }
  for (const auto& p : pts)  // a single run, or runs of equal error
    if (p.first == x) return p.second;
  return NAN;
}

double cheapest(const std::vector<std::pair<double, double>>& pts) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : pts) best = std::min(best, p.second);
  return std::exp(best);
}

}  // namespace

const char* reach_text(Reach how) {
  switch (how) {
    case Reach::run:
      return "the run";
    case Reach::interpolated:
      return "log-log between two runs";
    case Reach::at_most:
      return "at most: its cheapest run, already more accurate";
    case Reach::at_least:
      return "at least: its most accurate run, not as accurate";
  }
  return "?";
}

SecondsAt seconds_at(const ErrorCurve& curve, double error) {
  const auto pts = log_points(curve.errors, curve.seconds);
  LIQUID_VERIFY(!pts.empty() && error > 0.0, "{}: no run with a positive error and time to read {:g} from",
                curve.name, error);
  const double x = std::log(error);
  if (x < pts.front().first) {
    // More accurate than any run: at least what the most accurate run took.
    return {std::exp(pts.front().second), Reach::at_least};
  }
  if (x > pts.back().first) return {cheapest(pts), Reach::at_most};
  return {std::exp(between(pts, x)), Reach::interpolated};
}

EqualErrorRow speed_at_error(const ErrorCurve& method, std::span<const ErrorCurve> others, double error) {
  LIQUID_VERIFY(!others.empty(), "{}: no other method to compare with", method.name);
  EqualErrorRow row;
  row.error = error;
  row.seconds = seconds_at(method, error).seconds;
  // The fastest other's time T = min over the others: bounded below by each one's value or lower
  // bound (an upper bound says nothing below), above by each one's value or upper bound.
  // The method named is the one setting the upper bound where there is one, else the lower one.
  const double inf = std::numeric_limits<double>::infinity();
  double below = inf, above = inf;
  const ErrorCurve *by_below = nullptr, *by_above = nullptr;
  SecondsAt s_below, s_above;
  for (const ErrorCurve& c : others) {
    const SecondsAt s = seconds_at(c, error);
    const double b = s.how == Reach::at_most ? 0.0 : s.seconds;
    const double a = s.how == Reach::at_least ? inf : s.seconds;
    if (by_below == nullptr || b < below) below = b, by_below = &c, s_below = s;
    if (a < above) above = a, by_above = &c, s_above = s;
  }
  row.fastest = by_above != nullptr ? by_above->name : by_below->name;
  row.other = by_above != nullptr ? s_above : s_below;
  row.low = below / row.seconds;
  row.high = above / row.seconds;
  return row;
}

std::vector<EqualErrorRow> speed_at_equal_error(const ErrorCurve& method,
                                                std::span<const ErrorCurve> others) {
  std::vector<EqualErrorRow> rows;
  const auto own = log_points(method.errors, method.seconds);
  if (own.size() < 2 || others.empty()) return rows;
  // The range from the errors themselves (exp of their logs may round off the ends).
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (std::size_t i = 0; i < method.errors.size() && i < method.seconds.size(); ++i)
    if (method.errors[i] > 0.0 && method.seconds[i] > 0.0)
      lo = std::min(lo, method.errors[i]), hi = std::max(hi, method.errors[i]);
  std::vector<double> at;
  const auto take = [&](const ErrorCurve& c) {
    for (std::size_t i = 0; i < c.errors.size() && i < c.seconds.size(); ++i)
      if (c.errors[i] >= lo && c.errors[i] <= hi && c.seconds[i] > 0.0) at.push_back(c.errors[i]);
  };
  take(method);
  for (const ErrorCurve& c : others) take(c);
  std::sort(at.rbegin(), at.rend());
  at.erase(std::unique(at.begin(), at.end()), at.end());
  for (double e : at) rows.push_back(speed_at_error(method, others, e));
  return rows;
}

std::string speedup_text(const EqualErrorRow& row) {
  const auto x = [](double v) { return fmt::format("{:.2g}x", v); };
  if (row.low == row.high) return x(row.low);
  if (!std::isfinite(row.high)) return ">= " + x(row.low);
  if (row.low <= 0.0) return "<= " + x(row.high);
  return x(row.low) + " to " + x(row.high);
}

Table equal_error_table(const std::vector<EqualErrorRow>& rows, const std::string& title,
                        const std::string& error, const std::string& method) {
  Table t(title, {error, method + " seconds", "fastest other", "its seconds", "read as", "speed-up"});
  for (const EqualErrorRow& row : rows) {
    t.add_row({row.error, row.seconds, row.fastest, row.other.seconds, std::string(reach_text(row.other.how)),
               speedup_text(row)});
  }
  return t;
}

std::string equal_error_summary(const std::vector<EqualErrorRow>& rows) {
  std::string s;
  for (const EqualErrorRow& row : rows)
    s += fmt::format("{}{} at {:.2g}", s.empty() ? "" : ", ", speedup_text(row), row.error);
  return s;
}

}  // namespace liquid::verification
