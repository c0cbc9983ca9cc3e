#include "studies/paper_studies.hpp"

#include <algorithm>
#include <numbers>

#include "liquid/levelset/levelset.hpp"
#include "liquid/tree/builders.hpp"
#include "support/manufactured.hpp"

namespace liquid::verification {

template <int Dim>
PoissonStudy<Dim> neumann_study(bool full) {
  PoissonStudy<Dim> s;
  s.domain = Box<Dim>{Vec<Dim>::Zero(), Vec<Dim>::Constant(std::numbers::pi)};
  s.use(support::cosine_product<Dim>());
  const auto circle = levelset::sphere<Dim>(Vec<Dim>::Constant(0.5 * std::numbers::pi), 0.9);
  const Box<Dim> domain = s.domain;
  s.make_tree = [domain, circle](int level, const tree::CellGraphOptions<Dim>& options) {
    return tree::narrow_band<Dim>(domain, circle, level, level + 2, 2.0, options);
  };
  s.rows = RowProtocol::refine;
  if (Dim == 2)
    s.level_min = 5, s.level_max = full ? 9 : 8;
  else
    s.level_min = 3, s.level_max = full ? 5 : 4;
  return s;
}

template <int Dim>
PoissonStudy<Dim> dirichlet_study(bool full) {
  PoissonStudy<Dim> s;
  Vec<Dim> lo = Vec<Dim>::Constant(-1.5), hi = Vec<Dim>::Constant(1.5);
  lo[Dim - 1] = -1.75;
  hi[Dim - 1] = 1.25;
  s.domain = Box<Dim>{lo, hi};
  s.use(support::quartic_bowl<Dim>());
  s.levelset = s.exact;
  const Box<Dim> domain = s.domain;
  // p is not a distance: |grad p| is 4 at the apex of S and larger elsewhere, so a band of two
  // cells in p would be half a cell or less in distance, leaving cells one level coarser touching S
  // (the worst dp/dn sat at such faces). The band is measured in p / |grad p|, a distance to first
  // order near S.
  const auto p = s.exact;
  const auto grad = s.gradient;
  const auto distance = [p, grad](const Vec<Dim>& x) { return p(x) / std::max(grad(x).norm(), 1e-12); };
  s.make_tree = [domain, distance](int level, const tree::CellGraphOptions<Dim>& options) {
    return tree::narrow_band<Dim>(domain, distance, level, level + 2, 2.0, options);
  };
  s.rows = RowProtocol::refine;
  if (Dim == 2)
    s.level_min = 7, s.level_max = full ? 11 : 10;
  else
    s.level_min = 4, s.level_max = full ? 6 : 5;
  return s;
}

template PoissonStudy<2> neumann_study<2>(bool);
template PoissonStudy<3> neumann_study<3>(bool);
template PoissonStudy<2> dirichlet_study<2>(bool);
template PoissonStudy<3> dirichlet_study<3>(bool);

}  // namespace liquid::verification
