// cellgraph-invariants: the structural invariants of the Cellgraph (rbf-liquids-2020, section 5)
// under every maximum level jump, in 2D and 3D.
//
// Problem. For each dimension and each limit K in {1, 2, 3, 4, unlimited}: a seeded random tree
// (every node between the first and last level split with probability 0.5 in 2D, 0.3 in 3D, then
// balanced to K),
// followed by random adapt() steps (each leaf marked split with probability 3%, merge with 50%).
// check_invariants() runs after the build and after every step.
//
// Expected. Every invariant holds every time: faces tile every cell side, every interior face has
// two leaves, leaves do not overlap and fill the domain, address codes match boxes and point
// location, level jumps stay within K. For K >= 2 the trees are genuinely non-graded (some face
// has a jump of 2 or more). There is no order to fit: the table reports sizes (leaves, faces,
// hanging faces) and the worst jump seen, and the case passes only when no invariant failed.
//
// Options: --max-jump K (only that limit; 0 or >= 64 means unlimited), --levels A:B (levels of the
// random tree; default 2:7 in 2D, 2:5 in 3D: the 3D range ends two levels lower), --full (more
// adapt steps), --trees DIR (write each built tree as DIR/cellgraph-<D>d-jump<K>.h5 + .xmf, with
// the cell field "hanging_faces": how many faces cover only part of one of the cell's sides;
// ParaView opens the .xmf).
#include <cmath>

#include <fmt/format.h>

#include <algorithm>
#include <random>

#include "common/case.hpp"
#include "liquid/core/error.hpp"
#include "liquid/io/tree_output.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid::verification {
namespace {

struct Row {
  int n_leaves = 0, n_faces = 0, n_hanging = 0, n_boundary = 0, worst_jump = 0, n_steps = 0;
  long n_split = 0, n_merged = 0, n_failures = 0;
  std::string first_failure;
};

template <int Dim>
void measure(const tree::CellGraph<Dim>& g, Row& row) {
  row.n_leaves = g.n_cells();
  row.n_faces = g.n_faces();
  row.n_hanging = row.n_boundary = 0;
  g.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& face = g.face(f);
    if (face.is_boundary()) {
      ++row.n_boundary;
      return;
    }
    if (face.hanging()) ++row.n_hanging;
    row.worst_jump = std::max(row.worst_jump, std::abs(face.side_level[0] - face.side_level[1]));
  });
}

template <int Dim>
void check(const tree::CellGraph<Dim>& g, Row& row, const std::string& when) {
  const tree::InvariantReport r = g.check_invariants();
  if (r.ok()) return;
  row.n_failures += r.n_failures;
  if (row.first_failure.empty()) row.first_failure = when + ": " + r.text(3);
}

/// Writes the tree with, per cell, the number of faces that cover only part of one of its sides
/// (its T-junctions); returns the .xmf path.
template <int Dim>
std::string write(const tree::CellGraph<Dim>& g, const std::string& dir, const std::string& jump_name) {
  std::vector<double> hanging(static_cast<std::size_t>(g.cell_capacity()), 0.0);
  g.for_each_face([&](tree::FaceId f) {
    const tree::GraphFace& face = g.face(f);
    for (int s = 0; s < 2; ++s)
      if (face.cell[s] != tree::no_cell && face.hanging(s)) hanging[face.cell[s]] += 1.0;
  });
  const io::CellField fields[] = {{"hanging_faces", hanging}};
  return io::write_tree<Dim>(fmt::format("{}/cellgraph-{}d-jump{}", dir, Dim, jump_name), g, fields).xmf;
}

template <int Dim>
Row run_one(int jump, int first_level, int last_level, int n_steps, std::uint64_t seed,
            const std::optional<std::string>& trees_dir, std::vector<std::string>& written) {
  tree::CellGraphOptions<Dim> options;
  options.max_jump = jump;
  options.max_level = last_level + 1;
  Box<Dim> domain;
  domain.hi[0] = 2.0;  // anisotropic cells
  tree::CellGraph<Dim> g =
      tree::random<Dim>(domain, seed, first_level, last_level, Dim == 2 ? 0.5 : 0.3, options);
  Row row;
  check(g, row, "after the build");
  measure(g, row);
  if (trees_dir)
    written.push_back(
        write(g, *trees_dir, jump == tree::unlimited_jump ? "unlimited" : std::to_string(jump)));
  const Row built = row;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<tree::Mark> marks;
  for (int step = 0; step < n_steps; ++step) {
    marks.assign(g.cell_capacity(), tree::Mark::keep);
    g.for_each_cell([&](tree::CellId c) {
      const double r = u(rng);
      marks[c] = r < 0.03 ? tree::Mark::split : (r < 0.53 ? tree::Mark::merge : tree::Mark::keep);
    });
    const tree::AdaptReport report = g.adapt(marks);
    row.n_split += report.n_split;
    row.n_merged += report.n_merged;
    check(g, row, fmt::format("after adapt step {}", step + 1));
    measure(g, row);
    ++row.n_steps;
  }
  // Report the sizes of the built tree; the worst jump over the whole run.
  const int worst = row.worst_jump;
  row.n_leaves = built.n_leaves;
  row.n_faces = built.n_faces;
  row.n_hanging = built.n_hanging;
  row.n_boundary = built.n_boundary;
  row.worst_jump = worst;
  return row;
}

CaseResult run(const CaseOptions& options) {
  CaseResult result;
  std::vector<int> jumps{1, 2, 3, 4, tree::unlimited_jump};
  if (options.max_jump) {
    const int k = *options.max_jump;
    LIQUID_VERIFY(k >= 0, "cellgraph-invariants: --max-jump must be non-negative (got {})", k);
    jumps = {k == 0 || k >= 64 ? tree::unlimited_jump : k};
  }
  const int first = options.levels ? options.levels->first : 2;
  const int last = options.levels ? options.levels->last : 7;
  LIQUID_VERIFY(first >= 0 && last >= first + 1 && last <= 20,
                "cellgraph-invariants: --levels {}:{} needs 0 <= A < B <= 20", first, last);
  // Every tree holds at least its first level in 3D: refuse before building past the budget.
  LIQUID_VERIFY(
      options.max_cells <= 0 || std::ldexp(1.0, 3 * first) <= double(options.max_cells),
      "--levels {}:{}: a 3D tree from level {} has at least {:.3g} cells, over the budget of {} cells "
      "(--max-cells N raises it)",
      first, last, first, std::ldexp(1.0, 3 * first), options.max_cells);
  const int n_steps = options.full ? 100 : 25;
  std::vector<std::string> written;

  Table table("Random trees after build and adapt steps: sizes of the built tree, worst jump over the run",
              {"dim", "max jump", "leaves", "faces", "hanging faces", "boundary faces", "worst jump",
               "adapt steps", "splits", "merges", "invariant failures"});
  for (int dim : {2, 3}) {
    for (int jump : jumps) {
      const std::uint64_t seed = 1000 * dim + static_cast<std::uint64_t>(std::min(jump, 99));
      const Row row = dim == 2 ? run_one<2>(jump, first, last, n_steps, seed, options.trees_dir, written)
                               : run_one<3>(jump, std::max(0, first), std::max(first + 1, last - 2), n_steps,
                                            seed, options.trees_dir, written);
      const std::string jump_name = jump == tree::unlimited_jump ? "unlimited" : std::to_string(jump);
      table.add_row({long{dim}, jump_name, long{row.n_leaves}, long{row.n_faces}, long{row.n_hanging},
                     long{row.n_boundary}, long{row.worst_jump}, long{row.n_steps}, row.n_split, row.n_merged,
                     row.n_failures});
      result.gate.push_back({fmt::format("{}D jump {} invariant failures", dim, jump_name),
                             GateFigure::Kind::count, double(row.n_failures)});
      result.expect(row.n_failures == 0, fmt::format("{}D, max jump {}: {} invariant failure(s); first {}",
                                                     dim, jump_name, row.n_failures, row.first_failure));
      result.expect(row.worst_jump <= jump,
                    fmt::format("{}D, max jump {}: a jump of {} was seen", dim, jump_name, row.worst_jump));
      if (jump >= 2)
        result.expect(row.worst_jump >= 2,
                      fmt::format("{}D, max jump {}: the trees never became non-graded", dim, jump_name));
    }
  }
  result.tables.push_back(std::move(table));
  result.notes.push_back(
      "hanging faces: faces smaller than the cell side on one of their sides (T-junctions)");
  for (const auto& path : written) result.notes.push_back("tree written: " + path);
  return result;
}

LIQUID_VERIFICATION_CASE(
    {"cellgraph-invariants",
     "Cellgraph invariants on random non-graded trees, 2D and 3D, every level-jump limit",
     true,
     run,
     {Option::levels, Option::max_jump, Option::trees}});

}  // namespace
}  // namespace liquid::verification
