#pragma once
// The liquid's level set built from the particles, for the second-order Dirichlet surface of the
// PPE (PicOptions::surface = levelset). The construction is Zhu and Bridson's (2005):
//   phi(x) = |x - X(x)| - r,   X(x) = sum_i k(|x - x_i| / R) x_i / sum_i k(|x - x_i| / R),
//   k(s) = max(0, 1 - s^2)^3,  R = 2 h,  r = radius * h  (h: the finest cell size),
// over the particles within R of x; phi = R where there is none. Inside a fluid cell coarser than
// the finest level (the band keeps those away from the surface, where particles are sparse)
// phi = -half the cell size instead: the liquid's interior. Evaluations are thread-safe.

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "liquid/particles/particles.hpp"
#include "liquid/pic/classify.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::pic {

template <int Dim>
class ParticleSurface {
 public:
  /// `graph`, `cls` must outlive the surface; the positions are copied into a bucket grid of size R.
  ParticleSurface(const tree::CellGraph<Dim>& graph, const Classification& cls, std::span<const Vec<Dim>> x,
                  int fine_level, double radius);

  double operator()(const Vec<Dim>& x) const;
  double support() const { return support_; }

 private:
  std::uint64_t bucket_key(const IVec<Dim>& b) const;
  IVec<Dim> bucket_of(const Vec<Dim>& x) const;

  const tree::CellGraph<Dim>* graph_;
  const Classification* cls_;
  int fine_level_;
  double h_, support_, radius_;
  std::unordered_map<std::uint64_t, std::vector<Vec<Dim>>> buckets_;
};

extern template class ParticleSurface<2>;
extern template class ParticleSurface<3>;

}  // namespace liquid::pic
