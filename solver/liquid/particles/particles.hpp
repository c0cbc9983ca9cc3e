#pragma once
// Particles<Dim>: a structure of arrays. Every particle has a position and a velocity. Any other
// per-particle quantity (APIC's affine matrix, a distance, an id, a mass) is a named field of a
// fixed number of doubles per particle. Indices stay the same until the owner compacts; compaction
// keeps the survivors in their old order, so a step stays deterministic whatever the thread count.
//
//   Particles<2> p;
//   const int c = p.add_field("apic_c", 4);   // 4 doubles per particle
//   p.push_back(x, v);                          // fields of the new particle are zero
//   p.field(c)[4 * i + 1] = ...;
//   p.compact(dead);                            // dead[i] != 0 removes particle i

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "liquid/core/types.hpp"

namespace liquid::particles {

template <int Dim>
class Particles {
 public:
  int size() const { return static_cast<int>(x.size()); }
  bool empty() const { return x.empty(); }

  /// Registers a field of `components` doubles per particle (zero for the particles already there)
  /// and returns its index. Throws when the name is taken or components < 1.
  int add_field(const std::string& name, int components);
  /// The field's index, or -1 when there is no field of that name.
  int find_field(const std::string& name) const;
  /// The field's index; throws naming the field when there is none.
  int field_index(const std::string& name) const;
  int field_components(int field) const { return fields_[field].components; }
  const std::string& field_name(int field) const { return fields_[field].name; }
  int n_fields() const { return static_cast<int>(fields_.size()); }
  std::span<double> field(int f) { return fields_[f].data; }
  std::span<const double> field(int f) const { return fields_[f].data; }

  /// Appends one particle; its fields are zero.
  void push_back(const Vec<Dim>& position, const Vec<Dim>& velocity);
  /// Makes room for n particles in every array.
  void reserve(int n);
  /// Resizes every array (new particles at the origin, at rest, fields zero).
  void resize(int n);
  /// Removes every particle i with remove[i] != 0 (remove.size() == size()), keeping the order of
  /// the others. Returns how many were removed. `new_index` (optional, out) receives, per old
  /// index, the new index or -1.
  int compact(std::span<const std::uint8_t> remove, std::vector<std::int32_t>* new_index = nullptr);
  void clear() { resize(0); }

  std::vector<Vec<Dim>> x;  ///< positions
  std::vector<Vec<Dim>> v;  ///< velocities

 private:
  struct Field {
    std::string name;
    int components = 1;
    std::vector<double> data;  // components * size() doubles, particle-major
  };
  std::vector<Field> fields_;
};

extern template class Particles<2>;
extern template class Particles<3>;

}  // namespace liquid::particles
