#include "liquid/io/tree_output.hpp"

#include <fmt/format.h>
#include <hdf5.h>

#include <filesystem>
#include <utility>

#include "liquid/core/error.hpp"
#include "liquid/io/hdf5_detail.hpp"

namespace liquid::io {

namespace {

using detail::Handle;
using detail::QuietHdf5;

constexpr const char* who = "write_tree";

void write_dataset(hid_t where, const std::string& name, hid_t mem_type, hid_t file_type,
                   std::vector<hsize_t> dims, const void* data, const std::string& path) {
  detail::write_dataset(where, name, mem_type, file_type, std::move(dims), data, path, who);
}

bool valid_name(const std::string& name) {
  return detail::valid_field_name(name) && name != "level" && name != "cell_id";
}

/// Corner k of a cell in XDMF/VTK order, as offsets (0 or 1) per axis.
template <int Dim>
int corner_bit(int k, int d) {
  static constexpr int quad[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  if (d < 2) return quad[k % 4][d];
  return k / 4;
}

}  // namespace

template <int Dim>
TreeFiles write_tree(const std::string& stem, const tree::CellGraph<Dim>& graph,
                     std::span<const CellField> fields) {
  constexpr int n_corners = 1 << Dim;
  for (const CellField& f : fields) {
    LIQUID_VERIFY(
        valid_name(f.name),
        "write_tree: field name '{}' must be non-empty, not 'level' or 'cell_id', and use only letters, "
        "digits, '_', '-', '.'",
        f.name);
    LIQUID_VERIFY(f.values.size() >= static_cast<std::size_t>(graph.cell_capacity()),
                  "write_tree: field '{}' has {} values but the graph's cell ids go up to {}", f.name,
                  f.values.size(), graph.cell_capacity() - 1);
  }
  TreeFiles files{stem + ".h5", stem + ".xmf", ""};
  const std::vector<tree::CellId> ids = graph.cell_ids();
  const auto n = static_cast<hsize_t>(ids.size());

  std::vector<double> geometry(n * n_corners * Dim);
  std::vector<std::int64_t> topology(n * n_corners);
  std::vector<std::int32_t> level(n), cell_id(n);
#pragma omp parallel for schedule(static) if (static_cast <long>(n) > tree::detail::parallel_min)
  for (long i = 0; i < static_cast<long>(n); ++i) {
    const Box<Dim> b = graph.box(ids[i]);
    for (int k = 0; k < n_corners; ++k) {
      const std::size_t p = static_cast<std::size_t>(i) * n_corners + k;
      topology[p] = static_cast<std::int64_t>(p);
      for (int d = 0; d < Dim; ++d) geometry[p * Dim + d] = corner_bit<Dim>(k, d) ? b.hi[d] : b.lo[d];
    }
    level[i] = graph.level(ids[i]);
    cell_id[i] = ids[i];
  }

  const std::string h5_tmp = files.h5 + ".tmp", xmf_tmp = files.xmf + ".tmp";
  detail::TemporaryFiles temporaries({h5_tmp, xmf_tmp});
  {
    QuietHdf5 quiet;
    detail::MemoryFile file(h5_tmp, who);
    write_dataset(file.get(), "geometry", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n * n_corners, Dim},
                  geometry.data(), h5_tmp);
    write_dataset(file.get(), "topology", H5T_NATIVE_INT64, H5T_STD_I64LE, {n, n_corners}, topology.data(),
                  h5_tmp);
    write_dataset(file.get(), "level", H5T_NATIVE_INT32, H5T_STD_I32LE, {n}, level.data(), h5_tmp);
    write_dataset(file.get(), "cell_id", H5T_NATIVE_INT32, H5T_STD_I32LE, {n}, cell_id.data(), h5_tmp);
    if (!fields.empty()) {
      Handle group(H5Gcreate2(file.get(), "fields", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
      LIQUID_VERIFY(group.ok(), "write_tree: cannot create group /fields in {}", h5_tmp);
      std::vector<double> values(n);
      for (const CellField& f : fields) {
        for (hsize_t i = 0; i < n; ++i) values[i] = f.values[ids[i]];
        write_dataset(group.get(), f.name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n}, values.data(), h5_tmp);
      }
    }
    file.save(h5_tmp, who);
  }

  const std::string h5_name = std::filesystem::path(files.h5).filename().string();
  const std::string cells = std::to_string(n);
  std::string& grid = files.grid;
  grid += fmt::format("<Grid Name=\"cellgraph{}d\" GridType=\"Uniform\">\n", Dim);
  grid += fmt::format(
      "  <Topology TopologyType=\"{}\" NumberOfElements=\"{}\">\n    {}\n  </Topology>\n",
      Dim == 2 ? "Quadrilateral" : "Hexahedron", cells,
      detail::data_item(fmt::format("{} {}", cells, n_corners), "Int", 8, h5_name + ":/topology"));
  grid += fmt::format(
      "  <Geometry GeometryType=\"{}\">\n    {}\n  </Geometry>\n", Dim == 2 ? "XY" : "XYZ",
      detail::data_item(fmt::format("{} {}", n * n_corners, Dim), "Float", 8, h5_name + ":/geometry"));
  const auto attribute = [&](const std::string& name, const char* type, int precision,
                             const std::string& path) {
    grid += fmt::format(
        "  <Attribute Name=\"{}\" AttributeType=\"Scalar\" Center=\"Cell\">\n    {}\n  </Attribute>\n", name,
        detail::data_item(cells, type, precision, h5_name + ":" + path));
  };
  attribute("level", "Int", 4, "/level");
  attribute("cell_id", "Int", 4, "/cell_id");
  for (const CellField& f : fields) attribute(f.name, "Float", 8, "/fields/" + f.name);
  grid += "</Grid>";
  write_file(xmf_tmp, detail::xdmf_document(grid), who);
  detail::rename_file(h5_tmp, files.h5, who);
  detail::rename_file(xmf_tmp, files.xmf, who);
  temporaries.release();
  return files;
}

template TreeFiles write_tree<2>(const std::string&, const tree::CellGraph<2>&, std::span<const CellField>);
template TreeFiles write_tree<3>(const std::string&, const tree::CellGraph<3>&, std::span<const CellField>);

}  // namespace liquid::io
