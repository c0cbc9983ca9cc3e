// Mesh output: segments (2D) and triangles (3D) round-trip through HDF5, the XDMF file names the
// element type and the datasets' shapes, and an element naming a missing vertex is refused.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "liquid/core/error.hpp"
#include "liquid/io/mesh_output.hpp"

namespace liquid {
namespace {

std::string folder() {
  const auto dir = std::filesystem::temp_directory_path() / "liquid_mesh_output_test";
  std::filesystem::create_directories(dir);
  return dir.string();
}

TEST(MeshOutput, TrianglesRoundTripAndTheXdmfNamesThem) {
  const std::vector<Vec<3>> v{Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), Vec<3>(0, 1, 0), Vec<3>(0, 0, 1)};
  const std::vector<std::array<int, 3>> t{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const io::MeshFiles files = io::write_mesh<3>(folder() + "/tetra", v, t);
  const hid_t file = H5Fopen(files.h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  std::vector<std::int64_t> topology(12);
  std::vector<double> geometry(12);
  const hid_t top = H5Dopen2(file, "topology", H5P_DEFAULT), geo = H5Dopen2(file, "geometry", H5P_DEFAULT);
  ASSERT_GE(H5Dread(top, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, topology.data()), 0);
  ASSERT_GE(H5Dread(geo, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, geometry.data()), 0);
  H5Dclose(top), H5Dclose(geo), H5Fclose(file);
  for (int e = 0; e < 4; ++e)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(topology[3 * e + k], t[e][k]);
  for (int i = 0; i < 4; ++i)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(geometry[3 * i + d], v[i][d]);
  std::ifstream in(files.xmf);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("TopologyType=\"Triangle\" NumberOfElements=\"4\" NodesPerElement=\"3\""),
            std::string::npos);
  EXPECT_NE(text.str().find("Dimensions=\"4 3\""), std::string::npos);
  EXPECT_NE(text.str().find("tetra.h5:/topology"), std::string::npos);
}

TEST(MeshOutput, SegmentsAreAPolylineAndABadIndexIsRefused) {
  const std::vector<Vec<2>> v{Vec<2>(0, 0), Vec<2>(1, 0), Vec<2>(1, 1)};
  const std::vector<std::array<int, 2>> s{{0, 1}, {1, 2}, {2, 0}};
  const io::MeshFiles files = io::write_mesh<2>(folder() + "/triangle", v, s);
  std::ifstream in(files.xmf);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("TopologyType=\"Polyline\" NumberOfElements=\"3\" NodesPerElement=\"2\""),
            std::string::npos);
  const std::vector<std::array<int, 2>> bad{{0, 3}};
  try {
    io::write_mesh<2>(folder() + "/bad", v, bad);
    FAIL() << "an element naming vertex 3 of 3 was written";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("element 0 names vertex 3"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(folder() + "/bad.h5"));
}

}  // namespace
}  // namespace liquid
