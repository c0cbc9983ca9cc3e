// Checkpoint archive: every type round-trips exactly (doubles bit for bit: -0.0, denormals,
// infinities, extremes), empty arrays and groups work, a missing name or a wrong type is an error
// naming the file, the name and both types, and an uncommitted writer leaves no file.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include "liquid/core/error.hpp"
#include "liquid/io/archive.hpp"

namespace liquid {
namespace {

class ArchiveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("liquid_archive_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::filesystem::path dir_;
};

/// Expects `call` to throw liquid::Error whose message holds every one of `parts`.
template <typename Call>
void expect_error(Call&& call, std::initializer_list<std::string> parts) {
  try {
    call();
    ADD_FAILURE() << "no throw";
  } catch (const Error& e) {
    for (const std::string& p : parts)
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

std::vector<std::uint64_t> bits(const std::vector<double>& values) {
  std::vector<std::uint64_t> out;
  for (double v : values) out.push_back(std::bit_cast<std::uint64_t>(v));
  return out;
}

TEST_F(ArchiveTest, EveryTypeRoundTripsExactly) {
  using limits = std::numeric_limits<double>;
  const std::vector<double> doubles{0.0,
                                    -0.0,
                                    1.0 / 3.0,
                                    -2.5e-300,
                                    limits::denorm_min(),
                                    -limits::denorm_min() * 12345,
                                    limits::min(),
                                    limits::max(),
                                    limits::lowest(),
                                    limits::epsilon(),
                                    limits::infinity(),
                                    -limits::infinity()};
  const std::vector<std::int32_t> int32s{0, -1, 7, std::numeric_limits<std::int32_t>::min(),
                                         std::numeric_limits<std::int32_t>::max()};
  const std::vector<std::int64_t> int64s{0, -1, (std::int64_t{1} << 53) | 1,
                                         std::numeric_limits<std::int64_t>::min(),
                                         std::numeric_limits<std::int64_t>::max()};
  const std::vector<std::uint8_t> uint8s{0, 1, 127, 128, 255};
  const std::vector<std::uint32_t> uint32s{0, 1, std::numeric_limits<std::uint32_t>::max()};
  const std::vector<std::uint64_t> uint64s{0, 1, (std::uint64_t{1} << 63) + 5,
                                           std::numeric_limits<std::uint64_t>::max()};
  const std::string text = "line one\nline two, \"quoted\" & <tagged>";
  const std::string with_nuls("a\0b\0\0", 5);
  {
    io::ArchiveWriter out(path("all.h5"));
    out.put("doubles", doubles);
    out.put("int32s", int32s);
    out.put("int64s", int64s);
    out.put("uint8s", uint8s);
    out.put("uint32s", uint32s);
    out.put("uint64s", uint64s);
    out.put_scalar("time", 0.1);
    out.put_scalar("negative_zero", -0.0);
    out.put_scalar("denormal", limits::denorm_min());
    out.put_scalar("step", std::int64_t{-9007199254740993});
    out.put_string("text", text);
    out.put_string("with_nuls", with_nuls);
    out.put_string("empty_string", "");
    out.put("nan", std::vector<double>{limits::quiet_NaN(), -limits::quiet_NaN()});
    EXPECT_FALSE(std::filesystem::exists(path("all.h5")));  // only commit() makes the file
    out.commit();
  }
  EXPECT_FALSE(std::filesystem::exists(path("all.h5.tmp")));
  const io::ArchiveReader in(path("all.h5"));
  EXPECT_EQ(bits(in.doubles("doubles")), bits(doubles));
  EXPECT_EQ(in.int32s("int32s"), int32s);
  EXPECT_EQ(in.int64s("int64s"), int64s);
  EXPECT_EQ(in.uint8s("uint8s"), uint8s);
  EXPECT_EQ(in.uint32s("uint32s"), uint32s);
  EXPECT_EQ(in.uint64s("uint64s"), uint64s);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(in.scalar_double("time")), std::bit_cast<std::uint64_t>(0.1));
  EXPECT_TRUE(std::signbit(in.scalar_double("negative_zero")));
  EXPECT_EQ(in.scalar_double("negative_zero"), 0.0);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(in.scalar_double("denormal")),
            std::bit_cast<std::uint64_t>(limits::denorm_min()));
  EXPECT_EQ(in.scalar_int("step"), -9007199254740993);
  EXPECT_EQ(in.string("text"), text);
  EXPECT_EQ(in.string("with_nuls"), with_nuls);
  EXPECT_EQ(in.string("empty_string"), "");
  const std::vector<double> nan = in.doubles("nan");
  ASSERT_EQ(nan.size(), 2u);
  EXPECT_TRUE(std::isnan(nan[0]) && std::isnan(nan[1]));
}

TEST_F(ArchiveTest, EmptyArraysAndGroups) {
  {
    io::ArchiveWriter out(path("groups.h5"));
    out.put("empty/doubles", std::vector<double>{});
    out.put("empty/int32s", std::vector<std::int32_t>{});
    out.put("empty/int64s", std::vector<std::int64_t>{});
    out.put("empty/uint8s", std::vector<std::uint8_t>{});
    out.put("empty/uint32s", std::vector<std::uint32_t>{});
    out.put("empty/uint64s", std::vector<std::uint64_t>{});
    out.put("particles/x", std::vector<double>{1.0, 2.0});
    out.put("particles/cell", std::vector<std::int32_t>{4, 5});
    out.put_scalar("solver/pressure/iterations", std::int64_t{12});
    out.put_string("series/frame.0/grid-1", "<Grid/>");
    out.commit();
  }
  const io::ArchiveReader in(path("groups.h5"));
  EXPECT_TRUE(in.doubles("empty/doubles").empty());
  EXPECT_TRUE(in.int32s("empty/int32s").empty());
  EXPECT_TRUE(in.int64s("empty/int64s").empty());
  EXPECT_TRUE(in.uint8s("empty/uint8s").empty());
  EXPECT_TRUE(in.uint32s("empty/uint32s").empty());
  EXPECT_TRUE(in.uint64s("empty/uint64s").empty());
  EXPECT_EQ(in.doubles("particles/x"), (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(in.int32s("particles/cell"), (std::vector<std::int32_t>{4, 5}));
  EXPECT_EQ(in.scalar_int("solver/pressure/iterations"), 12);
  EXPECT_EQ(in.string("series/frame.0/grid-1"), "<Grid/>");
  EXPECT_TRUE(in.has("particles"));
  EXPECT_TRUE(in.has("particles/x"));
  EXPECT_TRUE(in.has("solver/pressure"));
  EXPECT_FALSE(in.has("particles/y"));
  EXPECT_FALSE(in.has("particles/x/deeper"));
  EXPECT_FALSE(in.has("nothing/here"));
  EXPECT_FALSE(in.has(""));
  EXPECT_FALSE(in.has("/particles"));

  // The file is plain HDF5: groups and datasets of the stated types.
  const hid_t file = H5Fopen(path("groups.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hid_t set = H5Dopen2(file, "/particles/cell", H5P_DEFAULT);
  ASSERT_GE(set, 0);
  const hid_t type = H5Dget_type(set);
  EXPECT_GT(H5Tequal(type, H5T_STD_I32LE), 0);
  H5Tclose(type);
  H5Dclose(set);
  H5Fclose(file);
}

TEST_F(ArchiveTest, MissingNamesAndWrongTypesAreErrorsNamingFileAndDataset) {
  {
    io::ArchiveWriter out(path("typed.h5"));
    out.put("particles/x", std::vector<double>{1.0});
    out.put("particles/cell", std::vector<std::int32_t>{1});
    out.put_scalar("time", 1.0);
    out.put_scalar("step", std::int64_t{3});
    out.put_string("name", "pool");
    out.commit();
  }
  const io::ArchiveReader in(path("typed.h5"));
  const std::string file = path("typed.h5");
  expect_error([&] { in.doubles("particles/y"); }, {file, "'particles/y'", "a 1-D array of double"});
  expect_error([&] { in.doubles("nothing/particles/y"); }, {file, "'nothing/particles/y'"});
  expect_error([&] { in.int64s("particles/cell"); },
               {file, "'particles/cell'", "holds a 1-D array of int32, expected a 1-D array of int64"});
  expect_error([&] { in.uint32s("particles/cell"); },
               {"holds a 1-D array of int32, expected a 1-D array of uint32"});
  expect_error([&] { in.int32s("particles/x"); },
               {"holds a 1-D array of double, expected a 1-D array of int32"});
  expect_error([&] { in.doubles("time"); },
               {"'time'", "holds a scalar double, expected a 1-D array of double"});
  expect_error([&] { in.scalar_double("step"); }, {"holds a scalar int64, expected a scalar double"});
  expect_error([&] { in.scalar_int("time"); }, {"holds a scalar double, expected a scalar int64"});
  expect_error([&] { in.scalar_double("particles/x"); },
               {"holds a 1-D array of double, expected a scalar double"});
  expect_error([&] { in.string("step"); }, {"holds a scalar int64, expected a string"});
  expect_error([&] { in.uint8s("name"); }, {"'name'", "holds a string, expected a 1-D array of uint8"});
  expect_error([&] { in.doubles("particles"); },
               {"'particles'", "is a group, expected a 1-D array of double"});
  expect_error([] { io::ArchiveReader missing("/nonexistent/folder/checkpoint.h5"); },
               {"/nonexistent/folder/checkpoint.h5", "does not exist"});
}

TEST_F(ArchiveTest, WriterRefusesBadUse) {
  io::ArchiveWriter out(path("bad.h5"));
  out.put("a/x", std::vector<double>{1.0});
  expect_error([&] { out.put("a/x", std::vector<double>{2.0}); }, {"already holds 'a/x'"});
  expect_error([&] { out.put_scalar("a", 1.0); }, {"already holds 'a'"});
  expect_error([&] { out.put("a/x/y", std::vector<double>{2.0}); }, {"'a/x/y'"});
  for (const std::string name : {"", "/a", "a/", "a//b", "a/../b", ".", "a b", "a\\b"})
    expect_error([&] { out.put_scalar(name, 1.0); }, {"bad name '" + name + "'"});
  out.commit();
  expect_error([&] { out.put_scalar("late", 1.0); }, {path("bad.h5"), "closed"});
  expect_error([&] { out.commit(); }, {path("bad.h5"), "closed"});
  expect_error([&] { io::ArchiveWriter lost(path("missing_folder/x.h5")); },
               {"missing_folder", "cannot create"});
}

// A damaged dataspace (one bit flipped in an array's length, as the checkpoint fuzzer found) claims
// more values than the file holds: refused by name before anything is allocated for it.
TEST_F(ArchiveTest, ADamagedLengthIsRefusedBeforeAllocating) {
  constexpr std::uint64_t n = 4099;
  {
    io::ArchiveWriter out(path("damaged.h5"));
    out.put("a", std::vector<double>(n, 0.5));
    out.commit();
  }
  std::string bytes;
  {
    std::ifstream in(path("damaged.h5"), std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::string length(8, '\0');
  for (int k = 0; k < 8; ++k) length[k] = static_cast<char>((n >> (8 * k)) & 0xff);
  const std::size_t at = bytes.find(length);
  ASSERT_NE(at, std::string::npos);
  bytes[at + 5] ^= 0x01;  // bit 40: 4099 + 2^40 values
  {
    std::ofstream out(path("damaged.h5"), std::ios::binary | std::ios::trunc);
    out << bytes;
  }
  expect_error([&] { (void)io::ArchiveReader(path("damaged.h5")).doubles("a"); },
               {path("damaged.h5"), "'a'", "more than the file's"});
}

TEST_F(ArchiveTest, UncommittedWriterLeavesNoFile) {
  {
    io::ArchiveWriter out(path("checkpoint.h5"));
    out.put("x", std::vector<double>{1.0, 2.0});
    // Built in memory: nothing is on disk before commit().
    EXPECT_FALSE(std::filesystem::exists(path("checkpoint.h5.tmp")));
  }
  EXPECT_FALSE(std::filesystem::exists(path("checkpoint.h5.tmp")));
  EXPECT_FALSE(std::filesystem::exists(path("checkpoint.h5")));

  // An older committed archive survives a later writer that never commits (a run killed mid-write),
  // and is replaced by one that does.
  {
    io::ArchiveWriter out(path("checkpoint.h5"));
    out.put_scalar("step", std::int64_t{1});
    out.commit();
  }
  {
    io::ArchiveWriter out(path("checkpoint.h5"));
    out.put_scalar("step", std::int64_t{2});
  }
  EXPECT_EQ(io::ArchiveReader(path("checkpoint.h5")).scalar_int("step"), 1);
  {
    io::ArchiveWriter first(path("checkpoint.h5"));
    first.put_scalar("step", std::int64_t{3});
    io::ArchiveWriter moved = std::move(first);  // the file goes with the writer
    moved.commit();
  }
  EXPECT_EQ(io::ArchiveReader(path("checkpoint.h5")).scalar_int("step"), 3);
  EXPECT_FALSE(std::filesystem::exists(path("checkpoint.h5.tmp")));
}

}  // namespace
}  // namespace liquid
