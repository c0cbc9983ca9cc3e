#include "liquid/levelset/levelset.hpp"

#include <cmath>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

#include "liquid/core/error.hpp"

namespace liquid::levelset {

template <int Dim>
Function<Dim> sphere(const Vec<Dim>& centre, double radius) {
  LIQUID_VERIFY(radius > 0.0, "sphere radius must be positive, got {}", radius);
  return [centre, radius](const Vec<Dim>& x) { return (x - centre).norm() - radius; };
}

template <int Dim>
Function<Dim> box(const Box<Dim>& b) {
  LIQUID_VERIFY(b.valid(), "box level set needs lo < hi on every axis");
  return [b](const Vec<Dim>& x) {
    const Vec<Dim> c = b.centre(), half = 0.5 * b.size();
    const Vec<Dim> q = (x - c).cwiseAbs() - half;
    const double outside = q.cwiseMax(0.0).norm();
    const double inside = std::min(q.maxCoeff(), 0.0);
    return outside + inside;
  };
}

template <int Dim>
Function<Dim> unite(Function<Dim> a, Function<Dim> b) {
  return [a = std::move(a), b = std::move(b)](const Vec<Dim>& x) { return std::min(a(x), b(x)); };
}
template <int Dim>
Function<Dim> intersect(Function<Dim> a, Function<Dim> b) {
  return [a = std::move(a), b = std::move(b)](const Vec<Dim>& x) { return std::max(a(x), b(x)); };
}
template <int Dim>
Function<Dim> subtract(Function<Dim> a, Function<Dim> b) {
  return [a = std::move(a), b = std::move(b)](const Vec<Dim>& x) { return std::max(a(x), -b(x)); };
}

namespace {
template <int Dim>
struct Segment {
  const Function<Dim>* phi;
  const Vec<Dim>* a;
  const Vec<Dim>* b;
};

template <int Dim>
double along(double t, void* params) {
  const auto* s = static_cast<const Segment<Dim>*>(params);
  return (*s->phi)(*s->a + t * (*s->b - *s->a));
}
}  // namespace

template <int Dim>
std::optional<Crossing<Dim>> crossing(const Function<Dim>& phi, const Vec<Dim>& a, const Vec<Dim>& b,
                                      double phi_a, double phi_b, double tolerance) {
  LIQUID_VERIFY(std::isfinite(phi_a) && std::isfinite(phi_b),
                "level set is not finite at a segment end ({} at a, {} at b)", phi_a, phi_b);
  if (phi_a == 0.0) return Crossing<Dim>{0.0, a};
  if (phi_b == 0.0) return Crossing<Dim>{1.0, b};
  if ((phi_a < 0.0) == (phi_b < 0.0)) return std::nullopt;

  Segment<Dim> seg{&phi, &a, &b};
  gsl_function f{&along<Dim>, &seg};
  gsl_root_fsolver* solver = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
  gsl_error_handler_t* previous = gsl_set_error_handler_off();
  double lo = 0.0, hi = 1.0, t = phi_a / (phi_a - phi_b);
  int status = gsl_root_fsolver_set(solver, &f, lo, hi);
  for (int it = 0; status == GSL_SUCCESS && it < 200; ++it) {
    status = gsl_root_fsolver_iterate(solver);
    t = gsl_root_fsolver_root(solver);
    lo = gsl_root_fsolver_x_lower(solver);
    hi = gsl_root_fsolver_x_upper(solver);
    if (gsl_root_test_interval(lo, hi, tolerance, 0.0) == GSL_SUCCESS) break;
  }
  gsl_root_fsolver_free(solver);
  gsl_set_error_handler(previous);
  LIQUID_VERIFY(status == GSL_SUCCESS && std::isfinite(t),
                "interface crossing search failed on the segment from ({}) to ({}): {}",
                fmt::join(a.data(), a.data() + Dim, ", "), fmt::join(b.data(), b.data() + Dim, ", "),
                gsl_strerror(status));
  return Crossing<Dim>{t, a + t * (b - a)};
}

template <int Dim>
Vec<Dim> gradient(const Function<Dim>& phi, const Vec<Dim>& x, double step) {
  Vec<Dim> g;
  for (int d = 0; d < Dim; ++d) {
    Vec<Dim> a = x, b = x;
    a[d] -= step, b[d] += step;
    g[d] = (phi(b) - phi(a)) / (2.0 * step);
  }
  return g;
}

#define LIQUID_LEVELSET_INSTANTIATE(D)                                                                      \
  template Function<D> sphere<D>(const Vec<D>&, double);                                                    \
  template Vec<D> gradient<D>(const Function<D>&, const Vec<D>&, double);                                   \
  template Function<D> box<D>(const Box<D>&);                                                               \
  template Function<D> unite<D>(Function<D>, Function<D>);                                                  \
  template Function<D> intersect<D>(Function<D>, Function<D>);                                              \
  template Function<D> subtract<D>(Function<D>, Function<D>);                                               \
  template std::optional<Crossing<D>> crossing<D>(const Function<D>&, const Vec<D>&, const Vec<D>&, double, \
                                                  double, double);
LIQUID_LEVELSET_INSTANTIATE(2)
LIQUID_LEVELSET_INSTANTIATE(3)

}  // namespace liquid::levelset
