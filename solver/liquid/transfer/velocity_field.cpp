#include "liquid/transfer/velocity_field.hpp"

#include <algorithm>
#include <array>
#include <optional>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/rbf/interpolant.hpp"
#include "liquid/transfer/face_stencil.hpp"

namespace liquid::transfer {

template <int Dim>
struct FaceVelocityField<Dim>::CellInterpolants {
  std::array<std::optional<rbf::Interpolant<Dim>>, Dim> interp;
  std::array<double, Dim> lo{}, hi{};  // range of the face values, for clamping
  std::array<double, Dim> fallback{};  // the mean, when the interpolant is unusable
  std::array<bool, Dim> empty{};
};

template <int Dim>
FaceVelocityField<Dim>::FaceVelocityField(const tree::CellGraph<Dim>& graph, std::span<const double> u,
                                          std::span<const std::uint8_t> known, const TransferOptions& options,
                                          std::span<const tree::CellId> cells,
                                          const UniformPatches<Dim>* patches,
                                          rbf::InterpolantCache<Dim>* shared)
    : graph_(&graph),
      patches_(patches),
      u_(u.begin(), u.end()),
      known_(known.begin(), known.end()),
      options_(options) {
  LIQUID_VERIFY(options.scheme == Scheme::rbf, "FaceVelocityField: scheme {} is not offered (rbf only)",
                to_string(options.scheme));
  LIQUID_VERIFY(static_cast<int>(u.size()) >= graph.face_capacity(),
                "FaceVelocityField: {} face values for {} face ids", u.size(), graph.face_capacity());
  LIQUID_VERIFY(known.empty() || known.size() == u.size(), "FaceVelocityField: {} known flags for {} faces",
                known.size(), u.size());
  if (options.share_factors && shared) {
    cache_ = shared;
  } else if (options.share_factors) {
    own_cache_ = std::make_unique<rbf::InterpolantCache<Dim>>();
    cache_ = own_cache_.get();
  }
  std::vector<tree::CellId> list(cells.begin(), cells.end());
  if (list.empty()) list = graph.cell_ids();
  if (patches_) std::erase_if(list, [&](tree::CellId c) { return patches_->cell(c); });
  slot_.assign(graph.cell_capacity(), -1);
  prepared_.resize(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    LIQUID_VERIFY(graph.alive(list[i]), "FaceVelocityField: cell {} is not alive", list[i]);
    slot_[list[i]] = static_cast<std::int32_t>(i);
  }
  parallel_for(
      static_cast<long>(list.size()),
      [&](long i) {
        prepared_[i] = std::make_unique<CellInterpolants>();
        prepare(list[i], *prepared_[i]);
      },
      16);
}

template <int Dim>
FaceVelocityField<Dim>::FaceVelocityField(const tree::CellGraph<Dim>& graph,
                                          const RegularLattice<Dim>& lattice, std::span<const double> u)
    : graph_(&graph), lattice_(&lattice), u_(u.begin(), u.end()) {
  LIQUID_VERIFY(static_cast<int>(u.size()) >= graph.face_capacity(),
                "FaceVelocityField: {} face values for {} face ids", u.size(), graph.face_capacity());
}

template <int Dim>
FaceVelocityField<Dim>::~FaceVelocityField() = default;
template <int Dim>
FaceVelocityField<Dim>::FaceVelocityField(FaceVelocityField&&) noexcept = default;

template <int Dim>
void FaceVelocityField<Dim>::prepare(tree::CellId c, CellInterpolants& out) const {
  transfer::FaceStencil<Dim> stencil;
  transfer::gather_face_stencil<Dim>(*graph_, c, options_.rings, u_, known_, stencil);
  const rbf::Config config = options_.rbf_config();
  for (int axis = 0; axis < Dim; ++axis) {
    const auto& nodes = stencil.nodes[axis];
    const Eigen::Map<const Eigen::VectorXd> values(stencil.values[axis].data(),
                                                   static_cast<long>(stencil.values[axis].size()));
    const long n = values.size();
    out.empty[axis] = n == 0;
    if (n == 0) continue;
    out.lo[axis] = values.minCoeff();
    out.hi[axis] = values.maxCoeff();
    out.fallback[axis] = values.mean();
    rbf::Interpolant<Dim> interp =
        transfer::fitted_interpolant<Dim>(*graph_, c, nodes, stencil.values[axis], config, cache_);
    if (interp.status().usable()) out.interp[axis].emplace(std::move(interp));
  }
}

template <int Dim>
Vec<Dim> FaceVelocityField<Dim>::evaluate(const CellInterpolants& ci, const Vec<Dim>& x) const {
  Vec<Dim> v;
  for (int k = 0; k < Dim; ++k) {
    if (ci.empty[k]) {
      v[k] = 0.0;
      continue;
    }
    double value = ci.interp[k] ? ci.interp[k]->value_at(x) : ci.fallback[k];
    if (options_.clamp) value = std::clamp(value, ci.lo[k], ci.hi[k]);
    v[k] = value;
  }
  return v;
}

template <int Dim>
Vec<Dim> FaceVelocityField<Dim>::operator()(const Vec<Dim>& x) const {
  LIQUID_VERIFY(x.allFinite(), "FaceVelocityField: non-finite evaluation point");
  const Box<Dim>& d = graph_->domain();
  const Vec<Dim> y = x.cwiseMax(d.lo).cwiseMin(d.hi);
  if (lattice_) {
    Vec<Dim> v;
    for (int k = 0; k < Dim; ++k) {
      const LinearStencil<Dim> st(*lattice_, k, y);
      double value = 0.0;
      for (int corner = 0; corner < (1 << Dim); ++corner) {
        IVec<Dim> a = st.base;
        for (int j = 0; j < Dim; ++j) a[j] += (corner >> j) & 1;
        value += st.weight(corner) * u_[lattice_->face(k, a)];
      }
      v[k] = value;
    }
    return v;
  }
  const tree::CellId c = graph_->locate(y);
  if (patches_ && patches_->cell(c)) return patches_->value(c, y, u_);
  if (slot_[c] >= 0) return evaluate(*prepared_[slot_[c]], y);
  CellInterpolants local;
  prepare(c, local);
  return evaluate(local, y);
}

template <int Dim>
Vec<Dim> FaceVelocityField<Dim>::with_gradient(const Vec<Dim>& x, double* grad) const {
  LIQUID_VERIFY(x.allFinite(), "FaceVelocityField: non-finite evaluation point");
  LIQUID_VERIFY(lattice_ == nullptr, "FaceVelocityField: with_gradient is for adaptive trees");
  const Box<Dim>& d = graph_->domain();
  const Vec<Dim> y = x.cwiseMax(d.lo).cwiseMin(d.hi);
  const tree::CellId c = graph_->locate(y);
  if (patches_ && patches_->cell(c)) return patches_->value(c, y, u_, grad);
  CellInterpolants local;
  const CellInterpolants* ci = &local;
  if (slot_[c] >= 0)
    ci = prepared_[slot_[c]].get();
  else
    prepare(c, local);
  Vec<Dim> v;
  for (int k = 0; k < Dim; ++k) {
    std::fill_n(grad + k * Dim, Dim, 0.0);
    if (ci->empty[k]) {
      v[k] = 0.0;
      continue;
    }
    if (!ci->interp[k]) {
      v[k] = options_.clamp ? std::clamp(ci->fallback[k], ci->lo[k], ci->hi[k]) : ci->fallback[k];
      continue;
    }
    const double raw = ci->interp[k]->value_and_gradient(y, 0, grad + k * Dim);
    const double value = options_.clamp ? std::clamp(raw, ci->lo[k], ci->hi[k]) : raw;
    v[k] = value;
    // A clamped value keeps no gradient.
    if (value != raw) std::fill_n(grad + k * Dim, Dim, 0.0);
  }
  return v;
}

template class FaceVelocityField<2>;
template class FaceVelocityField<3>;

}  // namespace liquid::transfer
