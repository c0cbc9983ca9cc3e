#pragma once
// The pressure Poisson equation on a CellGraph (staggered layout: pressure at cell centres,
// normal derivatives at faces), as in sections 4.2-4.3 and 7-8 of rbf-liquids-2020:
//   - rows of -Lap p: plain FD where the neighbourhood is regular, RBF-FD otherwise (laplacian.hpp);
//   - Neumann walls by mirror (ghost) nodes carrying the unknown they mirror plus the wall flux;
//   - Dirichlet on a level set {phi = 0}: unknowns are the cells with phi(centre) < 0; every
//     stencil edge from the centre to a cell outside is cut at the interface, and the crossing
//     point becomes a node carrying the Dirichlet value (in FD: the Shortley-Weller formula);
//   - a problem with no Dirichlet value anywhere (Neumann walls, and no level set or one negative
//     at every centre) is singular: one unknown near the domain centre is pinned to a given value
//     (the paper's way), or the mean is constrained to zero through a bordered system.
// The system is assembled as -Lap p = -f, whose FD part is symmetric positive definite.

#include <functional>
#include <vector>

#include "liquid/linalg/solver.hpp"
#include "liquid/mac/boundary.hpp"
#include "liquid/mac/dof_layout.hpp"
#include "liquid/mac/gradient.hpp"
#include "liquid/mac/laplacian.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::mac {

template <int Dim>
struct PoissonProblem {
  std::function<double(const Vec<Dim>&)> f;  ///< right-hand side of Lap p = f
  std::vector<double> f_cells;  ///< per cell id: f at the cell (used instead of f when not empty)
  Boundary<Dim> boundary;       ///< interface, walls and their values
  std::function<double(const Vec<Dim>&)> pin_value;  ///< p at the pinned centre (Nullspace::pin)
  /// Per face id, positive: beta in -div(beta grad p) = -f, a face's flux scaled by its beta (a
  /// variable-density PPE: beta = 1 / density). Empty: beta = 1. FD rows only: a problem with
  /// coefficients on a tree that needs an RBF-FD row is refused, naming the cell. The walls' flux
  /// (Boundary::wall_flux) is beta dp/dn there, not scaled.
  std::vector<double> face_coefficient;
};

struct AssemblyStats {
  long n_unknowns = 0;
  long n_fd_rows = 0;
  long n_rbf_rows = 0;
  long n_degree_reduced = 0;  ///< RBF rows whose stencil could not carry the requested degree
  long n_retried = 0;         ///< RBF rows that needed a node dropped (coincident or singular)
  long n_on_interface = 0;    ///< centres within 1e-3 cell sizes of the interface, set to its value
  long n_cache_hits = 0;      ///< weight lookups the cache served (cache_weights; retries included)
  int min_degree = 99;
  int max_stencil = 0;           ///< the most nodes of an RBF-FD row
  double worst_condition = 0.0;  ///< of the local RBF systems (cached ones: at unit scale)
  tree::CellId worst_condition_cell = tree::no_cell;
  double seconds = 0.0;
};

template <int Dim>
struct PoissonSystem {
  DofLayout<Dim> layout;
  Boundary<Dim> boundary;
  linalg::SparseMatrix A;
  linalg::Vector b;
  tree::CellId pinned = tree::no_cell;  ///< the pinned cell (Nullspace::pin on a singular problem)
  /// The pinned cell's own Laplacian row, which the pin replaced: the one equation the pinned system
  /// drops. Its residual at a solution is the discrete incompatibility of f with the wall fluxes,
  /// which the pin turns into a point source at the pinned cell (see make_compatible()).
  Row pinned_equation;
  bool singular = false;  ///< no Dirichlet value anywhere: p is defined up to a constant
  bool bordered = false;  ///< true for Nullspace::zero_mean: the last unknown is a multiplier
  AssemblyStats stats;

  long n_unknowns() const { return layout.n_unknowns(); }
};

/// Assembles the system. Throws liquid::Error naming the cell when a stencil has no usable
/// weights, when the level set leaves no unknowns, and when f or a boundary value is not finite.
/// `cache` (with options.cache_weights): the RBF-FD weight cache to use, e.g. one kept across the
/// time steps of a solver; none: a cache for this assembly alone. The weights are the same bits
/// either way (an entry is a function of its key).
template <int Dim>
PoissonSystem<Dim> assemble_poisson(const tree::CellGraph<Dim>& graph, const PoissonProblem<Dim>& problem,
                                    const PoissonOptions& options, rbf::WeightCache<Dim>* cache = nullptr);

/// For a pinned singular system: moves the discrete incompatibility from the pinned cell to a uniform
/// source, as a zero-mean (bordered) system would, without its dense row. `x` solves the pinned
/// system, `z` the pinned system with 1 in every row but the pin's (0 there); on return x solves
/// every Laplacian row, the pinned cell's included, with f shifted by one constant, and keeps the
/// pinned value. Returns the constant (0 and x unchanged when nothing is pinned).
template <int Dim>
double make_compatible(const PoissonSystem<Dim>& system, const linalg::Vector& z, linalg::Vector& x);
/// The right-hand side `z` above is solved for.
template <int Dim>
linalg::Vector uniform_source(const PoissonSystem<Dim>& system);

/// face_normal_derivative() on the system's unknowns and boundary.
template <int Dim>
std::vector<double> face_normal_derivative(const tree::CellGraph<Dim>& graph,
                                           const PoissonSystem<Dim>& system, const PoissonOptions& options,
                                           const linalg::Vector& p, rbf::WeightCache<Dim>* cache = nullptr) {
  return face_normal_derivative<Dim>(graph, system.layout, system.boundary, options, p, cache);
}

}  // namespace liquid::mac
