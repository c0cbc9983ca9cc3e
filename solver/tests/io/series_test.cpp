// Time series: the series file is well-formed XML with one Temporal collection whose Spatial
// collections list the frames in order with their times and uniquely named grids; truncate_after
// drops later frames; frames() and restore() carry the list across a resumed run; bad input is
// refused and leaves the list as it was.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "liquid/core/error.hpp"
#include "liquid/io/point_output.hpp"
#include "liquid/io/series.hpp"
#include "liquid/io/tree_output.hpp"
#include "liquid/tree/builders.hpp"

namespace liquid {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// One element of a parsed XML document: its tag, attributes and child elements.
struct Element {
  std::string tag;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::vector<Element> children;
  std::string attribute(const std::string& name) const {
    for (const auto& [key, value] : attributes)
      if (key == name) return value;
    return {};
  }
};

/// A small XML parser, enough for XDMF: declarations, a doctype, elements with quoted attributes
/// and text. Fails the test (and returns an empty root) unless the document is well-formed with one
/// root element.
Element parse_xml(const std::string& text) {
  static const std::regex tag_pattern(R"re(<(/?)([A-Za-z_][\w.-]*)((?:\s+[\w.-]+="[^"<]*")*)\s*(/?)>)re");
  static const std::regex attribute_pattern(R"re(([\w.-]+)="([^"]*)")re");
  std::vector<Element> open{Element{}};
  std::size_t at = 0, n_roots = 0;
  while ((at = text.find('<', at)) != std::string::npos) {
    if (text.compare(at, 2, "<?") == 0 || text.compare(at, 2, "<!") == 0) {
      at = text.find('>', at);
      if (at == std::string::npos) break;
      continue;
    }
    std::smatch m;
    const std::string rest = text.substr(at, text.find('>', at) - at + 1);
    if (!std::regex_match(rest, m, tag_pattern)) {
      ADD_FAILURE() << "not a well-formed tag: " << rest;
      return {};
    }
    at += rest.size();
    if (m[1].length() > 0) {  // an end tag closes the innermost open element
      if (open.size() < 2 || open.back().tag != m[2].str()) {
        ADD_FAILURE() << "</" << m[2].str() << "> closes <" << open.back().tag << ">";
        return {};
      }
      Element done = std::move(open.back());
      open.pop_back();
      open.back().children.push_back(std::move(done));
      continue;
    }
    Element e{m[2].str(), {}, {}};
    const std::string attributes = m[3].str();
    for (auto it = std::sregex_iterator(attributes.begin(), attributes.end(), attribute_pattern);
         it != std::sregex_iterator(); ++it)
      e.attributes.emplace_back((*it)[1].str(), (*it)[2].str());
    if (open.size() == 1) ++n_roots;
    if (m[4].length() > 0)
      open.back().children.push_back(std::move(e));
    else
      open.push_back(std::move(e));
  }
  EXPECT_EQ(open.size(), 1u) << "unclosed <" << open.back().tag << ">";
  EXPECT_EQ(n_roots, 1u);
  if (open.size() != 1 || open[0].children.size() != 1) return {};
  return std::move(open[0].children[0]);
}

/// The frames a series file lists: each frame's time and the Names of its grids.
struct ListedFrame {
  double time;
  std::vector<std::string> names;
};

std::vector<ListedFrame> listed_frames(const std::string& path) {
  const Element root = parse_xml(read_text(path));
  EXPECT_EQ(root.tag, "Xdmf");
  if (root.children.size() != 1 || root.children[0].children.size() != 1) {
    ADD_FAILURE() << "no Domain with one Grid in " << path;
    return {};
  }
  const Element& series = root.children[0].children[0];
  EXPECT_EQ(series.tag, "Grid");
  EXPECT_EQ(series.attribute("GridType"), "Collection");
  EXPECT_EQ(series.attribute("CollectionType"), "Temporal");
  std::vector<ListedFrame> frames;
  for (const Element& frame : series.children) {
    EXPECT_EQ(frame.tag, "Grid");
    EXPECT_EQ(frame.attribute("CollectionType"), "Spatial");
    ListedFrame listed{std::nan(""), {}};
    for (const Element& child : frame.children) {
      if (child.tag == "Time") listed.time = std::stod(child.attribute("Value"));
      if (child.tag == "Grid") listed.names.push_back(child.attribute("Name"));
    }
    frames.push_back(listed);
  }
  return frames;
}

std::vector<double> times(const std::vector<ListedFrame>& frames) {
  std::vector<double> out;
  for (const ListedFrame& f : frames) out.push_back(f.time);
  return out;
}

class SeriesWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("liquid_series_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  /// The grid of a few 2D points written as DIR/STEM.
  std::string points(const std::string& stem, int n) {
    std::vector<Vec<2>> x(n);
    for (int i = 0; i < n; ++i) x[i] = Vec<2>(0.1 * i, 0.2 * i);
    return io::write_points<2>((dir_ / stem).string(), x).grid;
  }

  std::filesystem::path dir_;
};

TEST_F(SeriesWriterTest, ListsFramesInOrderWithTheirTimesAndUniqueGridNames) {
  const std::string path = (dir_ / "run.xmf").string();
  io::SeriesWriter series(path);
  EXPECT_FALSE(std::filesystem::exists(path));  // nothing before the first frame
  series.add(0.0, {points("p0", 3), points("q0", 2)});
  series.add(0.5, {points("p1", 4)});
  series.add(1.25, {points("p2", 5), points("q2", 1), points("r2", 0)});
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const std::vector<ListedFrame> frames = listed_frames(path);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(times(frames), (std::vector<double>{0.0, 0.5, 1.25}));
  EXPECT_EQ(frames[0].names, (std::vector<std::string>{"points2d", "points2d_2"}));
  EXPECT_EQ(frames[1].names, (std::vector<std::string>{"points2d"}));
  EXPECT_EQ(frames[2].names, (std::vector<std::string>{"points2d", "points2d_2", "points2d_3"}));
  // frames() holds the grids as written, renamed.
  ASSERT_EQ(series.frames().size(), 3u);
  EXPECT_NE(series.frames()[2].grids[2].find("Name=\"points2d_3\""), std::string::npos);
  EXPECT_NE(read_text(path).find("r2.h5:/geometry"), std::string::npos);

  // A grid without a Name is named; a second one gets a suffix.
  series.add(2.0, {"<Grid GridType=\"Uniform\"></Grid>", "  <Grid>\n</Grid>\n"});
  EXPECT_EQ(listed_frames(path).back().names, (std::vector<std::string>{"grid", "grid_2"}));
}

TEST_F(SeriesWriterTest, TruncateAfterDropsLaterFrames) {
  const std::string path = (dir_ / "run.xmf").string();
  io::SeriesWriter series(path);
  for (int k = 0; k < 5; ++k) series.add(0.25 * k, {points(fmt::format("p{}", k), k)});
  series.truncate_after(0.6);
  EXPECT_EQ(times(listed_frames(path)), (std::vector<double>{0.0, 0.25, 0.5}));
  series.truncate_after(0.5);  // a frame at exactly the time stays
  EXPECT_EQ(series.frames().size(), 3u);
  series.add(0.55, {points("p_resumed", 2)});
  EXPECT_EQ(times(listed_frames(path)), (std::vector<double>{0.0, 0.25, 0.5, 0.55}));
  series.truncate_after(-1.0);
  EXPECT_TRUE(series.frames().empty());
  EXPECT_TRUE(listed_frames(path).empty());
}

TEST_F(SeriesWriterTest, FramesRestoreAcrossAResumedRun) {
  const std::string path = (dir_ / "run.xmf").string();
  std::vector<io::SeriesFrame> saved;
  {
    io::SeriesWriter series(path);
    series.add(0.1, {points("a", 2), points("b", 2)});
    series.add(0.2, {points("c", 3)});
    saved = series.frames();  // the checkpoint
    series.add(0.3, {points("d", 3)});
    series.add(0.4, {points("e", 3)});
  }
  // The run resumes from the checkpoint at 0.2: a new writer gets the saved frames.
  io::SeriesWriter resumed(path, saved);
  EXPECT_EQ(times(listed_frames(path)), (std::vector<double>{0.1, 0.2}));
  EXPECT_EQ(listed_frames(path)[0].names, (std::vector<std::string>{"points2d", "points2d_2"}));
  resumed.add(0.3, {points("d", 4)});
  EXPECT_EQ(times(listed_frames(path)), (std::vector<double>{0.1, 0.2, 0.3}));
  // Or a writer that kept going restores the list and truncates.
  io::SeriesWriter other(path);
  other.restore(resumed.frames());
  other.truncate_after(0.15);
  EXPECT_EQ(times(listed_frames(path)), (std::vector<double>{0.1}));
}

TEST_F(SeriesWriterTest, RefusesBadFramesAndKeepsTheList) {
  const std::string path = (dir_ / "run.xmf").string();
  io::SeriesWriter series(path);
  series.add(1.0, {points("p", 2)});
  const auto refused = [&](auto&& call, const std::string& expected) {
    try {
      call();
      ADD_FAILURE() << "no throw for " << expected;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
    EXPECT_EQ(series.frames().size(), 1u) << expected;
    EXPECT_EQ(listed_frames(path).size(), 1u) << expected;
  };
  refused([&] { series.add(1.0, {points("q", 2)}); }, "times must increase");
  refused([&] { series.add(0.5, {points("q", 2)}); }, "times must increase");
  refused([&] { series.add(std::nan(""), {points("q", 2)}); }, "finite");
  refused([&] { series.add(2.0, {}); }, "has no grid");
  refused([&] { series.add(2.0, {"<Domain></Domain>"}); }, "not one XDMF <Grid");
  refused([&] { series.add(2.0, {"<Grid Name=\"x\">"}); }, "not one XDMF <Grid");
  refused([&] { series.restore({{3.0, {points("q", 2)}}, {2.0, {points("r", 2)}}}); }, "times must increase");
  refused([&] { series.truncate_after(std::nan("")); }, "NaN");
  // A file that cannot be written is an error naming it, and the frame is not kept.
  io::SeriesWriter lost((dir_ / "missing_folder" / "run.xmf").string());
  try {
    lost.add(0.0, {points("p", 1)});
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing_folder"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(lost.frames().empty());
}

// The files the check_xdmf.py ctest reads (verification/CMakeLists.txt): a 2D series of the tree
// and the particles (the second frame has no particle) and a 3D series of particles, each frame's
// files also readable on their own. Written into $LIQUID_IO_SAMPLE_DIR when set, else a temporary
// folder.
TEST_F(SeriesWriterTest, SampleForTheXdmfChecker) {
  const char* sample = std::getenv("LIQUID_IO_SAMPLE_DIR");
  const std::filesystem::path dir = sample ? std::filesystem::path(sample) : dir_;
  io::SeriesWriter series_2d((dir / "series-2d.xmf").string()), series_3d((dir / "series-3d.xmf").string());
  const tree::CellGraph<2> tree = tree::uniform<2>(Box<2>{}, 2);
  std::vector<double> phi(tree.cell_capacity(), 0.0);
  tree.for_each_cell([&](tree::CellId c) { phi[c] = tree.centre(c).norm() - 0.5; });
  const std::vector<io::CellField> cell_fields{{"phi", phi}};
  for (int frame = 0; frame < 2; ++frame) {
    const int n = frame == 0 ? 6 : 0;
    std::vector<Vec<2>> x2(n);
    std::vector<Vec<3>> x3(n + 1);
    std::vector<double> mass(n), velocity(2 * n), velocity3(3 * (n + 1));
    for (int i = 0; i < n; ++i) {
      x2[i] = Vec<2>(0.1 * i, 0.05 * i * i);
      mass[i] = 1.0 + i;
      velocity[2 * i] = -x2[i][1];
      velocity[2 * i + 1] = x2[i][0];
    }
    for (int i = 0; i <= n; ++i) {
      x3[i] = Vec<3>(0.1 * i, 0.2, 0.3 * i);
      for (int d = 0; d < 3; ++d) velocity3[3 * i + d] = i + d;
    }
    const std::vector<io::PointField> fields2{{"mass", 1, mass}, {"velocity", 2, velocity}};
    const std::vector<io::PointField> fields3{{"velocity", 3, velocity3}};
    const std::string tag = std::to_string(frame);
    const io::TreeFiles cells = io::write_tree<2>((dir / ("cells-2d-" + tag)).string(), tree, cell_fields);
    const io::PointFiles particles =
        io::write_points<2>((dir / ("particles-2d-" + tag)).string(), x2, fields2);
    series_2d.add(0.5 * frame, {cells.grid, particles.grid});
    series_3d.add(0.5 * frame,
                  {io::write_points<3>((dir / ("particles-3d-" + tag)).string(), x3, fields3).grid});
  }
  EXPECT_EQ(times(listed_frames((dir / "series-2d.xmf").string())), (std::vector<double>{0.0, 0.5}));
  EXPECT_EQ(listed_frames((dir / "series-2d.xmf").string())[1].names,
            (std::vector<std::string>{"cellgraph2d", "points2d"}));
  EXPECT_EQ(times(listed_frames((dir / "series-3d.xmf").string())), (std::vector<double>{0.0, 0.5}));
}

}  // namespace
}  // namespace liquid
