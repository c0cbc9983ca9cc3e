#include "liquid/io/point_output.hpp"

#include <fmt/format.h>
#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <numeric>
#include <set>
#include <vector>

#include "liquid/core/error.hpp"
#include "liquid/io/hdf5_detail.hpp"

namespace liquid::io {

namespace {
constexpr const char* who = "write_points";
}  // namespace

template <int Dim>
PointFiles write_points(const std::string& stem, std::span<const Vec<Dim>> x,
                        std::span<const PointField> fields) {
  // The coordinates are written straight from the span: each Vec<Dim> is Dim packed doubles.
  static_assert(sizeof(Vec<Dim>) == Dim * sizeof(double));
  const auto n = static_cast<hsize_t>(x.size());
  std::set<std::string> names;
  for (const PointField& f : fields) {
    LIQUID_VERIFY(
        detail::valid_field_name(f.name),
        "write_points: field name '{}' must be non-empty and use only letters, digits, '_', '-', '.'",
        f.name);
    LIQUID_VERIFY(names.insert(f.name).second, "write_points: two fields are named '{}'", f.name);
    LIQUID_VERIFY(
        f.components == 1 || f.components == Dim,
        "write_points: field '{}' has {} components; a {}D point field has 1 (scalar) or {} (vector)", f.name,
        f.components, Dim, Dim);
    LIQUID_VERIFY(f.values.size() == n * static_cast<hsize_t>(f.components),
                  "write_points: field '{}' has {} values for {} points of {} component(s) (expected {})",
                  f.name, f.values.size(), n, f.components, n * static_cast<hsize_t>(f.components));
  }
  PointFiles files{stem + ".h5", stem + ".xmf", ""};
  std::vector<std::int64_t> topology(n);
  std::iota(topology.begin(), topology.end(), std::int64_t{0});

  const std::string h5_tmp = files.h5 + ".tmp", xmf_tmp = files.xmf + ".tmp";
  detail::TemporaryFiles temporaries({h5_tmp, xmf_tmp});
  {
    detail::QuietHdf5 quiet;
    detail::MemoryFile file(h5_tmp, who);
    detail::write_dataset(file.get(), "geometry", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n, Dim},
                          x.empty() ? nullptr : x.data()->data(), h5_tmp, who);
    detail::write_dataset(file.get(), "topology", H5T_NATIVE_INT64, H5T_STD_I64LE, {n}, topology.data(),
                          h5_tmp, who);
    if (!fields.empty()) {
      detail::Handle group(H5Gcreate2(file.get(), "fields", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
      LIQUID_VERIFY(group.ok(), "write_points: cannot create group /fields in {}", h5_tmp);
      for (const PointField& f : fields) {
        std::vector<hsize_t> dims{n};
        if (f.components > 1) dims.push_back(static_cast<hsize_t>(f.components));
        detail::write_dataset(group.get(), f.name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, dims, f.values.data(),
                              h5_tmp, who);
      }
    }
    file.save(h5_tmp, who);
  }

  const std::string h5_name = std::filesystem::path(files.h5).filename().string();
  const std::string points = std::to_string(n);
  std::string& grid = files.grid;
  grid += fmt::format("<Grid Name=\"points{}d\" GridType=\"Uniform\">\n", Dim);
  grid += fmt::format(
      "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{}\" NodesPerElement=\"1\">\n    {}\n  "
      "</Topology>\n",
      points, detail::data_item(points, "Int", 8, h5_name + ":/topology"));
  grid +=
      fmt::format("  <Geometry GeometryType=\"{}\">\n    {}\n  </Geometry>\n", Dim == 2 ? "XY" : "XYZ",
                  detail::data_item(fmt::format("{} {}", points, Dim), "Float", 8, h5_name + ":/geometry"));
  for (const PointField& f : fields) {
    const bool vector = f.components > 1;
    grid += fmt::format(
        "  <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"Node\">\n    {}\n  </Attribute>\n", f.name,
        vector ? "Vector" : "Scalar",
        detail::data_item(vector ? fmt::format("{} {}", points, Dim) : points, "Float", 8,
                          h5_name + ":/fields/" + f.name));
  }
  grid += "</Grid>";
  write_file(xmf_tmp, detail::xdmf_document(grid), who);
  detail::rename_file(h5_tmp, files.h5, who);
  detail::rename_file(xmf_tmp, files.xmf, who);
  temporaries.release();
  return files;
}

template PointFiles write_points<2>(const std::string&, std::span<const Vec<2>>, std::span<const PointField>);
template PointFiles write_points<3>(const std::string&, std::span<const Vec<3>>, std::span<const PointField>);

}  // namespace liquid::io
