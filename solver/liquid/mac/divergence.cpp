#include "liquid/mac/divergence.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/rbf/polynomial.hpp"

namespace liquid::mac {

template <int Dim>
std::vector<double> fv_divergence(const CellGraph<Dim>& graph, const std::vector<double>& u) {
  LIQUID_VERIFY(static_cast<int>(u.size()) >= graph.face_capacity(),
                "fv_divergence: {} face values for {} faces", u.size(), graph.face_capacity());
  std::vector<double> div(graph.cell_capacity(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<CellId> cells = graph.cell_ids();
#pragma omp parallel for schedule(static) if (cells.size() > 8192)
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const CellId c = cells[i];
    double flux = 0.0;
    for (FaceId f : graph.faces(c)) {
      const GraphFace& g = graph.face(f);
      const double sign = g.cell[0] == c ? 1.0 : -1.0;  // c below the face: outward normal is +axis
      flux += sign * u[f] * graph.face_area(f);
    }
    div[c] = flux / graph.volume(c);
  }
  return div;
}

template <int Dim>
std::vector<double> rbf_divergence(const CellGraph<Dim>& graph, const std::vector<double>& u,
                                   const rbf::Config& config, double growth) {
  LIQUID_VERIFY(static_cast<int>(u.size()) >= graph.face_capacity(),
                "rbf_divergence: {} face values for {} faces", u.size(), graph.face_capacity());
  std::vector<double> div(graph.cell_capacity(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<CellId> cells = graph.cell_ids();
  const std::size_t n_target =
      static_cast<std::size_t>(std::ceil(growth * rbf::n_polynomial_terms(Dim, config.degree))) + 1;
  std::string failure;
#pragma omp parallel
  {
    std::vector<CellId> ring;
    std::vector<FaceId> faces;
    std::vector<Vec<Dim>> nodes;
    std::vector<double> w;
#pragma omp for schedule(dynamic, 64)
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const CellId c = cells[i];
      const Vec<Dim> x = graph.centre(c);
      double sum = 0.0;
      try {
        for (int k = 0; k < Dim; ++k) {
          // The k-normal faces near c can lie on too few planes x_k = const for the requested degree
          // (the engine would lower it): widen the neighbourhood until the full degree is carried.
          rbf::Status st;
          std::size_t n_keep = n_target;
          for (int rings = 1; rings <= 3; ++rings, n_keep += n_target / 2) {
            graph.k_ring(c, rings, ring);
            faces.clear();
            for (CellId r : ring)
              for (FaceId f : graph.faces(r))
                if (graph.face(f).axis == k) faces.push_back(f);
            std::sort(faces.begin(), faces.end());
            faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
            std::sort(faces.begin(), faces.end(), [&](FaceId a, FaceId b) {
              const double da = (graph.face_centre(a) - x).squaredNorm(),
                           db = (graph.face_centre(b) - x).squaredNorm();
              return da != db ? da < db : a < b;
            });
            if (faces.size() > n_keep) faces.resize(n_keep);
            nodes.clear();
            for (FaceId f : faces) nodes.push_back(graph.face_centre(f));
            st = rbf::weights<Dim>(nodes, x, rbf::Operator<Dim>::partial(k), config, w);
            if (st.info == rbf::Info::ok) break;
          }
          LIQUID_VERIFY(st.usable(), "cell {}: RBF-FD divergence weights along axis {} unusable: {}", c, k,
                        st.describe());
          for (std::size_t j = 0; j < faces.size(); ++j) sum += w[j] * u[faces[j]];
        }
        div[c] = sum;
      } catch (const std::exception& e) {
#pragma omp critical(liquid_divergence_failure)
        if (failure.empty()) failure = e.what();
      }
    }
  }
  if (!failure.empty()) throw Error(failure);
  return div;
}

template std::vector<double> fv_divergence<2>(const CellGraph<2>&, const std::vector<double>&);
template std::vector<double> fv_divergence<3>(const CellGraph<3>&, const std::vector<double>&);
template std::vector<double> rbf_divergence<2>(const CellGraph<2>&, const std::vector<double>&,
                                               const rbf::Config&, double);
template std::vector<double> rbf_divergence<3>(const CellGraph<3>&, const std::vector<double>&,
                                               const rbf::Config&, double);

}  // namespace liquid::mac
