// Particles and transfers: binning a million particles (from scratch and rebinning after a small
// move), and particle -> face / face -> particle throughput per method, 2D and 3D.
//
//   liquid-bench --benchmark_filter='Binning|ToFaces|ToParticles'
//
// Transfers run on one uniform tree per dimension (2D level 8, 3D level 5: 65k and 32k cells) with
// 2^d jittered Halton particles per cell, so every method sees the same data. Methods: 0 rbf
// (paper), 1 cubic mls, 2 linear fit, 3 PIC (multilinear), 4 APIC, 5 rbf with each cell's own
// factorisation (share_factors = false; face -> particle only), 6 rbf with the full Hager-Higham
// condition estimate (particle -> face only; the default takes two probes), 7 and 8 PIC and APIC
// as a gather (particle -> face only; the scatter's reference), 9 and 10 APIC through the adaptive
// solver's uniform patches (particle -> face only; the tree is one patch), as a scatter and a gather.
#include <benchmark/benchmark.h>

#include <memory>
#include <random>

#include "liquid/particles/seeding.hpp"
#include "liquid/transfer/patches.hpp"
#include "liquid/transfer/regular.hpp"
#include "liquid/transfer/scattered.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

const char* kMethodNames[] = {"rbf",
                              "mls",
                              "linear",
                              "pic",
                              "apic",
                              "rbf, own factors",
                              "rbf, full condition estimate",
                              "pic, gather",
                              "apic, gather",
                              "apic, patches",
                              "apic, patches, gather"};

template <int Dim>
struct Scene {
  tree::CellGraph<Dim> graph;
  std::unique_ptr<transfer::RegularLattice<Dim>> lattice;
  std::unique_ptr<transfer::UniformPatches<Dim>> patches;
  particles::Particles<Dim> particles;
  particles::CellBins bins;
  transfer::FaceValues faces;

  Scene() : graph(tree::uniform<Dim>(Box<Dim>{}, Dim == 2 ? 8 : 5)) {
    lattice = std::make_unique<transfer::RegularLattice<Dim>>(graph);
    patches = std::make_unique<transfer::UniformPatches<Dim>>(graph, graph.cell_ids());
    particles::SeedOptions o;
    o.jitter = 0.5;
    particles::seed_region<Dim>(
        graph, [](const Vec<Dim>&) { return -1.0; }, o, particles);
    for (int i = 0; i < particles.size(); ++i)
      for (int k = 0; k < Dim; ++k) particles.v[i][k] = std::sin(3.0 * particles.x[i][(k + 1) % Dim] + k);
    particles.add_field("apic", Dim * Dim);
    particles::bin_particles<Dim>(graph, particles.x, bins);
    faces.reset(graph.face_capacity());
    graph.for_each_face([&](tree::FaceId f) { faces.value[f] = std::cos(2.0 * graph.face_centre(f)[0]); });
  }
};

template <int Dim>
Scene<Dim>& scene() {
  static Scene<Dim> s;
  return s;
}

transfer::TransferOptions scattered(int method) {
  if (method == 5 || method == 6) {
    transfer::TransferOptions o = transfer::TransferOptions::paper_rbf();
    if (method == 5) o.share_factors = false;
    if (method == 6) o.condition_estimate = rbf::ConditionEstimate::hager_higham;
    return o;
  }
  return method == 0 ? transfer::TransferOptions::paper_rbf()
                     : (method == 1 ? transfer::TransferOptions::cubic_mls()
                                    : transfer::TransferOptions::linear_fit());
}

template <int Dim>
void BM_ToFaces(benchmark::State& state) {
  const int method = static_cast<int>(state.range(0));
  Scene<Dim>& s = scene<Dim>();
  transfer::FaceValues out;
  for (auto _ : state) {
    if (method < 3 || method == 6)
      transfer::particles_to_faces<Dim>(s.graph, s.particles, s.bins, scattered(method), out);
    else if (method < 7)
      transfer::linear_to_faces<Dim>(
          s.graph, *s.lattice, s.particles, s.bins,
          method == 3 ? transfer::RegularScheme::pic : transfer::RegularScheme::apic, {}, out);
    else if (method < 9)
      transfer::linear_to_faces_gather<Dim>(
          s.graph, *s.lattice, s.particles, s.bins,
          method == 7 ? transfer::RegularScheme::pic : transfer::RegularScheme::apic, {}, out);
    else {
      out.reset(s.graph.face_capacity());
      const std::span<const double> affine = s.particles.field(s.particles.find_field("apic"));
      if (method == 9)
        s.patches->to_faces(s.particles, s.bins, affine, out);
      else
        s.patches->to_faces_gather(s.particles, s.bins, affine, out);
    }
    benchmark::DoNotOptimize(out.value.data());
  }
  state.SetLabel(kMethodNames[method]);
  state.counters["faces"] = s.graph.n_faces();
  state.counters["particles"] = s.particles.size();
  state.counters["faces_per_s"] = benchmark::Counter(static_cast<double>(s.graph.n_faces()),
                                                     benchmark::Counter::kIsIterationInvariantRate);
}

template <int Dim>
void BM_ToParticles(benchmark::State& state) {
  const int method = static_cast<int>(state.range(0));
  Scene<Dim>& s = scene<Dim>();
  std::vector<Vec<Dim>> v(s.particles.size());
  std::vector<double> affine(static_cast<std::size_t>(s.particles.size()) * Dim * Dim);
  for (auto _ : state) {
    if (method < 3 || method == 5)
      transfer::faces_to_points<Dim>(s.graph, s.faces.value, {}, s.particles.x, s.bins, scattered(method), v);
    else
      transfer::linear_to_points<Dim>(*s.lattice, s.faces.value, s.particles.x, v,
                                      method == 4 ? std::span<double>(affine) : std::span<double>{});
    benchmark::DoNotOptimize(v.data());
  }
  state.SetLabel(kMethodNames[method]);
  state.counters["particles"] = s.particles.size();
  state.counters["particles_per_s"] = benchmark::Counter(static_cast<double>(s.particles.size()),
                                                         benchmark::Counter::kIsIterationInvariantRate);
}

/// 1M particles on a narrow-band tree; arg 0: bin from scratch, 1: rebin after a move of about a
/// tenth of a finest cell (alternating between two position sets).
template <int Dim>
void BM_Binning(benchmark::State& state) {
  const auto phi = levelset::sphere<Dim>(Vec<Dim>::Constant(0.5), 0.3);
  static const tree::CellGraph<Dim> g =
      tree::narrow_band<Dim>(Box<Dim>{}, phi, Dim == 2 ? 5 : 3, Dim == 2 ? 10 : 7, 2.0);
  constexpr int n = 1 << 20;
  static std::vector<Vec<Dim>> x0, x1;
  if (x0.empty()) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(0.0, 1.0), d(-1.0, 1.0);
    const double step = 0.1 * std::ldexp(1.0, -g.deepest_level());
    x0.resize(n), x1.resize(n);
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < Dim; ++k) {
        x0[i][k] = u(rng);
        x1[i][k] = std::clamp(x0[i][k] + step * d(rng), 0.0, 1.0);
      }
  }
  particles::CellBins bins;
  particles::bin_particles<Dim>(g, x0, bins);
  particles::BinStats stats;
  bool odd = false;
  for (auto _ : state) {
    if (state.range(0) == 0) {
      particles::bin_particles<Dim>(g, x0, bins);
    } else {
      stats = particles::rebin<Dim>(g, odd ? x0 : x1, bins);
      odd = !odd;
    }
    benchmark::DoNotOptimize(bins.index.data());
  }
  state.SetLabel(state.range(0) == 0 ? "from scratch" : "rebin after a move");
  state.counters["cells"] = g.n_cells();
  state.counters["particles_per_s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
  if (state.range(0) == 1) state.counters["stayed_fraction"] = static_cast<double>(stats.stayed) / n;
}

BENCHMARK_TEMPLATE(BM_Binning, 2)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_TEMPLATE(BM_Binning, 3)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_TEMPLATE(BM_ToFaces, 2)
    ->DenseRange(0, 4)
    ->DenseRange(6, 10)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_TEMPLATE(BM_ToFaces, 3)
    ->DenseRange(0, 4)
    ->DenseRange(6, 10)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_TEMPLATE(BM_ToParticles, 2)->DenseRange(0, 5)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_TEMPLATE(BM_ToParticles, 3)->DenseRange(0, 5)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace liquid
