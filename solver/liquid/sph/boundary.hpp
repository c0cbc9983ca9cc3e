#pragma once
// Walls for SPH particles as a continuum: the container's faces and the obstacles (level sets,
// negative inside the solid) add to a particle's density the kernel mass that lies beyond them, and
// push back with the gradient of that share. With only collisions, the particles next to a wall miss
// the kernel mass beyond it, read a low density and are crushed against the wall until the lattice
// collapses there; with the wall's share counted they sit at rest. Each wall is taken as the plane
// tangent to it at the particle's distance d, so its share is a function of d / r alone:
//   density    rho_0 Phi(d / r),    Phi(delta) = the density kernel's mass beyond a plane at delta r
//   pressure   a = -(P_i rho_0 / rho_i^2) grad Phi: a wall at zero pressure (FluidConstants::
//              mirror_walls = false). By default the wall is the liquid mirrored in it, as the pair
//              force of Eq. 1 summed over the wall sees it: pressure P_i beyond it, growing with
//              depth as at rest (hydrostatic_gradient), and the normal velocity reversed, so the
//              push and the continuity's wall term are both twice the zero-pressure wall's (doubling
//              the push alone breaks the energy balance between them). The zero-pressure wall pushes
//              a particle of uniform pressure back with half the force the liquid on its other side
//              pushes it with. Without the growth with depth, a particle by a side wall misses the
//              vertical pressure gradient of the kernel's part beyond it and slides along the wall.
//              Why: docs/findings/sph.md.
// Phi and its derivative are tabulated once per dimension (1024 points, linear interpolation). Near
// a corner several walls are within reach: the mass beyond any of them is taken as 1 - prod_k (1 - Phi_k),
// exact for one wall and for a kernel that factorises along the axes (a Gaussian); summing the
// Phi_k instead counts the corner's quadrant twice and overestimates the density at corners.

#include <vector>

#include "liquid/core/types.hpp"
#include "liquid/levelset/levelset.hpp"
#include "liquid/sph/fluid.hpp"

namespace liquid::sph {

template <int Dim>
class Boundary {
 public:
  Boundary() = default;
  Boundary(const Box<Dim>& container, std::vector<levelset::Function<Dim>> obstacles);

  /// The walls' share of the density kernel around x (support r): the kernel mass beyond them, in
  /// [0, 1]; they add rho_0 times it to the density.
  double share(const Vec<Dim>& x, double r, KernelSet kernels) const;
  /// The gradient of share() with respect to x (it points into the walls). The walls push a particle
  /// with a = -(P rho_0 / rho^2) grad share and, with a continuity density, change its density at
  /// the rate rho_0 grad share . v; twice each as the mirrored liquid (FluidConstants::mirror_walls).
  Vec<Dim> share_gradient(const Vec<Dim>& x, double r, KernelSet kernels) const;

  /// What the walls add to the pressure force where the mirrored liquid's pressure grows with depth
  /// as at rest, P_w(y) = P_i + rho_0 g . (y - x): the integral over the walls of
  /// (P_w(y) - P_i) grad W(x - y) dy, per unit rho_0, with the density kernel. For one wall at
  /// distance d with normal n into the liquid, exactly: (g . n) d Pi(d) n + Phi(d) g, with Phi the
  /// kernel mass beyond the wall and Pi its plane integral there. Near a corner the walls' terms are
  /// summed, which counts the quadrant beyond both twice; share()'s product rule is no more exact
  /// here, and the sum is simpler (docs/findings/sph.md).
  Vec<Dim> hydrostatic_gradient(const Vec<Dim>& x, double r, KernelSet kernels, const Vec<Dim>& g) const;

  /// Both of the above from one walk over the walls (the pressure force needs both, and each walk
  /// evaluates every obstacle's level set).
  struct Push {
    Vec<Dim> share_gradient, hydrostatic;
  };
  Push push(const Vec<Dim>& x, double r, KernelSet kernels, const Vec<Dim>& g) const;

  /// The nearest wall or obstacle closer to x than `reach`: its distance (0 from inside a solid) and,
  /// through `closest`, its point nearest x; infinite (and `closest` untouched) when none is.
  double nearest(const Vec<Dim>& x, double reach, Vec<Dim>* closest = nullptr) const;

  /// The density kernel's mass beyond a plane at distance delta * r, for r = 1; 0 for delta >= 1.
  static double beyond(KernelSet kernels, double delta);
  /// -d/d delta of beyond(): the density kernel integrated over the plane at delta.
  static double on_plane(KernelSet kernels, double delta);

 private:
  template <class F>
  void for_each_wall(const Vec<Dim>& x, double r, F f) const;

  /// A wall within reach of a particle: its distance, the kernel's mass beyond it and its plane
  /// integral there (unit support), its normal into the liquid.
  struct NearWall {
    double distance, beyond, on_plane;
    Vec<Dim> n;
  };
  /// Every wall within r of x (a thread's own list, overwritten by its next call).
  const std::vector<NearWall>& near_walls(const Vec<Dim>& x, double r, KernelSet kernels) const;
  static Vec<Dim> share_gradient_of(const std::vector<NearWall>& walls, double r);
  static Vec<Dim> hydrostatic_of(const std::vector<NearWall>& walls, double r, const Vec<Dim>& g);

  Box<Dim> container_;
  bool has_container_ = false;
  std::vector<levelset::Function<Dim>> obstacles_;
};

}  // namespace liquid::sph
