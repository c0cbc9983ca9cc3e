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

std::vector<FlowMethod> chosen_methods(std::span<const FlowMethod> all,
                                       const std::vector<std::string>& names) {
  if (names.empty()) return {all.begin(), all.end()};
  std::vector<FlowMethod> out;
  std::vector<std::string> known;
  for (const FlowMethod& m : all) known.emplace_back(m.name);
  for (const std::string& name : names) {
    const auto it = std::find(known.begin(), known.end(), name);
    if (it == known.end())
      throw Error(fmt::format("--methods: '{}' is not a method of this case (its methods: {})", name,
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

double seconds_at_error(const std::vector<double>& errors, const std::vector<double>& seconds, double target,
                        Reach& how) {
  std::vector<std::pair<double, double>> pts;  // (log error, log seconds)
  for (std::size_t i = 0; i < errors.size() && i < seconds.size(); ++i)
    if (errors[i] > 0.0 && seconds[i] > 0.0) pts.emplace_back(std::log(errors[i]), std::log(seconds[i]));
  std::sort(pts.begin(), pts.end());
  const double x = std::log(target);
  how = Reach::interpolated;
  if (!pts.empty() && x >= pts.back().first) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& p : pts) best = std::min(best, p.second);
    how = Reach::at_most;
    return std::exp(best);
  }
  for (std::size_t i = 0; i + 1 < pts.size(); ++i)
    if (pts[i].first <= x && x <= pts[i + 1].first && pts[i + 1].first > pts[i].first) {
      const double f = (x - pts[i].first) / (pts[i + 1].first - pts[i].first);
      return std::exp(pts[i].second + f * (pts[i + 1].second - pts[i].second));
    }
  how = Reach::extrapolated;
  if (pts.size() < 2) return pts.empty() ? NAN : std::exp(pts[0].second);
  // The power law through the points' mean with fit_order's least-squares slope (log base is moot).
  std::vector<double> e, t;
  double mx = 0, my = 0;
  for (const auto& p : pts) {
    e.push_back(std::exp(p.first)), t.push_back(std::exp(p.second));
    mx += p.first / static_cast<double>(pts.size()), my += p.second / static_cast<double>(pts.size());
  }
  const double slope = fit_order(e, t);
  return std::exp(my + (std::isfinite(slope) ? slope : 0.0) * (x - mx));
}

}  // namespace liquid::verification
