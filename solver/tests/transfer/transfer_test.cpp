// Particle <-> face transfers: the RBF transfer reproduces linear fields on any non-graded tree;
// MLS weights reproduce their polynomial degree; APIC conserves linear and angular momentum
// (particle -> face -> particle) on a uniform tree, and its face -> particle transfer keeps no more
// energy than the faces hold; faces no particle reaches are reported and
// extrapolated, never NaN; clamping acts and is counted; every transfer gives the same bits on 1
// and on several threads; face -> particle with shared factors agrees with per-cell factors.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <fmt/format.h>

#include "liquid/core/error.hpp"
#include "liquid/particles/advect.hpp"
#include "liquid/particles/seeding.hpp"
#include "liquid/transfer/extrapolate.hpp"
#include "liquid/transfer/mls.hpp"
#include "liquid/transfer/regular.hpp"
#include "liquid/transfer/scattered.hpp"
#include "liquid/transfer/velocity_field.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

template <typename T>
class TransferTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(TransferTest, Dims);

template <int Dim>
Vec<Dim> linear_field(const Vec<Dim>& x) {
  Vec<Dim> v;
  for (int k = 0; k < Dim; ++k) {
    v[k] = 0.3 - 0.7 * k;
    for (int j = 0; j < Dim; ++j) v[k] += (1.0 + k - 0.5 * j) * x[j];
  }
  return v;
}

template <int Dim>
tree::CellGraph<Dim> random_tree(std::uint64_t seed, int jump) {
  tree::CellGraphOptions<Dim> options;
  options.max_jump = jump;
  return tree::random<Dim>(Box<Dim>{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)}, seed, 2,
                           Dim == 2 ? 6 : 4, 0.35, options);
}

template <int Dim>
particles::Particles<Dim> seeded(const tree::CellGraph<Dim>& g, double jitter,
                                 const levelset::Function<Dim>& region = {}) {
  particles::Particles<Dim> p;
  particles::SeedOptions o;
  o.jitter = jitter;
  const auto everywhere = [](const Vec<Dim>&) { return -1.0; };
  particles::seed_region<Dim>(g, region ? region : levelset::Function<Dim>(everywhere), o, p);
  return p;
}

TYPED_TEST(TransferTest, RbfReproducesLinearFieldsOnNonGradedTrees) {
  constexpr int Dim = TypeParam::value;
  for (int jump : {1, 2, 3}) {
    const auto g = random_tree<Dim>(20 + jump, jump);
    auto p = seeded<Dim>(g, 0.6);
    for (int i = 0; i < p.size(); ++i) p.v[i] = linear_field<Dim>(p.x[i]);
    particles::CellBins bins;
    particles::bin_particles<Dim>(g, p.x, bins);
    transfer::TransferOptions o = transfer::TransferOptions::paper_rbf();
    o.clamp = false;
    transfer::FaceValues faces;
    const transfer::TransferReport r = transfer::particles_to_faces<Dim>(g, p, bins, o, faces);
    EXPECT_EQ(r.empty, 0);
    EXPECT_EQ(r.fallback, 0);
    double worst = 0.0;
    g.for_each_face([&](tree::FaceId f) {
      ASSERT_TRUE(faces.known[f]);
      worst = std::max(worst, std::abs(faces.value[f] - linear_field<Dim>(g.face_centre(f))[g.face(f).axis]));
    });
    EXPECT_LT(worst, 1e-10) << "particle -> face, jump " << jump;

    std::vector<double> u(g.face_capacity(), 0.0);
    g.for_each_face([&](tree::FaceId f) { u[f] = linear_field<Dim>(g.face_centre(f))[g.face(f).axis]; });
    std::vector<Vec<Dim>> v(p.size());
    const transfer::TransferReport back = transfer::faces_to_points<Dim>(g, u, {}, p.x, bins, o, v);
    EXPECT_EQ(back.empty, 0);
    double worst_back = 0.0;
    for (int i = 0; i < p.size(); ++i)
      worst_back = std::max(worst_back, (v[i] - linear_field<Dim>(p.x[i])).norm());
    EXPECT_LT(worst_back, 1e-10) << "face -> particle, jump " << jump;
  }
}

TYPED_TEST(TransferTest, MlsWeightsReproduceTheirDegreeAndLowerItWhenShort) {
  constexpr int Dim = TypeParam::value;
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto cubic = [](const Vec<Dim>& x) {
    double v = 1.0 + x[0] - 2 * x[1] * x[1] * x[0] + 0.5 * x[1] * x[1] * x[1];
    if constexpr (Dim == 3) v += x[2] * x[0] * x[1] - x[2] * x[2] * x[2];
    return v;
  };
  std::vector<Vec<Dim>> nodes(60);
  for (auto& x : nodes)
    for (int k = 0; k < Dim; ++k) x[k] = u(rng);
  const Vec<Dim> at = Vec<Dim>::Constant(0.1);
  std::vector<double> w;
  ASSERT_EQ(transfer::mls_weights<Dim>(nodes, at, 3, w), 3);
  double value = 0.0;
  for (std::size_t i = 0; i < nodes.size(); ++i) value += w[i] * cubic(nodes[i]);
  EXPECT_NEAR(value, cubic(at), 1e-10);
  // Three nodes carry a linear fit in 2D, not a quadratic; collinear nodes only a line's.
  std::vector<Vec<Dim>> few(nodes.begin(), nodes.begin() + Dim + 1);
  EXPECT_EQ(transfer::mls_weights<Dim>(few, at, 3, w), 1);
  std::vector<Vec<Dim>> line(8, Vec<Dim>::Zero());
  for (int i = 0; i < 8; ++i) line[i][0] = 0.1 * i;
  EXPECT_EQ(transfer::mls_weights<Dim>(line, at, 2, w), 0);
  EXPECT_EQ(transfer::mls_weights<Dim>({}, at, 2, w), -1);
}

/// n particles carrying APIC's field "apic" (C = 0) at random positions at least 1.5 cells from
/// the walls of the unit box (whole stencils), with random velocities in [-1, 1]^Dim.
template <int Dim>
particles::Particles<Dim> interior_apic_particles(const transfer::RegularLattice<Dim>& lattice, int n,
                                                  std::mt19937_64& rng) {
  const double h = lattice.h()[0];
  particles::Particles<Dim> p;
  p.add_field("apic", Dim * Dim);
  std::uniform_real_distribution<double> pos(1.5 * h, 1.0 - 1.5 * h), vel(-1.0, 1.0);
  for (int i = 0; i < n; ++i) {
    Vec<Dim> x, v;
    for (int k = 0; k < Dim; ++k) x[k] = pos(rng), v[k] = vel(rng);
    p.push_back(x, v);
  }
  return p;
}

TYPED_TEST(TransferTest, RegularScatterMatchesTheGatherOnAnyThreadCount) {
  // The scatter must give every face the gather's weight and value (up to the order of the sums),
  // for particles anywhere: at walls (clamped stencils), exactly on cell faces of the slowest axis
  // (the slab borders) and on the walls, with masses and APIC's affine part, on odd and tiny
  // lattices (one slab, a lone odd slab). And the same bits on one thread as on two.
  constexpr int Dim = TypeParam::value;
  for (const int level : {1, 2, 3}) {
    const auto g = tree::uniform<Dim>(Box<Dim>{}, level);
    const transfer::RegularLattice<Dim> lattice(g);
    const double h = lattice.h()[0];
    std::mt19937_64 rng(30 + level);
    std::uniform_real_distribution<double> pos(0.0, 1.0), vel(-1.0, 1.0);
    std::uniform_int_distribution<int> layer(0, static_cast<int>(lattice.n()));
    particles::Particles<Dim> p;
    p.add_field("apic", Dim * Dim);
    for (int i = 0; i < 600; ++i) {
      Vec<Dim> x, v;
      for (int k = 0; k < Dim; ++k) x[k] = pos(rng), v[k] = vel(rng);
      if (i % 5 == 0) x[Dim - 1] = h * layer(rng);  // on a face of the slowest axis (walls too)
      if (i % 7 == 1) x[0] = 0.0;
      p.push_back(x, v);
    }
    for (double& c : p.field(p.field_index("apic"))) c = 2.0 * vel(rng);
    std::vector<double> masses(p.size());
    for (double& m : masses) m = 0.25 + std::abs(vel(rng));
    particles::CellBins bins;
    particles::bin_particles<Dim>(g, p.x, bins);
    for (const auto scheme : {transfer::RegularScheme::pic, transfer::RegularScheme::apic}) {
      transfer::FaceValues gathered, one, two;
      const transfer::TransferReport rg =
          transfer::linear_to_faces_gather<Dim>(g, lattice, p, bins, scheme, masses, gathered);
      const int threads = omp_get_max_threads();
      omp_set_num_threads(1);
      const transfer::TransferReport r1 =
          transfer::linear_to_faces<Dim>(g, lattice, p, bins, scheme, masses, one);
      omp_set_num_threads(std::max(2, threads));
      transfer::linear_to_faces<Dim>(g, lattice, p, bins, scheme, masses, two);
      omp_set_num_threads(threads);
      EXPECT_EQ(r1.targets, rg.targets);
      EXPECT_EQ(r1.empty, rg.empty);
      long compared = 0;
      g.for_each_face([&](tree::FaceId f) {
        ASSERT_EQ(one.known[f], gathered.known[f]) << "face " << f << " level " << level;
        EXPECT_EQ(one.value[f], two.value[f]) << "face " << f;
        EXPECT_EQ(one.weight[f], two.weight[f]) << "face " << f;
        if (!gathered.known[f]) return;
        ++compared;
        EXPECT_NEAR(one.weight[f], gathered.weight[f], 1e-13 * gathered.weight[f]) << "face " << f;
        EXPECT_NEAR(one.value[f], gathered.value[f], 1e-12 * (1.0 + std::abs(gathered.value[f])))
            << "face " << f;
      });
      EXPECT_GT(compared, 0);
    }
  }
}

TYPED_TEST(TransferTest, ApicConservesLinearAndAngularMomentum) {
  constexpr int Dim = TypeParam::value;
  const auto g = tree::uniform<Dim>(Box<Dim>{}, Dim == 2 ? 5 : 3);
  const transfer::RegularLattice<Dim> lattice(g);
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> vel(-1.0, 1.0);
  particles::Particles<Dim> p = interior_apic_particles<Dim>(lattice, 2000, rng);
  const int apic = p.field_index("apic");
  for (double& c : p.field(apic)) c = 3.0 * vel(rng);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  std::vector<double> masses(p.size());
  for (double& m : masses) m = 0.5 + 0.5 * std::abs(vel(rng));

  const Vec<Dim> p0 = transfer::particle_momentum<Dim>(p, masses);
  const Eigen::Vector3d l0 = transfer::particle_angular_momentum<Dim>(lattice, p, p.field(apic), masses);
  transfer::FaceValues faces;
  transfer::linear_to_faces<Dim>(g, lattice, p, bins, transfer::RegularScheme::apic, masses, faces);
  const Vec<Dim> p1 = transfer::face_momentum<Dim>(g, faces);
  const Eigen::Vector3d l1 = transfer::face_angular_momentum<Dim>(g, faces);
  EXPECT_LT((p1 - p0).norm(), 1e-11 * p0.norm() + 1e-11);
  EXPECT_LT((l1 - l0).norm(), 1e-11 * l0.norm() + 1e-11);

  // Visiting the points cell by cell (the bins' order) gives the same values bit for bit.
  std::vector<Vec<Dim>> v_binned(p.size());
  std::vector<double> c_binned(p.field(apic).size());
  transfer::linear_to_points<Dim>(lattice, faces.value, p.x, v_binned, c_binned, bins.index);
  transfer::linear_to_points<Dim>(lattice, faces.value, p.x, p.v, p.field(apic));
  for (int i = 0; i < p.size(); ++i) EXPECT_EQ(v_binned[i], p.v[i]) << "point " << i;
  EXPECT_TRUE(std::equal(c_binned.begin(), c_binned.end(), p.field(apic).begin()));
  EXPECT_THROW(transfer::linear_to_points<Dim>(lattice, faces.value, p.x, v_binned, {},
                                               std::span(bins.index).first(bins.index.size() - 1)),
               Error);
  const Vec<Dim> p2 = transfer::particle_momentum<Dim>(p, masses);
  const Eigen::Vector3d l2 = transfer::particle_angular_momentum<Dim>(lattice, p, p.field(apic), masses);
  EXPECT_LT((p2 - p0).norm(), 1e-11 * p0.norm() + 1e-11);
  EXPECT_LT((l2 - l0).norm(), 1e-11 * l0.norm() + 1e-11);

  // PIC (no affine part) keeps linear momentum but not angular momentum.
  particles::Particles<Dim> q = p;
  for (double& c : q.field(apic)) c = 0.0;
  const Eigen::Vector3d lq0 = transfer::particle_angular_momentum<Dim>(lattice, q, {}, masses);
  transfer::linear_to_faces<Dim>(g, lattice, q, bins, transfer::RegularScheme::pic, masses, faces);
  transfer::linear_to_points<Dim>(lattice, faces.value, q.x, q.v);
  EXPECT_LT(
      (transfer::particle_momentum<Dim>(q, masses) - transfer::particle_momentum<Dim>(p, masses)).norm(),
      1e-9);
  EXPECT_GT((transfer::particle_angular_momentum<Dim>(lattice, q, {}, masses) - lq0).norm(),
            1e-6 * lq0.norm());

  EXPECT_THROW(transfer::RegularLattice<Dim>(random_tree<Dim>(1, 2)), Error);
}

// Face -> particle with APIC fits v + C (x_f - x_p) to the stencil's faces by weighted least
// squares, so the particle's energy with its affine part, |v|^2 / 2 + particle_affine_energy, is at
// most the stencil's weighted face energy sum_f w_f u_f^2 / 2, and equal to it for a linear field.
TYPED_TEST(TransferTest, ApicAffineEnergyIsWhatTheFitKeepsOfTheFaces) {
  constexpr int Dim = TypeParam::value;
  const auto g = tree::uniform<Dim>(Box<Dim>{}, Dim == 2 ? 5 : 3);
  const transfer::RegularLattice<Dim> lattice(g);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> vel(-1.0, 1.0);
  particles::Particles<Dim> p = interior_apic_particles<Dim>(lattice, 500, rng);
  const int apic = p.field_index("apic");
  const auto face_energy = [&](std::span<const double> u) {
    double e = 0.0;
    for (const Vec<Dim>& x : p.x)
      for (int k = 0; k < Dim; ++k) {
        const transfer::LinearStencil<Dim> st(lattice, k, x);
        for (int corner = 0; corner < (1 << Dim); ++corner) {
          IVec<Dim> a = st.base;
          for (int j = 0; j < Dim; ++j) a[j] += (corner >> j) & 1;
          e += 0.5 * st.weight(corner) * u[lattice.face(k, a)] * u[lattice.face(k, a)];
        }
      }
    return e;
  };
  const auto particle_energy = [&] {
    double e = transfer::particle_affine_energy<Dim>(lattice, p, p.field(apic));
    for (const Vec<Dim>& v : p.v) e += 0.5 * v.squaredNorm();
    return e;
  };
  std::vector<double> u(g.face_capacity(), 0.0);
  // A linear field: the fit is exact, nothing is lost.
  g.for_each_face([&](tree::FaceId f) { u[f] = linear_field<Dim>(g.face_centre(f))[g.face(f).axis]; });
  transfer::linear_to_points<Dim>(lattice, u, p.x, p.v, p.field(apic));
  const double affine = transfer::particle_affine_energy<Dim>(lattice, p, p.field(apic));
  // The affine part is a few 1e-4 of the whole here (2D) and the check below holds to 1e-12 of it.
  EXPECT_GT(affine, 1e-5 * particle_energy());
  EXPECT_NEAR(particle_energy(), face_energy(u), 1e-12 * face_energy(u));
  // Random faces: the fit keeps less than the faces hold.
  for (double& x : u) x = vel(rng);
  transfer::linear_to_points<Dim>(lattice, u, p.x, p.v, p.field(apic));
  EXPECT_LT(particle_energy(), face_energy(u));
}

TYPED_TEST(TransferTest, EmptyFacesAreReportedExtrapolatedAndNeverNaN) {
  constexpr int Dim = TypeParam::value;
  const auto g = random_tree<Dim>(31, 2);
  const auto blob = levelset::sphere<Dim>(Vec<Dim>::Constant(-0.3), 0.45);
  auto p = seeded<Dim>(g, 0.3, blob);
  for (int i = 0; i < p.size(); ++i) p.v[i] = linear_field<Dim>(p.x[i]);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  for (const transfer::TransferOptions& o :
       {transfer::TransferOptions::paper_rbf(), transfer::TransferOptions::cubic_mls()}) {
    transfer::FaceValues faces;
    const transfer::TransferReport r = transfer::particles_to_faces<Dim>(g, p, bins, o, faces);
    long unknown = 0;
    g.for_each_face([&](tree::FaceId f) {
      ASSERT_TRUE(std::isfinite(faces.value[f]));
      unknown += !faces.known[f];
    });
    EXPECT_GT(r.empty, 0);
    EXPECT_EQ(r.empty, unknown);
    // Points in cells with no known face nearby are left at zero and counted.
    std::vector<Vec<Dim>> far{Vec<Dim>::Constant(0.97)};
    particles::CellBins far_bins;
    particles::bin_particles<Dim>(g, far, far_bins);
    std::vector<Vec<Dim>> v(1, Vec<Dim>::Constant(5.0));
    const transfer::TransferReport back =
        transfer::faces_to_points<Dim>(g, faces.value, faces.known, far, far_bins, o, v);
    EXPECT_EQ(back.empty, Dim);
    EXPECT_EQ(v[0], Vec<Dim>::Zero());
    double lo = 1e300, hi = -1e300;
    g.for_each_face([&](tree::FaceId f) {
      if (faces.known[f]) lo = std::min(lo, faces.value[f]), hi = std::max(hi, faces.value[f]);
    });
    // One layer fills the faces next to the blob; enough layers fill the whole (connected) graph.
    const transfer::ExtrapolationReport e1 = transfer::extrapolate_faces<Dim>(g, 1, faces.value, faces.known);
    ASSERT_EQ(e1.filled.size(), 1u);
    EXPECT_GT(e1.filled[0], 0);
    EXPECT_GT(e1.left_unknown, 0);
    EXPECT_EQ(e1.filled[0] + e1.left_unknown, unknown);
    const transfer::ExtrapolationReport all =
        transfer::extrapolate_faces<Dim>(g, 1000, faces.value, faces.known);
    EXPECT_EQ(all.left_unknown, 0);
    g.for_each_face([&](tree::FaceId f) {
      ASSERT_TRUE(std::isfinite(faces.value[f]));
      // Means of known neighbours: a maximum principle.
      EXPECT_GE(faces.value[f], lo);
      EXPECT_LE(faces.value[f], hi);
    });
  }
}

// The definition the frontier extrapolation must reproduce: each layer visits every unknown face and
// gives it the mean of the known same-axis faces of its cells and of their face neighbours.
template <int Dim>
std::vector<long> extrapolate_by_definition(const tree::CellGraph<Dim>& g, int layers,
                                            std::vector<double>& value, std::vector<std::uint8_t>& known) {
  std::vector<long> counts;
  for (int layer = 0; layer < layers; ++layer) {
    long unknown = 0;
    g.for_each_face([&](tree::FaceId f) { unknown += !known[f]; });
    if (unknown == 0) break;
    std::vector<std::pair<tree::FaceId, double>> fills;
    std::vector<tree::CellId> ring, cells;
    g.for_each_face([&](tree::FaceId f) {
      if (known[f]) return;
      cells.clear();
      for (tree::CellId c : g.face(f).cell) {
        if (c == tree::no_cell) continue;
        g.k_ring(c, 1, ring);
        cells.insert(cells.end(), ring.begin(), ring.end());
      }
      std::sort(cells.begin(), cells.end());
      cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
      std::vector<tree::FaceId> seen;
      for (tree::CellId c : cells)
        for (tree::FaceId h : g.faces(c))
          if (g.face(h).axis == g.face(f).axis && known[h]) seen.push_back(h);
      std::sort(seen.begin(), seen.end());
      seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
      if (seen.empty()) return;
      double sum = 0.0;
      for (tree::FaceId h : seen) sum += value[h];
      fills.emplace_back(f, sum / static_cast<double>(seen.size()));
    });
    for (const auto& [f, v] : fills) value[f] = v, known[f] = 1;
    counts.push_back(static_cast<long>(fills.size()));
    if (fills.empty()) break;
  }
  return counts;
}

/// Compares an extrapolation's result (v1, k1, report r) with the definition's (v2, k2, counts):
/// the same faces filled per layer and left unknown, the values to round-off (the sums run in
/// another order). Returns the faces left unknown.
template <int Dim>
long expect_as_defined(const tree::CellGraph<Dim>& g, const transfer::ExtrapolationReport& r,
                       const std::vector<double>& v1, const std::vector<std::uint8_t>& k1,
                       const std::vector<double>& v2, const std::vector<std::uint8_t>& k2,
                       const std::vector<long>& counts, const std::string& label) {
  EXPECT_EQ(r.filled, counts) << label;
  long unknown = 0, differ = 0;
  double worst = 0.0;
  g.for_each_face([&](tree::FaceId f) {
    unknown += !k1[f];
    differ += k1[f] != k2[f];
    worst = std::max(worst, std::abs(v1[f] - v2[f]));
  });
  EXPECT_EQ(r.left_unknown, unknown) << label;
  EXPECT_EQ(differ, 0) << label;
  EXPECT_LT(worst, 1e-14) << label;
  return unknown;
}

TYPED_TEST(TransferTest, ExtrapolationMatchesTheDefinitionOnAnyThreadCount) {
  // The tree's extrapolation finds each layer's faces by sweeps over the cells and faces: the same
  // faces in each layer as the definition, values to round-off, and the same bits on one thread as
  // on two.
  constexpr int Dim = TypeParam::value;
  for (int jump : {1, 3}) {
    const auto g = random_tree<Dim>(40 + jump, jump);
    std::mt19937_64 rng(7 + jump);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto elsewhere = random_tree<Dim>(60 + jump, jump);
    tree::CellAdjacency<Dim> kept;
    kept.bind(elsewhere);
    // Known faces: those in a ball and, per axis, a few scattered ones, so fronts of different axes
    // start in different places and meet.
    // Known inside a ball (few known faces: the layers spread from them) or outside it (few unknown:
    // the first layer asks them, as in an adaptive tree's narrow band of air).
    for (bool inside : {true, false})
      for (int layers : {1, 3, 1000}) {
        std::vector<double> value(g.face_capacity(), 0.0);
        std::vector<std::uint8_t> known(g.face_capacity(), 0);
        g.for_each_face([&](tree::FaceId f) {
          const Vec<Dim> x = g.face_centre(f);
          if ((x.norm() < 0.4) == inside || u(rng) > 0.995) known[f] = 1, value[f] = u(rng);
        });
        std::vector<double> v1 = value, v2 = value, v3 = value;
        std::vector<std::uint8_t> k1 = known, k2 = known, k3 = known;
        const int threads = omp_get_max_threads();
        omp_set_num_threads(1);
        const transfer::ExtrapolationReport r = transfer::extrapolate_faces<Dim>(g, layers, v1, k1);
        omp_set_num_threads(std::max(2, threads));
        // With an adjacency kept from a call on another graph: it is remade for this one.
        const transfer::ExtrapolationReport r2 = transfer::extrapolate_faces<Dim>(g, layers, v3, k3, &kept);
        omp_set_num_threads(threads);
        const std::vector<long> counts = extrapolate_by_definition<Dim>(g, layers, v2, k2);
        const long unknown =
            expect_as_defined<Dim>(g, r, v1, k1, v2, k2, counts,
                                   fmt::format("jump {}, {} layers, known inside {}", jump, layers, inside));
        EXPECT_EQ(r2.filled, r.filled);
        EXPECT_EQ(v1, v3);
        EXPECT_EQ(k1, k3);
        if (layers == 1000) {
          EXPECT_EQ(unknown, 0);
        }
      }
  }
}

TYPED_TEST(TransferTest, LatticeExtrapolationMatchesTheDefinitionOnAnyThreadCount) {
  // The regular baselines' extrapolation walks the lattice instead of the graph: the same faces in
  // each layer as the definition, values to round-off, walls and corners included (a ball touching
  // the box's side), known regions large and small, and the same bits on one thread as on two.
  constexpr int Dim = TypeParam::value;
  for (const int level : {1, 3, Dim == 2 ? 5 : 4}) {
    const auto g = tree::uniform<Dim>(Box<Dim>{}, level);
    const transfer::RegularLattice<Dim> lattice(g);
    std::mt19937_64 rng(50 + level);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vec<Dim> centre = Vec<Dim>::Constant(0.5);
    centre[0] = 0.1;
    for (bool inside : {true, false})
      for (int layers : {1, 3, 1000}) {
        std::vector<double> value(g.face_capacity(), 0.0);
        std::vector<std::uint8_t> known(g.face_capacity(), 0);
        g.for_each_face([&](tree::FaceId f) {
          const Vec<Dim> x = g.face_centre(f);
          if (((x - centre).norm() < 0.3) == inside || u(rng) > 0.99) known[f] = 1, value[f] = u(rng);
        });
        std::vector<double> v1 = value, v2 = value, v3 = value;
        std::vector<std::uint8_t> k1 = known, k2 = known, k3 = known;
        const int threads = omp_get_max_threads();
        omp_set_num_threads(1);
        const transfer::ExtrapolationReport r = transfer::extrapolate_lattice<Dim>(lattice, layers, v1, k1);
        omp_set_num_threads(std::max(2, threads));
        transfer::extrapolate_lattice<Dim>(lattice, layers, v3, k3);
        omp_set_num_threads(threads);
        const std::vector<long> counts = extrapolate_by_definition<Dim>(g, layers, v2, k2);
        const long unknown = expect_as_defined<Dim>(
            g, r, v1, k1, v2, k2, counts,
            fmt::format("level {}, {} layers, known inside {}", level, layers, inside));
        EXPECT_EQ(v1, v3);
        EXPECT_EQ(k1, k3);
        // Every face fills in the end when its axis has a known face to start from.
        std::array<bool, Dim> seeded{};
        g.for_each_face([&](tree::FaceId f) { seeded[g.face(f).axis] = seeded[g.face(f).axis] || known[f]; });
        if (layers == 1000 && std::all_of(seeded.begin(), seeded.end(), [](bool b) { return b; })) {
          EXPECT_EQ(unknown, 0);
        }
      }
  }
}

TYPED_TEST(TransferTest, ClampingKeepsValuesInTheRangeOfTheirSources) {
  constexpr int Dim = TypeParam::value;
  const auto g = random_tree<Dim>(41, 2);
  auto p = seeded<Dim>(g, 0.6);
  // A jump: RBF and MLS overshoot next to it.
  for (int i = 0; i < p.size(); ++i) p.v[i] = Vec<Dim>::Constant(p.x[i][0] + p.x[i][1] > 0.05 ? 1.0 : 0.0);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  for (transfer::TransferOptions o :
       {transfer::TransferOptions::paper_rbf(), transfer::TransferOptions::cubic_mls()}) {
    // Particle -> face (clamp_faces, off by default).
    transfer::FaceValues faces;
    transfer::particles_to_faces<Dim>(g, p, bins, o, faces);
    double lo = 0.0, hi = 1.0;
    g.for_each_face(
        [&](tree::FaceId f) { lo = std::min(lo, faces.value[f]), hi = std::max(hi, faces.value[f]); });
    EXPECT_GT(std::max(-lo, hi - 1.0), 1e-3) << o.describe() << ": range " << lo << " .. " << hi;
    o.clamp_faces = true;
    const transfer::TransferReport r = transfer::particles_to_faces<Dim>(g, p, bins, o, faces);
    EXPECT_GT(r.clamped, 0);
    g.for_each_face([&](tree::FaceId f) {
      EXPECT_GE(faces.value[f], 0.0);
      EXPECT_LE(faces.value[f], 1.0);
    });
    // Face -> particle (clamp, on by default) from the step sampled on the faces.
    g.for_each_face([&](tree::FaceId f) {
      const Vec<Dim> x = g.face_centre(f);
      faces.value[f] = x[0] + x[1] > 0.05 ? 1.0 : 0.0;
    });
    std::vector<Vec<Dim>> v(p.size());
    o.clamp = false;
    transfer::faces_to_points<Dim>(g, faces.value, {}, p.x, bins, o, v);
    double vlo = 0.0, vhi = 1.0;
    for (const auto& x : v) vlo = std::min(vlo, x.minCoeff()), vhi = std::max(vhi, x.maxCoeff());
    EXPECT_GT(std::max(-vlo, vhi - 1.0), 1e-3) << o.describe();
    o.clamp = true;
    const transfer::TransferReport back = transfer::faces_to_points<Dim>(g, faces.value, {}, p.x, bins, o, v);
    EXPECT_GT(back.clamped, 0);
    for (const auto& x : v) {
      EXPECT_GE(x.minCoeff(), 0.0);
      EXPECT_LE(x.maxCoeff(), 1.0);
    }
  }
}

TYPED_TEST(TransferTest, SameBitsOnOneAndSeveralThreads) {
  constexpr int Dim = TypeParam::value;
  const auto g = random_tree<Dim>(51, 2);
  auto p = seeded<Dim>(g, 0.5);
  for (int i = 0; i < p.size(); ++i) p.v[i] = Vec<Dim>::Constant(std::sin(3 * p.x[i][0]) * p.x[i][1]);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  const auto uniform =
      tree::uniform<Dim>(Box<Dim>{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)}, Dim == 2 ? 5 : 3);
  const transfer::RegularLattice<Dim> lattice(uniform);
  auto q = seeded<Dim>(uniform, 0.5);
  const int apic = q.add_field("apic", Dim * Dim);
  for (int i = 0; i < q.size(); ++i) q.v[i] = Vec<Dim>::Constant(std::cos(2 * q.x[i][1]));
  particles::CellBins qbins;
  particles::bin_particles<Dim>(uniform, q.x, qbins);

  struct Outcome {
    std::vector<double> rbf, mls, apic;
    std::vector<Vec<Dim>> v_rbf, v_mls, v_apic;
    std::vector<double> c_apic;
  };
  const auto run = [&] {
    Outcome o;
    transfer::FaceValues f;
    transfer::particles_to_faces<Dim>(g, p, bins, transfer::TransferOptions::paper_rbf(), f);
    o.rbf = f.value;
    o.v_rbf.resize(p.size());
    transfer::faces_to_points<Dim>(g, f.value, f.known, p.x, bins, transfer::TransferOptions::paper_rbf(),
                                   o.v_rbf);
    transfer::particles_to_faces<Dim>(g, p, bins, transfer::TransferOptions::cubic_mls(), f);
    o.mls = f.value;
    o.v_mls.resize(p.size());
    transfer::faces_to_points<Dim>(g, f.value, f.known, p.x, bins, transfer::TransferOptions::cubic_mls(),
                                   o.v_mls);
    transfer::linear_to_faces<Dim>(uniform, lattice, q, qbins, transfer::RegularScheme::apic, {}, f);
    o.apic = f.value;
    o.v_apic.resize(q.size());
    o.c_apic.resize(q.field(apic).size());
    transfer::linear_to_points<Dim>(lattice, f.value, q.x, o.v_apic, o.c_apic);
    return o;
  };
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Outcome one = run();
  omp_set_num_threads(std::max(2, threads));
  const Outcome many = run();
  omp_set_num_threads(threads);
  EXPECT_EQ(one.rbf, many.rbf);
  EXPECT_EQ(one.mls, many.mls);
  EXPECT_EQ(one.apic, many.apic);
  EXPECT_EQ(one.v_rbf, many.v_rbf);
  EXPECT_EQ(one.v_mls, many.v_mls);
  EXPECT_EQ(one.v_apic, many.v_apic);
  EXPECT_EQ(one.c_apic, many.c_apic);
}

// Shared factors (one factorisation per stencil layout, the default) and each cell's own agree to
// round-off on a non-graded tree with unknown faces, in faces_to_points and in the velocity field.
TYPED_TEST(TransferTest, SharedFactorsAgreeWithEachCellsOwn) {
  constexpr int Dim = TypeParam::value;
  const auto g = random_tree<Dim>(33, 2);
  const auto p = seeded<Dim>(g, 0.5);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  std::vector<double> u(g.face_capacity(), 0.0);
  std::vector<std::uint8_t> known(g.face_capacity(), 0);
  g.for_each_face([&](tree::FaceId f) {
    const Vec<Dim> x = g.face_centre(f);
    u[f] = std::sin(3.0 * x[0] + x[Dim - 1]) * std::cos(2.0 * x[1]);
    known[f] = x[0] + 0.5 * x[1] < 0.6;  // a band of unknown faces makes more layouts
  });
  transfer::TransferOptions shared = transfer::TransferOptions::paper_rbf(), own = shared;
  own.share_factors = false;
  std::vector<Vec<Dim>> a(p.size()), b(p.size());
  const transfer::TransferReport ra = transfer::faces_to_points<Dim>(g, u, known, p.x, bins, shared, a);
  const transfer::TransferReport rb = transfer::faces_to_points<Dim>(g, u, known, p.x, bins, own, b);
  EXPECT_EQ(ra.fallback, rb.fallback);
  EXPECT_EQ(ra.degree_reduced, rb.degree_reduced);
  const transfer::FaceVelocityField<Dim> fa(g, u, known, shared), fb(g, u, known, own);
  double worst = 0.0, worst_field = 0.0, largest = 0.0;
  for (int i = 0; i < p.size(); ++i) {
    worst = std::max(worst, (a[i] - b[i]).cwiseAbs().maxCoeff());
    worst_field = std::max(worst_field, (fa(p.x[i]) - fb(p.x[i])).cwiseAbs().maxCoeff());
    largest = std::max(largest, b[i].cwiseAbs().maxCoeff());
  }
  EXPECT_GT(largest, 0.5);
  EXPECT_LT(worst, 1e-11);
  EXPECT_LT(worst_field, 1e-11);

  // A cache kept by the caller (the PIC step keeps one across steps): a second field on the same
  // tree makes no new factorisation, and both give the own-cache field's values bit for bit.
  rbf::InterpolantCache<Dim> kept;
  const transfer::FaceVelocityField<Dim> first(g, u, known, shared, {}, nullptr, &kept);
  const long made = kept.misses();
  EXPECT_GT(made, 0);
  const transfer::FaceVelocityField<Dim> second(g, u, known, shared, {}, nullptr, &kept);
  EXPECT_EQ(kept.misses(), made);
  EXPECT_GT(kept.hits(), 0);
  for (int i = 0; i < p.size(); ++i) {
    ASSERT_EQ(first(p.x[i]), fa(p.x[i])) << "particle " << i;
    ASSERT_EQ(second(p.x[i]), fa(p.x[i])) << "particle " << i;
  }
}

TYPED_TEST(TransferTest, AdvectionThroughFaceVelocitiesIsExactForLinearFields) {
  constexpr int Dim = TypeParam::value;
  // A rigid rotation is linear, so the RBF field reproduces it and RK3 through it equals RK3
  // through the analytic field, on any non-graded tree; likewise multilinear on a uniform one.
  const auto rotation = [](const Vec<Dim>& x) {
    Vec<Dim> v = Vec<Dim>::Zero();
    v[0] = -x[1], v[1] = x[0];
    return v;
  };
  const Box<Dim> domain{Vec<Dim>::Constant(-1.0), Vec<Dim>::Constant(1.0)};
  const auto g = random_tree<Dim>(61, 2);
  const auto uniform = tree::uniform<Dim>(domain, Dim == 2 ? 4 : 3);
  const transfer::RegularLattice<Dim> lattice(uniform);
  const auto sample = [&](const tree::CellGraph<Dim>& graph) {
    std::vector<double> u(graph.face_capacity(), 0.0);
    graph.for_each_face([&](tree::FaceId f) { u[f] = rotation(graph.face_centre(f))[graph.face(f).axis]; });
    return u;
  };
  transfer::TransferOptions o = transfer::TransferOptions::paper_rbf();
  o.clamp = false;
  const transfer::FaceVelocityField<Dim> rbf_field(g, sample(g), {}, o);
  const transfer::FaceVelocityField<Dim> linear_field(uniform, lattice, sample(uniform));
  std::vector<Vec<Dim>> a(50), b, c;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (auto& x : a)
    for (int k = 0; k < Dim; ++k) x[k] = u(rng);
  b = a, c = a;
  for (int step = 0; step < 20; ++step) {
    particles::advect<Dim>(a, 0.05, particles::Integrator::rk3, rotation, domain);
    particles::advect<Dim>(b, 0.05, particles::Integrator::rk3, rbf_field, domain);
    particles::advect<Dim>(c, 0.05, particles::Integrator::rk3, linear_field, domain);
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_LT((a[i] - b[i]).norm(), 1e-9);
    EXPECT_LT((a[i] - c[i]).norm(), 1e-12);
  }
  // Cells not prepared up front are factorised on the fly, with the same result.
  const std::vector<tree::CellId> one{g.locate(Vec<Dim>::Zero())};
  const transfer::FaceVelocityField<Dim> partial(g, sample(g), {}, o, one);
  const Vec<Dim> x = Vec<Dim>::Constant(0.61);
  EXPECT_LT((partial(x) - rbf_field(x)).norm(), 1e-14);
  EXPECT_THROW(rbf_field(Vec<Dim>::Constant(std::nan(""))), Error);
}

TYPED_TEST(TransferTest, NodeLimitKeepsTheNearestParticlesAndStaysExactForLinearFields) {
  constexpr int Dim = TypeParam::value;
  transfer::TransferOptions o = transfer::TransferOptions::paper_rbf();
  EXPECT_EQ(o.node_cap(Dim), 4 * (Dim == 2 ? 6 : 10));  // 4 x the degree-2 terms
  o.max_nodes = -1;
  EXPECT_EQ(o.node_cap(Dim), 0);
  // 30 particles per cell: every face's two cells hold more than any limit below.
  const auto g = random_tree<Dim>(71, 2);
  particles::Particles<Dim> p;
  particles::SeedOptions so;
  so.per_cell = 30;
  so.jitter = 0.5;
  particles::seed_region<Dim>(
      g, [](const Vec<Dim>&) { return -1.0; }, so, p);
  for (int i = 0; i < p.size(); ++i) p.v[i] = linear_field<Dim>(p.x[i]);
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, p.x, bins);
  for (int cap : {12, 0, -1}) {
    o.max_nodes = cap;
    transfer::FaceValues faces;
    transfer::particles_to_faces<Dim>(g, p, bins, o, faces);
    double worst = 0.0;
    g.for_each_face([&](tree::FaceId f) {
      worst = std::max(worst, std::abs(faces.value[f] - linear_field<Dim>(g.face_centre(f))[g.face(f).axis]));
    });
    EXPECT_LT(worst, 1e-9) << "max_nodes " << cap;
  }
}

TEST(Transfer, FlipKeepsWhatTheGridDidNotChangeAndPicForgetsIt) {
  // Particles with sub-grid detail on a grid whose velocity changes by a constant: FLIP (alpha 1)
  // adds the change to each particle's own velocity; PIC (alpha 0) replaces it by the grid's.
  const auto g = tree::uniform<2>(Box<2>{}, 4);
  const transfer::RegularLattice<2> lattice(g);
  auto p = seeded<2>(g, 0.5);
  for (int i = 0; i < p.size(); ++i) p.v[i] = Vec<2>(std::sin(40.0 * p.x[i][0]), std::cos(37.0 * p.x[i][1]));
  particles::CellBins bins;
  particles::bin_particles<2>(g, p.x, bins);
  transfer::FaceValues old_faces;
  transfer::linear_to_faces<2>(g, lattice, p, bins, transfer::RegularScheme::pic, {}, old_faces);
  std::vector<double> new_u = old_faces.value, delta_u(new_u.size(), 0.0);
  g.for_each_face([&](tree::FaceId f) {
    delta_u[f] = g.face(f).axis == 0 ? 0.25 : -0.5;
    new_u[f] += delta_u[f];
  });
  std::vector<Vec<2>> pic(p.size()), delta(p.size());
  transfer::linear_to_points<2>(lattice, new_u, p.x, pic);
  transfer::linear_to_points<2>(lattice, delta_u, p.x, delta);
  std::vector<Vec<2>> flip = p.v, blend = p.v, pure_pic = p.v;
  transfer::flip_blend<2>(pic, delta, 1.0, flip);
  transfer::flip_blend<2>(pic, delta, 0.95, blend);
  transfer::flip_blend<2>(pic, delta, 0.0, pure_pic);
  for (int i = 0; i < p.size(); ++i) {
    EXPECT_LT((flip[i] - (p.v[i] + Vec<2>(0.25, -0.5))).norm(), 1e-12);
    EXPECT_EQ(pure_pic[i], pic[i]);
    EXPECT_LT((blend[i] - (0.95 * flip[i] + 0.05 * pic[i])).norm(), 1e-12);
  }
}

TEST(Transfer, BadOptionsAndSizesAreRefused) {
  const auto g = tree::uniform<2>(Box<2>{}, 3);
  particles::Particles<2> p;
  p.push_back(Vec<2>(0.5, 0.5), Vec<2>(1, 1));
  particles::CellBins bins;
  particles::bin_particles<2>(g, p.x, bins);
  transfer::FaceValues f;
  transfer::TransferOptions o;
  o.degree = 7;
  EXPECT_THROW(transfer::particles_to_faces<2>(g, p, bins, o, f), Error);
  o = {};
  o.exponent = 4;
  EXPECT_THROW(transfer::particles_to_faces<2>(g, p, bins, o, f), Error);
  o = {};
  o.wall_rings = 3;
  EXPECT_THROW(transfer::particles_to_faces<2>(g, p, bins, o, f), Error);
  o = {};
  o.rings = 0;
  EXPECT_THROW(transfer::particles_to_faces<2>(g, p, bins, o, f), Error);
  std::vector<double> u(3, 0.0);
  std::vector<Vec<2>> v(1);
  EXPECT_THROW(transfer::faces_to_points<2>(g, u, {}, p.x, bins, transfer::TransferOptions{}, v), Error);
  EXPECT_THROW(transfer::flip_blend<2>(v, v, 1.5, v), Error);
}

}  // namespace
}  // namespace liquid
