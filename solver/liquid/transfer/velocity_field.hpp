#pragma once
// A face velocity field that can be evaluated anywhere: what advection needs at the intermediate
// points of its Runge-Kutta stages. On any tree, component k at x is the RBF interpolant of the
// axis-k faces around x's cell (the stencil of faces_to_points); the interpolants of the cells
// named at construction are factorised once, up front and in parallel, so an evaluation there costs
// one point location and Dim short sums. On a uniform tree the multilinear interpolation of the
// regular baselines is available instead (RegularLattice); on an adaptive tree, given its uniform
// patches, points in patch cells take the patches' multilinear interpolation and only the others
// the RBF.
//
//   const FaceVelocityField<2> u(graph, faces.value, faces.known, TransferOptions::paper_rbf());
//   advect<2>(particles.x, dt, Integrator::rk3, u, graph.domain());

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "liquid/rbf/interpolant_cache.hpp"
#include "liquid/transfer/patches.hpp"
#include "liquid/transfer/regular.hpp"
#include "liquid/transfer/scattered.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::transfer {

template <int Dim>
class FaceVelocityField {
 public:
  /// RBF (options.scheme must be rbf) on any tree. `u` and `known` (empty: all known) are copied.
  /// `cells`: the cells to prepare (empty: every cell); elsewhere an evaluation factorises on the
  /// fly. Evaluations are thread-safe. `patches` (optional; must outlive the field): its patch
  /// cells are interpolated multilinearly and not prepared. `shared` (optional, with
  /// options.share_factors; must outlive the field): a factor cache kept by the caller, e.g. across
  /// time steps, where the tree's stencil shapes repeat; the values are the same bits either way.
  FaceVelocityField(const tree::CellGraph<Dim>& graph, std::span<const double> u,
                    std::span<const std::uint8_t> known, const TransferOptions& options,
                    std::span<const tree::CellId> cells = {}, const UniformPatches<Dim>* patches = nullptr,
                    rbf::InterpolantCache<Dim>* shared = nullptr);
  /// Multilinear interpolation on a uniform tree.
  FaceVelocityField(const tree::CellGraph<Dim>& graph, const RegularLattice<Dim>& lattice,
                    std::span<const double> u);
  ~FaceVelocityField();
  FaceVelocityField(FaceVelocityField&&) noexcept;

  /// The velocity at x (clamped onto the domain). Throws on a non-finite x.
  Vec<Dim> operator()(const Vec<Dim>& x) const;
  /// The velocity at x and its gradient written to `grad` (Dim x Dim, row-major, row k the gradient
  /// of component k: APIC's C): the multilinear one in patch cells, the RBF interpolant's elsewhere,
  /// 0 for a component whose value was clamped or whose interpolant is unusable. Adaptive trees only.
  Vec<Dim> with_gradient(const Vec<Dim>& x, double* grad) const;

 private:
  struct CellInterpolants;
  void prepare(tree::CellId c, CellInterpolants& out) const;
  Vec<Dim> evaluate(const CellInterpolants& ci, const Vec<Dim>& x) const;

  const tree::CellGraph<Dim>* graph_ = nullptr;
  const RegularLattice<Dim>* lattice_ = nullptr;
  const UniformPatches<Dim>* patches_ = nullptr;
  std::vector<double> u_;
  std::vector<std::uint8_t> known_;
  TransferOptions options_;
  std::vector<std::int32_t> slot_;  // per cell id: index into prepared_, or -1
  std::vector<std::unique_ptr<CellInterpolants>> prepared_;
  std::unique_ptr<rbf::InterpolantCache<Dim>> own_cache_;  // shared factors (options.share_factors)
  rbf::InterpolantCache<Dim>* cache_ = nullptr;            // own_cache_, the caller's, or none
};

extern template class FaceVelocityField<2>;
extern template class FaceVelocityField<3>;

}  // namespace liquid::transfer
