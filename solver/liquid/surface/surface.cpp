#include "liquid/surface/surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "liquid/core/error.hpp"

namespace liquid::surface {

template <int Dim>
double Mesh<Dim>::measure() const {
  double sum = 0.0;
  for (const auto& e : elements) {
    if constexpr (Dim == 2) {
      sum += (vertices[e[1]] - vertices[e[0]]).norm();
    } else {
      sum += 0.5 * (vertices[e[1]] - vertices[e[0]]).cross(vertices[e[2]] - vertices[e[0]]).norm();
    }
  }
  return sum;
}

namespace {

using Index = std::int64_t;

template <int Dim>
struct Grid {
  Eigen::Matrix<Index, Dim, 1> n;  ///< cells per axis
  Vec<Dim> lo, h;
  Index n_nodes() const { return (n.array() + 1).prod(); }
  Index node(const Eigen::Matrix<Index, Dim, 1>& k) const {
    Index f = 0;
    for (int d = Dim - 1; d >= 0; --d) f = f * (n[d] + 1) + k[d];
    return f;
  }
  Eigen::Matrix<Index, Dim, 1> coords(Index f) const {
    Eigen::Matrix<Index, Dim, 1> k;
    for (int d = 0; d < Dim; ++d) k[d] = f % (n[d] + 1), f /= n[d] + 1;
    return k;
  }
  Vec<Dim> point(const Eigen::Matrix<Index, Dim, 1>& k) const {
    return lo + h.cwiseProduct(k.template cast<double>());
  }
};

/// The mesh under construction, with one vertex per cut segment between two nodes (a < b: key a, b).
template <int Dim>
struct Builder {
  const Grid<Dim>& grid;
  const std::vector<double>& value;
  Mesh<Dim> mesh;
  std::unordered_map<std::uint64_t, int> on_segment;

  int vertex(Index a, Index b) {
    if (a > b) std::swap(a, b);
    const std::uint64_t key = (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint64_t>(b);
    auto [it, fresh] = on_segment.try_emplace(key, static_cast<int>(mesh.vertices.size()));
    if (fresh) {
      const double fa = value[a], fb = value[b];
      const double t = fa / (fa - fb);
      const Vec<Dim> pa = grid.point(grid.coords(a)), pb = grid.point(grid.coords(b));
      mesh.vertices.push_back(pa + t * (pb - pa));
    }
    return it->second;
  }
};

bool inside(double f) {
  return f < 0.0;
}

/// Marching squares on one cell with corner nodes c[0..3] counter-clockwise from the low corner.
void square(Builder<2>& b, const std::array<Index, 4>& c, double centre) {
  int mask = 0;
  for (int k = 0; k < 4; ++k) mask |= inside(b.value[c[k]]) << k;
  if (mask == 0 || mask == 15) return;
  // Walking the square's edges counter-clockwise, the zero set is left (an exit) on an edge from an
  // inside corner to an outside one and entered on the others; a segment exit -> entry has the
  // outside on its right.
  std::array<int, 2> exits{}, entries{};
  int n_exit = 0, n_entry = 0;
  for (int k = 0; k < 4; ++k) {
    const int l = (k + 1) % 4;
    const bool in_k = (mask >> k) & 1, in_l = (mask >> l) & 1;
    if (in_k == in_l) continue;
    const int v = b.vertex(c[k], c[l]);
    if (in_k)
      exits[n_exit++] = v;
    else
      entries[n_entry++] = v;
  }
  auto add = [&](int from, int to) { b.mesh.elements.push_back({from, to}); };
  if (n_exit == 1) {
    add(exits[0], entries[0]);
    return;
  }
  // Two opposite corners inside: the centre value decides whether they connect through the middle.
  const bool centre_in = inside(centre);
  if (mask == 5) {  // corners 0 and 2 inside: exits on edges 0 and 2, entries on edges 1 and 3
    if (centre_in)
      add(exits[0], entries[0]), add(exits[1], entries[1]);
    else
      add(exits[0], entries[1]), add(exits[1], entries[0]);
  } else {  // mask 10, corners 1 and 3 inside: entries on edges 0 and 2, exits on edges 1 and 3
    if (centre_in)
      add(exits[1], entries[0]), add(exits[0], entries[1]);
    else
      add(exits[0], entries[0]), add(exits[1], entries[1]);
  }
}

/// Marching tetrahedra on one tetrahedron of nodes t[0..3].
void tetrahedron(Builder<3>& b, const std::array<Index, 4>& t) {
  std::array<Index, 4> in{}, out{};
  int n_in = 0, n_out = 0;
  for (Index node : t) (inside(b.value[node]) ? in[n_in++] : out[n_out++]) = node;
  if (n_in == 0 || n_in == 4) return;
  auto point = [&](Index node) { return b.grid.point(b.grid.coords(node)); };
  // Orients a triangle so that its normal points from the inside nodes towards the outside ones.
  auto add = [&](int v0, int v1, int v2) {
    const Vec<3>& p0 = b.mesh.vertices[v0];
    const Vec<3> normal = (b.mesh.vertices[v1] - p0).cross(b.mesh.vertices[v2] - p0);
    Vec<3> towards = Vec<3>::Zero();
    for (int k = 0; k < n_out; ++k) towards += point(out[k]);
    for (int k = 0; k < n_in; ++k) towards -= point(in[k]) * (double(n_out) / n_in);
    if (normal.dot(towards) < 0.0) std::swap(v1, v2);
    b.mesh.elements.push_back({v0, v1, v2});
  };
  if (n_in == 1 || n_in == 3) {
    const Index apex = n_in == 1 ? in[0] : out[0];
    const std::array<Index, 3> base =
        n_in == 1 ? std::array<Index, 3>{out[0], out[1], out[2]} : std::array<Index, 3>{in[0], in[1], in[2]};
    add(b.vertex(apex, base[0]), b.vertex(apex, base[1]), b.vertex(apex, base[2]));
    return;
  }
  // Two in, two out: the four cut edges form a quadrilateral in0-out0, in0-out1, in1-out1, in1-out0.
  const int q0 = b.vertex(in[0], out[0]), q1 = b.vertex(in[0], out[1]), q2 = b.vertex(in[1], out[1]),
            q3 = b.vertex(in[1], out[0]);
  add(q0, q1, q2);
  add(q0, q2, q3);
}

}  // namespace

template <int Dim>
Mesh<Dim> extract(const Function<Dim>& phi, const Box<Dim>& box, double cell) {
  LIQUID_VERIFY(box.valid(), "surface: the box must have lo < hi along every axis");
  LIQUID_VERIFY(cell > 0.0 && std::isfinite(cell), "surface: the cell size must be positive, not {}", cell);
  Grid<Dim> grid;
  grid.lo = box.lo;
  for (int d = 0; d < Dim; ++d) {
    grid.n[d] = std::max<Index>(1, static_cast<Index>(std::ceil(box.size()[d] / cell - 1e-9)));
    grid.h[d] = box.size()[d] / static_cast<double>(grid.n[d]);
  }
  const Index n_nodes = grid.n_nodes();
  LIQUID_VERIFY(n_nodes < (Index(1) << 31), "surface: a grid of {} nodes is too large (cell {} in a box {})",
                n_nodes, cell, fmt::join(box.size().array(), " x "));
  std::vector<double> value(n_nodes);
#pragma omp parallel for schedule(dynamic, 1024)
  for (Index f = 0; f < n_nodes; ++f) value[f] = phi(grid.point(grid.coords(f)));
  for (Index f = 0; f < n_nodes; ++f) {
    LIQUID_VERIFY(std::isfinite(value[f]), "surface: the level set is not finite at node {} ({})", f,
                  fmt::join(grid.point(grid.coords(f)).array(), ", "));
    if (value[f] == 0.0) value[f] = 1e-300;  // a node exactly on the surface counts as outside
  }
  Builder<Dim> b{grid, value, {}, {}};
  Eigen::Matrix<Index, Dim, 1> k = Eigen::Matrix<Index, Dim, 1>::Zero();
  while (true) {
    if constexpr (Dim == 2) {
      const Index c0 = grid.node(k), c1 = grid.node(k + Eigen::Matrix<Index, 2, 1>(1, 0)),
                  c2 = grid.node(k + Eigen::Matrix<Index, 2, 1>(1, 1)),
                  c3 = grid.node(k + Eigen::Matrix<Index, 2, 1>(0, 1));
      const double centre = 0.25 * (value[c0] + value[c1] + value[c2] + value[c3]);
      square(b, {c0, c1, c2, c3}, centre);
    } else {
      static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
      for (const auto& perm : perms) {
        std::array<Index, 4> t{};
        Eigen::Matrix<Index, 3, 1> c = k;
        t[0] = grid.node(c);
        for (int s = 0; s < 3; ++s) {
          ++c[perm[s]];
          t[s + 1] = grid.node(c);
        }
        tetrahedron(b, t);
      }
    }
    int d = 0;
    while (d < Dim && ++k[d] >= grid.n[d]) k[d] = 0, ++d;
    if (d == Dim) break;
  }
  return std::move(b.mesh);
}

template struct Mesh<2>;
template struct Mesh<3>;
template Mesh<2> extract<2>(const Function<2>&, const Box<2>&, double);
template Mesh<3> extract<3>(const Function<3>&, const Box<3>&, double);

}  // namespace liquid::surface
