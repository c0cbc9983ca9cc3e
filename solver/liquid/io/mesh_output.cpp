#include "liquid/io/mesh_output.hpp"

#include <fmt/format.h>
#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <vector>

#include "liquid/core/error.hpp"
#include "liquid/io/hdf5_detail.hpp"

namespace liquid::io {

namespace {
constexpr const char* who = "write_mesh";
}  // namespace

template <int Dim>
MeshFiles write_mesh(const std::string& stem, std::span<const Vec<Dim>> vertices,
                     std::span<const std::array<int, Dim>> elements) {
  static_assert(sizeof(Vec<Dim>) == Dim * sizeof(double));
  const auto nv = static_cast<hsize_t>(vertices.size()), ne = static_cast<hsize_t>(elements.size());
  std::vector<std::int64_t> topology;
  topology.reserve(ne * Dim);
  for (hsize_t e = 0; e < ne; ++e)
    for (int k = 0; k < Dim; ++k) {
      const int v = elements[e][k];
      LIQUID_VERIFY(v >= 0 && static_cast<hsize_t>(v) < nv,
                    "write_mesh: element {} names vertex {}, but the mesh has {} vertices", e, v, nv);
      topology.push_back(v);
    }
  MeshFiles files{stem + ".h5", stem + ".xmf", ""};
  const std::string h5_tmp = files.h5 + ".tmp", xmf_tmp = files.xmf + ".tmp";
  detail::TemporaryFiles temporaries({h5_tmp, xmf_tmp});
  {
    detail::QuietHdf5 quiet;
    detail::MemoryFile file(h5_tmp, who);
    detail::write_dataset(file.get(), "geometry", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {nv, Dim},
                          vertices.empty() ? nullptr : vertices.data()->data(), h5_tmp, who);
    detail::write_dataset(file.get(), "topology", H5T_NATIVE_INT64, H5T_STD_I64LE, {ne, Dim},
                          topology.empty() ? nullptr : topology.data(), h5_tmp, who);
    file.save(h5_tmp, who);
  }
  const std::string h5_name = std::filesystem::path(files.h5).filename().string();
  std::string& grid = files.grid;
  grid += fmt::format("<Grid Name=\"surface{}d\" GridType=\"Uniform\">\n", Dim);
  grid += fmt::format(
      "  <Topology TopologyType=\"{}\" NumberOfElements=\"{}\" NodesPerElement=\"{}\">\n    {}\n  "
      "</Topology>\n",
      Dim == 2 ? "Polyline" : "Triangle", ne, Dim,
      detail::data_item(fmt::format("{} {}", ne, Dim), "Int", 8, h5_name + ":/topology"));
  grid += fmt::format("  <Geometry GeometryType=\"{}\">\n    {}\n  </Geometry>\n", Dim == 2 ? "XY" : "XYZ",
                      detail::data_item(fmt::format("{} {}", nv, Dim), "Float", 8, h5_name + ":/geometry"));
  grid += "</Grid>";
  write_file(xmf_tmp, detail::xdmf_document(grid), who);
  detail::rename_file(h5_tmp, files.h5, who);
  detail::rename_file(xmf_tmp, files.xmf, who);
  temporaries.release();
  return files;
}

template MeshFiles write_mesh<2>(const std::string&, std::span<const Vec<2>>,
                                 std::span<const std::array<int, 2>>);
template MeshFiles write_mesh<3>(const std::string&, std::span<const Vec<3>>,
                                 std::span<const std::array<int, 3>>);

}  // namespace liquid::io
