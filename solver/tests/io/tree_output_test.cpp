// Tree output: the HDF5 file holds what the XDMF file says it holds (every DataItem reference
// names a dataset of exactly the stated dimensions), values round-trip, bad input is refused.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "liquid/core/error.hpp"
#include "liquid/io/tree_output.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

std::vector<hsize_t> dataset_dims(hid_t file, const std::string& path) {
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (set < 0) return {};
  const hid_t space = H5Dget_space(set);
  std::vector<hsize_t> dims(H5Sget_simple_extent_ndims(space));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  H5Sclose(space);
  H5Dclose(set);
  return dims;
}

/// `text` without the spaces that start its lines (the file indents the grid it embeds).
std::string without_indent(const std::string& text) {
  return std::regex_replace(text, std::regex("(^|\n) +"), "$1");
}

template <typename T>
class TreeOutputTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(TreeOutputTest, Dims);

TYPED_TEST(TreeOutputTest, XdmfReferencesMatchTheHdf5Datasets) {
  constexpr int Dim = TypeParam::value;
  const auto dir = std::filesystem::temp_directory_path() / ("liquid_tree_output_" + std::to_string(Dim));
  std::filesystem::create_directories(dir);
  tree::CellGraphOptions<Dim> options;
  options.max_jump = 3;
  auto g = tree::random<Dim>(Box<Dim>{}, 4, 1, Dim == 2 ? 6 : 4, 0.4, options);
  // Remove a few cells so ids have holes and rows differ from ids.
  for (tree::CellId c : g.cell_ids())
    if (g.alive(c) && g.can_merge(c)) {
      g.merge(*g.siblings(c));
      break;
    }
  std::vector<double> x(g.cell_capacity(), -1.0), lvl2(g.cell_capacity(), 0.0);
  g.for_each_cell([&](tree::CellId c) {
    x[c] = g.centre(c)[0];
    lvl2[c] = 2.0 * g.level(c);
  });
  const std::vector<io::CellField> fields{{"x", x}, {"twice_level", lvl2}};
  const io::TreeFiles files = io::write_tree<Dim>((dir / "tree").string(), g, fields);
  ASSERT_TRUE(std::filesystem::exists(files.h5));
  ASSERT_TRUE(std::filesystem::exists(files.xmf));
  EXPECT_FALSE(std::filesystem::exists(files.h5 + ".tmp"));

  std::ifstream in(files.xmf);
  std::stringstream text;
  text << in.rdbuf();
  const std::string xmf = text.str();
  EXPECT_NE(xmf.find(Dim == 2 ? "TopologyType=\"Quadrilateral\"" : "TopologyType=\"Hexahedron\""),
            std::string::npos);
  EXPECT_NE(xmf.find("NumberOfElements=\"" + std::to_string(g.n_cells()) + "\""), std::string::npos);
  // The returned grid is the file's one Grid element, naming the HDF5 file by its name alone.
  EXPECT_EQ(files.grid.rfind("<Grid Name=\"cellgraph" + std::to_string(Dim) + "d\"", 0), 0u) << files.grid;
  EXPECT_EQ(files.grid.substr(files.grid.size() - 7), "</Grid>");
  EXPECT_NE(without_indent(xmf).find(without_indent(files.grid)), std::string::npos);
  EXPECT_EQ(files.grid.find(dir.string()), std::string::npos);

  const hid_t file = H5Fopen(files.h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const std::regex item(R"re(<DataItem Dimensions="([0-9 ]+)"[^>]*>([^:<]+):([^<]+)</DataItem>)re");
  int n_items = 0;
  for (auto it = std::sregex_iterator(xmf.begin(), xmf.end(), item); it != std::sregex_iterator(); ++it) {
    ++n_items;
    const std::smatch& m = *it;
    EXPECT_EQ(m[2].str(), "tree.h5");
    std::vector<hsize_t> stated;
    std::istringstream dims(m[1].str());
    for (hsize_t d; dims >> d;) stated.push_back(d);
    EXPECT_EQ(dataset_dims(file, m[3].str()), stated) << m[3].str();
  }
  EXPECT_EQ(n_items, 6);  // topology, geometry, level, cell_id, two fields

  // Values round-trip in ascending cell-id order.
  const auto ids = g.cell_ids();
  std::vector<double> back(ids.size());
  const hid_t set = H5Dopen2(file, "/fields/x", H5P_DEFAULT);
  ASSERT_GE(set, 0);
  ASSERT_GE(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, back.data()), 0);
  H5Dclose(set);
  for (std::size_t i = 0; i < ids.size(); ++i) EXPECT_EQ(back[i], x[ids[i]]);
  std::vector<double> corners(ids.size() * (1 << Dim) * Dim);
  const hid_t geo = H5Dopen2(file, "/geometry", H5P_DEFAULT);
  ASSERT_GE(H5Dread(geo, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, corners.data()), 0);
  H5Dclose(geo);
  H5Fclose(file);
  const Box<Dim> b = g.box(ids[0]);
  for (int d = 0; d < Dim; ++d) EXPECT_EQ(corners[d], b.lo[d]);  // corner 0 is the lower corner

  // Bad input is refused with a message naming it.
  const std::vector<double> short_field(1, 0.0);
  const std::vector<io::CellField> bad_size{{"short", short_field}};
  EXPECT_THROW(io::write_tree<Dim>((dir / "bad").string(), g, bad_size), Error);
  const std::vector<io::CellField> bad_name{{"a/b", x}};
  EXPECT_THROW(io::write_tree<Dim>((dir / "bad").string(), g, bad_name), Error);
  try {
    io::write_tree<Dim>((dir / "missing_folder" / "tree").string(), g);
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing_folder"), std::string::npos);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace liquid
