#pragma once
// Writing the leaves of a CellGraph so ParaView opens the tree: STEM.h5 holds the data, STEM.xmf
// (XDMF 3) describes it. Each leaf is a Quadrilateral (2D) or Hexahedron (3D) with its own corner
// points (no sharing), so hanging nodes need no special care; cell-centred attributes are "level",
// "cell_id" and every named field given.
//
// Datasets in STEM.h5:
//   /geometry   (n_cells * 2^Dim) x Dim doubles   corner coordinates
//   /topology   n_cells x 2^Dim    int64          corner indices, VTK/XDMF corner order
//   /level      n_cells            int32
//   /cell_id    n_cells            int32          the graph's cell id of each row
//   /fields/NAME n_cells           double         one per field
// Rows are the alive cells in ascending id order. Both files are written under temporary names
// and renamed, so an error never leaves a truncated file behind.

#include <span>
#include <string>
#include <vector>

#include "liquid/tree/cell_graph.hpp"

namespace liquid::io {

/// A cell field to write: values indexed by cell id (size >= graph.cell_capacity()).
struct CellField {
  std::string name;  ///< letters, digits, '_', '-' and '.' only
  std::span<const double> values;
};

/// What write_tree() wrote: the two paths, and the XDMF <Grid>...</Grid> element of STEM.xmf (one
/// Uniform grid named "cellgraph2d" or "cellgraph3d"). The grid's DataItems name the HDF5 file by
/// its file name only, so the text can be embedded in another XDMF file of the same folder (a
/// SeriesWriter frame).
struct TreeFiles {
  std::string h5, xmf;
  std::string grid;
};

/// Writes STEM.h5 and STEM.xmf for `graph` with `fields`. `stem` is a path without extension;
/// its folder must exist. Throws liquid::Error naming the file on any failure.
template <int Dim>
TreeFiles write_tree(const std::string& stem, const tree::CellGraph<Dim>& graph,
                     std::span<const CellField> fields = {});

}  // namespace liquid::io
