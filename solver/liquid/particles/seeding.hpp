#pragma once
// Seeding and reseeding with Halton points (GSL's gsl_qrng_halton), paper Sec. 4.4.
//
// Every cell gets the same pattern: the first n points of the Halton sequence in [0, 1)^Dim,
// scaled to the cell's box. Seeding is then reproducible, independent of the thread count and of
// the cell numbering, and a cell of any level gets the same relative sampling. Jitter, when asked
// for, moves each point by a hash of (cell key, point number, seed), so it is reproducible too.

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "liquid/levelset/levelset.hpp"
#include "liquid/particles/bins.hpp"
#include "liquid/particles/particles.hpp"
#include "liquid/tree/cell_graph.hpp"

namespace liquid::particles {

/// The first n points of the Dim-dimensional Halton sequence (bases 2, 3, 5), in (0, 1)^Dim.
template <int Dim>
std::vector<Vec<Dim>> halton_points(int n);

/// Velocities for new particles: fills v[i] for the positions x[i] that lie in cells cell[i].
template <int Dim>
using VelocitySource = std::function<void(std::span<const Vec<Dim>> x, std::span<const tree::CellId> cell,
                                          std::span<Vec<Dim>> v)>;

struct SeedOptions {
  int per_cell = 0;        ///< points per cell; 0 means 2^Dim
  double jitter = 0.0;     ///< in [0, 1): each point moves by up to jitter/2 of the pattern spacing per axis
  std::uint64_t seed = 1;  ///< the jitter's seed
};

/// Appends a particle at every pattern point of every cell where region(x) < 0 (the region is a
/// level set: a box, a sphere, any CSG of them). Velocities come from `velocity` (zero when it is
/// empty). Cells are visited in id order, so particle indices are reproducible. Returns how many
/// particles were added. `region` is called from several threads at once.
template <int Dim>
long seed_region(const tree::CellGraph<Dim>& graph, const levelset::Function<Dim>& region,
                 const SeedOptions& options, Particles<Dim>& particles,
                 const VelocitySource<Dim>& velocity = {});

/// The reseeding range of paper Sec. 4.4.
struct ReseedOptions {
  int lo = 0;        ///< a cell with fewer particles is reseeded; 0 means 3 in 2D, 5 in 3D
  int hi = 0;        ///< a cell with more particles is reseeded; 0 means 12 in 2D, 15 in 3D
  int per_cell = 0;  ///< new particles per reseeded cell; 0 means 2^Dim
  double jitter = 0.0;
  std::uint64_t seed = 1;
  bool fill_empty =
      false;  ///< also seed listed cells that hold no particle (holes the caller knows are fluid)
  /// false (the paper): a reseeded cell's particles are all removed and per_cell new ones take their
  /// place. true: a crowded cell keeps per_cell of its own particles (the one nearest each pattern
  /// point) and a sparse one keeps all of its own and gets new ones at the pattern points farthest
  /// from them, up to per_cell; only the new ones take the velocity source's values.
  bool keep = false;
};

struct ReseedReport {
  long cells = 0;    ///< cells reseeded
  long deleted = 0;  ///< particles removed
  long created = 0;  ///< particles added
};

/// Reseeds each cell of `cells` (the caller's fluid cells; the paper leaves surface cells alone)
/// whose particle count is outside [lo, hi]: its particles are removed and per_cell Halton points
/// take their place, with velocities from `velocity` (required); with options.keep, only the
/// surplus is removed, or only the shortfall added. A cell with no particles is not
/// fluid and is left alone, unless options.fill_empty says the caller knows it is. `bins` must be current; it
/// is current again on return (new particles at the end, survivors in their old order). Deterministic.
template <int Dim>
ReseedReport reseed(const tree::CellGraph<Dim>& graph, std::span<const tree::CellId> cells,
                    const ReseedOptions& options, const VelocitySource<Dim>& velocity,
                    Particles<Dim>& particles, CellBins& bins);

}  // namespace liquid::particles
