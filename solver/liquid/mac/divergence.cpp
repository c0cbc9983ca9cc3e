#include "liquid/mac/divergence.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/core/parallel.hpp"
#include "liquid/mac/stencil.hpp"

namespace liquid::mac {

template <int Dim>
std::vector<double> fv_divergence(const tree::CellGraph<Dim>& graph, const std::vector<double>& u) {
  LIQUID_VERIFY(static_cast<int>(u.size()) >= graph.face_capacity(),
                "fv_divergence: {} face values for {} faces", u.size(), graph.face_capacity());
  std::vector<double> div(graph.cell_capacity(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<tree::CellId> cells = graph.cell_ids();
#pragma omp parallel for schedule(static) if (cells.size() > 8192)
  for (std::size_t i = 0; i < cells.size(); ++i) div[cells[i]] = fv_divergence_at<Dim>(graph, u, cells[i]);
  return div;
}

template <int Dim>
double fv_divergence_at(const tree::CellGraph<Dim>& graph, std::span<const double> u, tree::CellId c) {
  double flux = 0.0;
  for (tree::FaceId f : graph.faces(c)) {
    const tree::GraphFace& g = graph.face(f);
    const double sign = g.cell[0] == c ? 1.0 : -1.0;  // c below the face: outward normal is +axis
    flux += sign * u[f] * graph.face_area(f);
  }
  return flux / graph.volume(c);
}

template <int Dim>
std::vector<double> rbf_divergence(const tree::CellGraph<Dim>& graph, const std::vector<double>& u,
                                   const rbf::Config& config, double growth) {
  LIQUID_VERIFY(static_cast<int>(u.size()) >= graph.face_capacity(),
                "rbf_divergence: {} face values for {} faces", u.size(), graph.face_capacity());
  std::vector<double> div(graph.cell_capacity(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<tree::CellId> cells = graph.cell_ids();
  const std::size_t n_target = stencil_size(Dim, config.degree, growth);
  struct Scratch {
    std::vector<tree::CellId> ring;
    std::vector<tree::FaceId> faces;
    std::vector<Vec<Dim>> nodes;
    std::vector<double> w;
  };
  parallel_for(
      static_cast<long>(cells.size()), [] { return Scratch{}; },
      [&](Scratch& s, long i) {
        const tree::CellId c = cells[i];
        const Vec<Dim> x = graph.centre(c);
        double sum = 0.0;
        for (int k = 0; k < Dim; ++k) {
          // The k-normal faces near c can lie on too few planes x_k = const for the requested degree
          // (the engine would lower it): widen the neighbourhood until the full degree is carried.
          rbf::Status st;
          std::size_t n_keep = n_target;
          for (int rings = 1; rings <= 3; ++rings, n_keep += n_target / 2) {
            graph.k_ring(c, rings, s.ring);
            s.faces.clear();
            for (tree::CellId r : s.ring)
              for (tree::FaceId f : graph.faces(r))
                if (graph.face(f).axis == k) s.faces.push_back(f);
            std::sort(s.faces.begin(), s.faces.end());
            s.faces.erase(std::unique(s.faces.begin(), s.faces.end()), s.faces.end());
            std::sort(s.faces.begin(), s.faces.end(), [&](tree::FaceId a, tree::FaceId b) {
              const double da = (graph.face_centre(a) - x).squaredNorm(),
                           db = (graph.face_centre(b) - x).squaredNorm();
              return da != db ? da < db : a < b;
            });
            if (s.faces.size() > n_keep) s.faces.resize(n_keep);
            s.nodes.clear();
            for (tree::FaceId f : s.faces) s.nodes.push_back(graph.face_centre(f));
            st = rbf::weights<Dim>(s.nodes, x, rbf::Operator<Dim>::partial(k), config, s.w);
            if (st.info == rbf::Info::ok) break;
          }
          LIQUID_VERIFY(st.usable(), "cell {}: RBF-FD divergence weights along axis {} unusable: {}", c, k,
                        st.describe());
          for (std::size_t j = 0; j < s.faces.size(); ++j) sum += s.w[j] * u[s.faces[j]];
        }
        div[c] = sum;
      },
      [](Scratch&) {});
  return div;
}

template double fv_divergence_at<2>(const tree::CellGraph<2>&, std::span<const double>, tree::CellId);
template double fv_divergence_at<3>(const tree::CellGraph<3>&, std::span<const double>, tree::CellId);
template std::vector<double> fv_divergence<2>(const tree::CellGraph<2>&, const std::vector<double>&);
template std::vector<double> fv_divergence<3>(const tree::CellGraph<3>&, const std::vector<double>&);
template std::vector<double> rbf_divergence<2>(const tree::CellGraph<2>&, const std::vector<double>&,
                                               const rbf::Config&, double);
template std::vector<double> rbf_divergence<3>(const tree::CellGraph<3>&, const std::vector<double>&,
                                               const rbf::Config&, double);

}  // namespace liquid::mac
