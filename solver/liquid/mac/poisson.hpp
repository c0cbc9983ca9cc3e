#pragma once
// The pressure Poisson equation on a CellGraph (staggered layout: pressure at cell centres,
// normal derivatives at faces), as in sections 4.2-4.3 and 7-8 of rbf-liquids-2020:
//   - the Laplacian at a cell centre is the standard 5/7-point FD where the cell and its face
//     neighbours have one size, and RBF-FD (PHS + polynomials) on nearby cell centres otherwise;
//   - homogeneous Neumann walls by mirror (ghost) nodes carrying the unknown they mirror, so the
//     ghost weight folds into that unknown (in FD: into the centre);
//   - Dirichlet on a level set {phi = 0}: unknowns are the cells with phi(centre) < 0; every
//     stencil edge from the centre to a cell outside is cut at the interface, and the crossing
//     point becomes a node carrying the Dirichlet value (in FD: the Shortley-Weller formula);
//   - a pure Neumann problem is singular: one unknown near the domain centre is pinned to a given
//     value (the paper's way), or the mean is constrained to zero through a bordered system.
// The system is assembled as -Lap p = -f, whose FD part is symmetric positive definite.

#include <functional>
#include <string>
#include <vector>

#include "liquid/linalg/solver.hpp"
#include "liquid/mac/stencil.hpp"
#include "liquid/rbf/weights.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::mac {

enum class Nullspace { pin, zero_mean };

// Polynomial degrees. The paper uses degree 2 everywhere; both defaults here are 3, as measured:
//   - Laplacian rows: degree m reproduces polynomials of degree m, so the truncation error of a
//     second derivative is O(h^(m-1)). Degree 2 leaves O(h) on the layer of T-junction rows. p still
//     converges at second order, but that layer's error shows in dp/dn: with rows made by
//     subdivision, dp/dn converged at 1.75 (2D Neumann, worst faces the hanging faces at the layer)
//     and 1.18 (3D Neumann), and 3D Dirichlet missed in p too (1.49). Degree 3 gave 1.9-2.3 on all
//     four paper studies (case poisson-rbf-degree runs both side by side).
//   - Face gradients: with degree 2 (an O(h^2) gradient stencil) the L-inf of dp/dn at hanging
//     faces next to a Dirichlet interface converged at about 1.7 on the 2D level-set case; degree 3
//     gave 1.9-2.0 and 5-10 times smaller errors, the maximum moving to plain FD faces.
struct PoissonOptions {
  rbf::Config rbf{3, 3};                 ///< kernel and polynomial degree of the RBF-FD Laplacian rows
  int gradient_degree = 3;               ///< polynomial degree of RBF-FD face gradients (see above)
  StencilRule rule = StencilRule::ring;  ///< how irregular stencils are chosen (ring: best L-inf measured)
  double growth = 2.0;                   ///< irregular stencils get growth * (polynomial terms) + 1 nodes
  bool regular_fd = true;                ///< plain FD where the neighbourhood is regular
  Nullspace nullspace = Nullspace::pin;  ///< for pure Neumann problems
  /// Share RBF-FD weights between congruent stencils within one assembly (rbf::WeightCache):
  /// T-junctions of one layout repeat across the tree and across levels. Stencils holding an
  /// interface crossing are always solved directly.
  bool cache_weights = true;
};

template <int Dim>
struct PoissonProblem {
  std::function<double(const Vec<Dim>&)> f;          ///< right-hand side of Lap p = f
  levelset::Function<Dim> levelset;                  ///< empty: whole domain with Neumann walls
  std::function<double(const Vec<Dim>&)> dirichlet;  ///< p on the interface (level-set problems) and walls
  bool dirichlet_walls = false;                      ///< walls carry `dirichlet` values (else Neumann)
  std::function<double(const Vec<Dim>&)> pin_value;  ///< p at the pinned centre (Nullspace::pin)
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
  double worst_condition = 0.0;  ///< of the local RBF systems (cached ones: at unit scale)
  CellId worst_condition_cell = no_cell;
  double seconds = 0.0;
};

template <int Dim>
struct PoissonSystem {
  DofLayout<Dim> layout;
  linalg::SparseMatrix A;
  linalg::Vector b;
  CellId pinned = no_cell;  ///< the pinned cell (Nullspace::pin on a Neumann problem)
  bool bordered = false;    ///< true for Nullspace::zero_mean: the last unknown is a multiplier
  AssemblyStats stats;

  long n_unknowns() const { return static_cast<long>(layout.cell_of_dof.size()); }
};

/// Assembles the system. Throws liquid::Error naming the cell when a stencil has no usable
/// weights, and when the level set leaves no unknowns.
template <int Dim>
PoissonSystem<Dim> assemble_poisson(const CellGraph<Dim>& graph, const PoissonProblem<Dim>& problem,
                                    const PoissonOptions& options);

/// dp/dx_axis at every interior face whose two cells are unknowns, indexed by face id (NaN at the
/// others): the two-point difference between equal cells, RBF-FD at the face centre otherwise.
/// `p` holds one value per unknown (a bordered multiplier, if any, is ignored).
template <int Dim>
std::vector<double> face_normal_derivative(const CellGraph<Dim>& graph, const PoissonSystem<Dim>& system,
                                           const PoissonOptions& options, const linalg::Vector& p);

}  // namespace liquid::mac
