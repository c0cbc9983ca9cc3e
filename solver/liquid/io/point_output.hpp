#pragma once
// Writing points (particles) so ParaView opens them: STEM.h5 holds the data, STEM.xmf (XDMF 3)
// describes it as one Polyvertex grid with one vertex per point; every field is point-centred.
//
// Datasets in STEM.h5:
//   /geometry     n x Dim doubles   point coordinates, row i is point i
//   /topology     n       int64     0, 1, ..., n-1 (vertex i is point i)
//   /fields/NAME  n doubles (a Scalar field) or n x Dim doubles (a Vector field)
// Zero points give zero-row datasets of the same shapes and an XDMF grid of zero vertices: ParaView's
// XDMF3 readers (Xdmf3ReaderS/T) read it as an empty block; its legacy "XDMF Reader" cannot read an
// empty grid (it reports an error and leaves that block out of the frame). Both files are written
// under temporary names and renamed, so an error never leaves a truncated file behind.

#include <span>
#include <string>

#include "liquid/core/types.hpp"

namespace liquid::io {

/// A point field to write: `components` values per point, point-major (values[i * components + c]).
struct PointField {
  std::string name;                ///< letters, digits, '_', '-' and '.' only; unique among the fields
  int components;                  ///< 1 (written as a Scalar attribute) or Dim (a Vector attribute)
  std::span<const double> values;  ///< exactly n_points * components values
};

/// What write_points() wrote: the two paths, and the XDMF <Grid>...</Grid> element of STEM.xmf (one
/// Uniform grid named "points2d" or "points3d"). The grid's DataItems name the HDF5 file by its
/// file name only, so the text can be embedded in another XDMF file of the same folder (a
/// SeriesWriter frame).
struct PointFiles {
  std::string h5, xmf;
  std::string grid;
};

/// Writes STEM.h5 and STEM.xmf for the points `x` with `fields`. `stem` is a path without
/// extension; its folder must exist. Throws liquid::Error naming the file or the field on any
/// failure (a bad name, a wrong number of components or values, a file that cannot be written).
template <int Dim>
PointFiles write_points(const std::string& stem, std::span<const Vec<Dim>> x,
                        std::span<const PointField> fields = {});

}  // namespace liquid::io
