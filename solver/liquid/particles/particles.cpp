#include "liquid/particles/particles.hpp"

#include "liquid/core/error.hpp"
#include "liquid/particles/advect.hpp"

namespace liquid::particles {

template <int Dim>
int Particles<Dim>::add_field(const std::string& name, int components) {
  LIQUID_VERIFY(components >= 1, "particle field '{}': {} components (need at least 1)", name, components);
  LIQUID_VERIFY(find_field(name) < 0, "particle field '{}' is already registered", name);
  fields_.push_back({name, components, std::vector<double>(static_cast<std::size_t>(components) * x.size())});
  return n_fields() - 1;
}

template <int Dim>
int Particles<Dim>::find_field(const std::string& name) const {
  for (int f = 0; f < n_fields(); ++f)
    if (fields_[f].name == name) return f;
  return -1;
}

template <int Dim>
int Particles<Dim>::field_index(const std::string& name) const {
  const int f = find_field(name);
  LIQUID_VERIFY(f >= 0, "no particle field named '{}'", name);
  return f;
}

template <int Dim>
void Particles<Dim>::push_back(const Vec<Dim>& position, const Vec<Dim>& velocity) {
  x.push_back(position);
  v.push_back(velocity);
  for (auto& f : fields_) f.data.resize(f.data.size() + f.components, 0.0);
}

template <int Dim>
void Particles<Dim>::reserve(int n) {
  x.reserve(n);
  v.reserve(n);
  for (auto& f : fields_) f.data.reserve(static_cast<std::size_t>(n) * f.components);
}

template <int Dim>
void Particles<Dim>::resize(int n) {
  x.resize(n, Vec<Dim>::Zero());
  v.resize(n, Vec<Dim>::Zero());
  for (auto& f : fields_) f.data.resize(static_cast<std::size_t>(n) * f.components, 0.0);
}

template <int Dim>
int Particles<Dim>::compact(std::span<const std::uint8_t> remove, std::vector<std::int32_t>* new_index) {
  LIQUID_VERIFY(remove.size() == x.size(), "Particles::compact: {} flags for {} particles", remove.size(),
                x.size());
  if (new_index) new_index->assign(x.size(), -1);
  int out = 0;
  for (int i = 0; i < size(); ++i) {
    if (remove[i]) continue;
    if (new_index) (*new_index)[i] = out;
    if (out != i) {
      x[out] = x[i];
      v[out] = v[i];
      for (auto& f : fields_)
        for (int k = 0; k < f.components; ++k) f.data[out * f.components + k] = f.data[i * f.components + k];
    }
    ++out;
  }
  const int removed = size() - out;
  resize(out);
  return removed;
}

const char* to_string(Integrator integrator) {
  return integrator == Integrator::rk2 ? "rk2" : "rk3";
}

template class Particles<2>;
template class Particles<3>;

}  // namespace liquid::particles
