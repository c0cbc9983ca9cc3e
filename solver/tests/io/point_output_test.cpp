// Point output: the HDF5 file holds what the XDMF file says it holds (one Polyvertex vertex per
// point, Scalar and Vector point fields), values round-trip, zero points give valid empty files,
// the returned grid is the file's Grid element, bad input is refused naming the field.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "liquid/core/error.hpp"
#include "liquid/io/point_output.hpp"

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

template <typename T>
std::vector<T> read_all(hid_t file, const std::string& path, hid_t mem_type, std::size_t n) {
  std::vector<T> values(n);
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(set, 0) << path;
  if (n > 0) {
    EXPECT_GE(H5Dread(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0) << path;
  }
  H5Dclose(set);
  return values;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// `text` without the spaces that start its lines (the file indents the grid it embeds).
std::string without_indent(const std::string& text) {
  return std::regex_replace(text, std::regex("(^|\n) +"), "$1");
}

/// Checks every HDF DataItem of `xmf` against the dataset it names; returns how many there are.
int check_data_items(const std::string& xmf, hid_t file, const std::string& h5_name) {
  const std::regex item(R"re(<DataItem Dimensions="([0-9 ]+)"[^>]*>([^:<]+):([^<]+)</DataItem>)re");
  int n_items = 0;
  for (auto it = std::sregex_iterator(xmf.begin(), xmf.end(), item); it != std::sregex_iterator(); ++it) {
    ++n_items;
    const std::smatch& m = *it;
    EXPECT_EQ(m[2].str(), h5_name);
    std::vector<hsize_t> stated;
    std::istringstream dims(m[1].str());
    for (hsize_t d; dims >> d;) stated.push_back(d);
    EXPECT_EQ(dataset_dims(file, m[3].str()), stated) << m[3].str();
  }
  return n_items;
}

template <typename T>
class PointOutputTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(PointOutputTest, Dims);

TYPED_TEST(PointOutputTest, XdmfReferencesMatchTheHdf5DatasetsAndValuesRoundTrip) {
  constexpr int Dim = TypeParam::value;
  const auto dir = std::filesystem::temp_directory_path() / ("liquid_point_output_" + std::to_string(Dim));
  std::filesystem::create_directories(dir);
  const int n = 7;
  std::vector<Vec<Dim>> x(n);
  std::vector<double> speed(n), velocity(n * Dim);
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < Dim; ++d) {
      x[i][d] = 0.125 * i + 1.0 / (d + 3);
      velocity[i * Dim + d] = i - 0.5 * d;
    }
    speed[i] = x[i].norm();
  }
  const std::vector<io::PointField> fields{{"speed", 1, speed}, {"velocity", Dim, velocity}};
  const io::PointFiles files = io::write_points<Dim>((dir / "particles").string(), x, fields);
  ASSERT_TRUE(std::filesystem::exists(files.h5));
  ASSERT_TRUE(std::filesystem::exists(files.xmf));
  EXPECT_FALSE(std::filesystem::exists(files.h5 + ".tmp"));
  EXPECT_FALSE(std::filesystem::exists(files.xmf + ".tmp"));

  const std::string xmf = read_text(files.xmf);
  EXPECT_NE(xmf.find(R"(TopologyType="Polyvertex" NumberOfElements="7" NodesPerElement="1")"),
            std::string::npos);
  EXPECT_NE(xmf.find(Dim == 2 ? R"(GeometryType="XY")" : R"(GeometryType="XYZ")"), std::string::npos);
  EXPECT_NE(xmf.find(R"(<Attribute Name="speed" AttributeType="Scalar" Center="Node">)"), std::string::npos);
  EXPECT_NE(xmf.find(R"(<Attribute Name="velocity" AttributeType="Vector" Center="Node">)"),
            std::string::npos);
  // The returned grid is the file's one Grid element, naming the HDF5 file by its name alone.
  EXPECT_EQ(files.grid.rfind("<Grid Name=\"points" + std::to_string(Dim) + "d\"", 0), 0u) << files.grid;
  EXPECT_EQ(files.grid.substr(files.grid.size() - 7), "</Grid>");
  EXPECT_NE(without_indent(xmf).find(without_indent(files.grid)), std::string::npos);
  EXPECT_EQ(files.grid.find(dir.string()), std::string::npos);

  const hid_t file = H5Fopen(files.h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  EXPECT_EQ(check_data_items(xmf, file, "particles.h5"), 4);  // topology, geometry, two fields
  EXPECT_EQ(check_data_items(files.grid, file, "particles.h5"), 4);
  EXPECT_EQ(dataset_dims(file, "/geometry"), (std::vector<hsize_t>{n, Dim}));
  EXPECT_EQ(dataset_dims(file, "/fields/velocity"), (std::vector<hsize_t>{n, Dim}));
  EXPECT_EQ(dataset_dims(file, "/fields/speed"), (std::vector<hsize_t>{n}));
  const auto geometry = read_all<double>(file, "/geometry", H5T_NATIVE_DOUBLE, n * Dim);
  const auto topology = read_all<std::int64_t>(file, "/topology", H5T_NATIVE_INT64, n);
  const auto speed_back = read_all<double>(file, "/fields/speed", H5T_NATIVE_DOUBLE, n);
  const auto velocity_back = read_all<double>(file, "/fields/velocity", H5T_NATIVE_DOUBLE, n * Dim);
  H5Fclose(file);
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(topology[i], i);
    EXPECT_EQ(speed_back[i], speed[i]);
    for (int d = 0; d < Dim; ++d) {
      EXPECT_EQ(geometry[i * Dim + d], x[i][d]);
      EXPECT_EQ(velocity_back[i * Dim + d], velocity[i * Dim + d]);
    }
  }
  std::filesystem::remove_all(dir);
}

TYPED_TEST(PointOutputTest, ZeroPointsGiveValidEmptyFiles) {
  constexpr int Dim = TypeParam::value;
  const auto dir =
      std::filesystem::temp_directory_path() / ("liquid_point_output_empty_" + std::to_string(Dim));
  std::filesystem::create_directories(dir);
  const std::vector<io::PointField> fields{{"speed", 1, {}}, {"velocity", Dim, {}}};
  const io::PointFiles files =
      io::write_points<Dim>((dir / "none").string(), std::span<const Vec<Dim>>{}, fields);
  const std::string xmf = read_text(files.xmf);
  EXPECT_NE(xmf.find(R"(NumberOfElements="0")"), std::string::npos);
  const hid_t file = H5Fopen(files.h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  EXPECT_EQ(check_data_items(xmf, file, "none.h5"), 4);
  EXPECT_EQ(dataset_dims(file, "/geometry"), (std::vector<hsize_t>{0, Dim}));
  EXPECT_EQ(dataset_dims(file, "/topology"), (std::vector<hsize_t>{0}));
  EXPECT_EQ(dataset_dims(file, "/fields/speed"), (std::vector<hsize_t>{0}));
  EXPECT_EQ(dataset_dims(file, "/fields/velocity"), (std::vector<hsize_t>{0, Dim}));
  H5Fclose(file);
  // No fields at all is fine too.
  EXPECT_NO_THROW(io::write_points<Dim>((dir / "bare").string(), std::span<const Vec<Dim>>{}));
  std::filesystem::remove_all(dir);
}

TYPED_TEST(PointOutputTest, RefusesBadFieldsNamingThem) {
  constexpr int Dim = TypeParam::value;
  const auto dir =
      std::filesystem::temp_directory_path() / ("liquid_point_output_bad_" + std::to_string(Dim));
  std::filesystem::create_directories(dir);
  const std::vector<Vec<Dim>> x(3, Vec<Dim>::Zero());
  const std::vector<double> three(3, 1.0), ten(10, 1.0), vector(3 * Dim, 1.0);
  const auto refused = [&](std::vector<io::PointField> fields, const std::string& expected) {
    try {
      io::write_points<Dim>((dir / "bad").string(), x, fields);
      ADD_FAILURE() << "no throw for " << expected;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused({{"a/b", 1, three}}, "'a/b'");
  refused({{"", 1, three}}, "''");
  refused({{"twice", 1, three}, {"twice", 1, three}}, "two fields are named 'twice'");
  refused({{"too_many", Dim + 1, std::vector<double>(3 * (Dim + 1), 0.0)}},
          "'too_many' has " + std::to_string(Dim + 1) + " components");
  refused({{"none", 0, {}}}, "'none' has 0 components");
  refused({{"short", 1, std::span<const double>(three).first(2)}}, "'short' has 2 values for 3 points");
  refused({{"long", Dim, ten}}, "'long' has 10 values");
  refused({{"scalar_as_vector", 1, vector}}, "'scalar_as_vector'");
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.h5"));
  try {
    io::write_points<Dim>((dir / "missing_folder" / "points").string(), x);
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing_folder"), std::string::npos);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace liquid
