#pragma once
// Rows of -Lap p at cell centres (the pressure Poisson equation of rbf-liquids-2020, Secs. 4.2-4.3):
// the standard 5/7-point FD where the cell and its face neighbours have one size (Shortley-Weller
// at interface cuts, mirror ghosts at Neumann walls), and RBF-FD (PHS + polynomials) on nearby
// cell centres otherwise. One row at a time, over plain data; the driver (assemble_poisson) loops.

#include <span>
#include <string>
#include <utility>
#include <vector>

#include "liquid/mac/boundary.hpp"
#include "liquid/mac/dof_layout.hpp"
#include "liquid/mac/stencil.hpp"
#include "liquid/rbf/weight_cache.hpp"
#include "liquid/rbf/weights.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::mac {

enum class Nullspace { pin, zero_mean };

/// The rows of cells whose neighbourhood is not regular (T-junctions, level jumps):
///   - laplacian: RBF-FD of -Lap p at the cell centre (the paper's, Sec. 4.3);
///   - flux: the finite-volume sum of the projection's own face gradients, -(1/V) sum_f area_f dp/dn_f
///     (two-point at equal faces, RBF-FD at hanging ones, face_normal_derivative's weights), so that
///     the PPE is exactly the divergence of the gradient the projection subtracts: the projected
///     velocity's divergence is the solver's residual alone, and a repeated projection changes nothing.
///     Every row is then such a sum: in the interior of a regular neighbourhood it is the FD row, and
///     next to a level-set crossing the ghost-fluid flux form (the FD rows use Shortley-Weller there).
enum class IrregularRows { laplacian, flux };
const char* to_string(IrregularRows rows);
IrregularRows parse_irregular_rows(const std::string& name);

// Polynomial degrees. The paper uses degree 2 everywhere; both defaults here are 3:
//   - Laplacian rows: degree m reproduces polynomials of degree m, so the truncation error of a
//     second derivative is O(h^(m-1)). Degree 2 leaves O(h) on the layer of T-junction rows; p still
//     converges at second order, but that layer's error shows in dp/dn.
//   - Face gradients: degree 2 (an O(h^2) gradient stencil) loses order in dp/dn at hanging faces
//     next to a Dirichlet interface.
// Why these defaults: docs/findings/rbf-fd-degree.md (case poisson-rbf-degree runs both).
struct PoissonOptions {
  rbf::Config rbf{3, 3};                 ///< kernel and polynomial degree of the RBF-FD Laplacian rows
  int gradient_degree = 3;               ///< polynomial degree of RBF-FD face gradients (see above)
  StencilRule rule = StencilRule::ring;  ///< irregular stencil choice (docs/findings/poisson-convergence.md)
  double growth = 2.0;                   ///< irregular stencils get stencil_size(Dim, degree, growth) nodes
  /// `ring` rule: keep at most ring_cap times that size, the nodes nearest the centre (with every
  /// node tied with the last kept); 0 keeps the whole rings. A study option (liquid-verify
  /// --ring-cap), not the default: faster in 3D but less accurate and less stable
  /// (docs/findings/poisson-convergence.md).
  double ring_cap = 0.0;
  /// `ring` rule, face gradients only: keep at most this times their size (as ring_cap; 0: ring_cap
  /// applies). The PIC step caps its 3D gradients at 2, the studies keep whole rings: at degree 2 the
  /// cap leaves p untouched and dp/dn within 5% on the 3D Neumann study, and halves the projection's
  /// cost in 3D scenes (docs/findings/table1-scale.md, "Capped gradient stencils").
  double gradient_ring_cap = 0.0;
  /// The most nodes a stencil of `n_target` may keep under the rule (0: no limit): Laplacian rows,
  /// and face gradients.
  int node_cap(int n_target) const;
  int gradient_node_cap(int n_target) const;
  bool regular_fd = true;                              ///< plain FD where the neighbourhood is regular
  IrregularRows irregular = IrregularRows::laplacian;  ///< the rows of the other cells (see above)
  Nullspace nullspace = Nullspace::pin;                ///< for singular (pure Neumann) problems
  /// Share RBF-FD weights between congruent stencils within one assembly (rbf::WeightCache):
  /// T-junctions of one layout repeat across the tree and across levels. Stencils holding an
  /// interface crossing are always solved directly.
  bool cache_weights = true;
};

/// One matrix row: (column, value) pairs and a right-hand-side term.
struct Row {
  std::vector<std::pair<int, double>> entries;
  double rhs = 0.0;
};

enum class RowKind { fd, rbf, on_interface };

/// Per-thread scratch of the row kernels.
template <int Dim>
struct RowScratch {
  std::vector<StencilNode<Dim>> nodes;
  std::vector<double> w;
  long n_retried = 0;
};

/// True when every side of c has exactly one face and it is full (same level) or a wall.
template <int Dim>
bool regular_neighbourhood(const tree::CellGraph<Dim>& graph, tree::CellId c);

/// Adds the FD row of -Lap p at the regular cell c to `row` (whose rhs already holds -f); a centre
/// on the interface becomes p_c = value. Returns RowKind::fd or RowKind::on_interface. With
/// `coefficient` (per face id) the row is -div(beta grad p): each side's weight times its face's
/// beta, except at a Neumann wall, whose flux (beta dp/dn) is given.
template <int Dim>
RowKind fd_row(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout, const Boundary<Dim>& boundary,
               tree::CellId c, Row& row, std::span<const double> coefficient = {});

/// Adds the RBF-FD row of -Lap p at cell c to `row`; a centre within 1e-3 cell sizes of the
/// interface takes the interface value (RowKind::on_interface). `status` receives the weights'
/// status. Throws liquid::Error naming the cell when no usable weights exist.
template <int Dim>
RowKind rbf_row(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                const Boundary<Dim>& boundary, tree::CellId c, const PoissonOptions& options,
                rbf::WeightCache<Dim>* cache, RowScratch<Dim>& scratch, Row& row, rbf::Status& status);

/// Adds the flux row of -div(beta grad p) at cell c (IrregularRows::flux) to `row`: each face's
/// outward normal derivative (face_gradient_weights; towards a cell outside a level set, the
/// ghost-fluid difference to the crossing, theta >= 1e-3 as the projection takes it; a Neumann wall's
/// given flux, not scaled by beta) times area / volume and the face's beta (`coefficient`, empty:
/// 1). `status` receives the weakest RBF-FD weights' status. Returns RowKind::rbf, or RowKind::fd when
/// no face needed RBF-FD weights.
template <int Dim>
RowKind flux_row(const tree::CellGraph<Dim>& graph, const DofLayout<Dim>& layout,
                 const Boundary<Dim>& boundary, tree::CellId c, const PoissonOptions& options,
                 rbf::WeightCache<Dim>* cache, RowScratch<Dim>& scratch, Row& row, rbf::Status& status,
                 std::span<const double> coefficient = {});

}  // namespace liquid::mac
