#pragma once
// What a particle -> face transfer produces, and what every transfer reports.

#include <cstdint>
#include <string>
#include <vector>

namespace liquid::transfer {

/// One normal velocity component per face id (dead ids unused). A face that no particle reaches is
/// unknown: value 0, known 0, to be filled by extrapolate_faces() or the caller. Never NaN.
struct FaceValues {
  std::vector<double> value;
  std::vector<std::uint8_t> known;
  std::vector<double> weight;  ///< the transfer's mass at the face (sum of particle weights; linear/APIC)

  void reset(int face_capacity) {
    value.assign(face_capacity, 0.0);
    known.assign(face_capacity, 0);
    weight.assign(face_capacity, 0.0);
  }
};

/// Counts of what a transfer did, summed over every target (face or particle component).
struct TransferReport {
  long targets = 0;         ///< values computed
  long empty = 0;           ///< targets with no source in reach (unknown faces; particles left at 0)
  long clamped = 0;         ///< values clamped to the range of their sources
  long degree_reduced = 0;  ///< stencils whose polynomial degree was lowered (too few or degenerate nodes)
  long fallback =
      0;  ///< stencils that could not be factorised (coincident nodes): inverse-distance mean used
  int max_degree_used = -1;

  TransferReport& operator+=(const TransferReport& o);
  /// One line: "targets 1200, empty 3, clamped 41 (3.4%), degree lowered 0, fallback 0".
  std::string describe() const;
};

/// A face's value from a positive-weight transfer: the weighted mean sum / mass of its particles'
/// values, or unknown (value 0, weight 0) when no particle reaches it; counted in r.
inline void store_mean(FaceValues& out, int f, double sum, double mass, TransferReport& r) {
  ++r.targets;
  if (mass > 0.0) {
    out.value[f] = sum / mass;
    out.known[f] = 1;
    out.weight[f] = mass;
  } else {
    out.value[f] = 0.0, out.known[f] = 0, out.weight[f] = 0.0;
    ++r.empty;
  }
}

}  // namespace liquid::transfer
