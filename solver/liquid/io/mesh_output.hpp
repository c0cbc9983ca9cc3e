#pragma once
// Writing a surface mesh (surface::extract's output, or any segments / triangles) so ParaView opens
// it: STEM.h5 holds the data, STEM.xmf (XDMF 3) describes it as one grid of Polyline elements of 2
// nodes (2D) or Triangle elements (3D).
//
// Datasets in STEM.h5:
//   /geometry     n_vertices x Dim doubles    vertex coordinates
//   /topology     n_elements x Dim int64      vertex indices of each element
// Both files are written under temporary names and renamed, so an error never leaves a truncated
// file behind. The library's modules stay apart: this takes plain arrays, not a surface::Mesh.

#include <array>
#include <span>
#include <string>

#include "liquid/core/types.hpp"

namespace liquid::io {

struct MeshFiles {
  std::string h5, xmf;
  std::string grid;  ///< the XDMF <Grid> element (HDF5 file named by file name only)
};

/// Writes STEM.h5 and STEM.xmf. Throws liquid::Error naming the file or the element whose vertex
/// index is out of range.
template <int Dim>
MeshFiles write_mesh(const std::string& stem, std::span<const Vec<Dim>> vertices,
                     std::span<const std::array<int, Dim>> elements);

}  // namespace liquid::io
