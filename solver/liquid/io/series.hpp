#pragma once
// A time series ParaView opens as one dataset with a time slider: DIR/NAME.xmf (XDMF 3) holds a
// Temporal collection grid with one Spatial collection per frame, each a <Time Value="..."/> and
// the grids of that frame (say the tree's cells and the particles) embedded as written by
// write_tree() / write_points(). The grids name their HDF5 files by file name only, so the frames'
// files must lie in the series file's folder.
//
// The whole series file is rewritten (under a temporary name, then renamed) after every change, so
// it is complete whenever a run is killed. A run that resumes from a checkpoint saves frames() with
// the checkpoint and hands them back (constructor or restore()), then truncate_after(t) drops what a
// later, abandoned part of the run had added.

#include <string>
#include <vector>

namespace liquid::io {

/// One frame of a series: its time and its grids, each one XDMF <Grid>...</Grid> element.
struct SeriesFrame {
  double time = 0.0;
  std::vector<std::string> grids;
};

class SeriesWriter {
 public:
  /// A writer of `path` (DIR/NAME.xmf; DIR must exist) with no frames yet. Nothing is written
  /// before the first change.
  explicit SeriesWriter(std::string path);
  /// A writer of `path` holding `frames` (as from frames()); writes the series file at once.
  SeriesWriter(std::string path, std::vector<SeriesFrame> frames);

  /// Appends a frame at `time` (finite, later than every frame's) holding `grids` (at least one,
  /// each a <Grid>...</Grid> element), then rewrites the series file. Grids of the frame that share a
  /// Name get "_2", "_3", ... appended (a grid without a Name is named "grid"), so ParaView's blocks
  /// are told apart. Throws liquid::Error on bad input or when the file cannot be written.
  void add(double time, std::vector<std::string> grids);
  /// Drops every frame later than `time`, then rewrites the series file. When the file cannot be
  /// written, every call here throws and leaves frames() as it was.
  void truncate_after(double time);
  /// Replaces the frames by `frames` (checked as add() checks them), then rewrites the series file.
  void restore(std::vector<SeriesFrame> frames);

  /// The frames, in time order, with their grids as written (unique Names).
  std::vector<SeriesFrame> frames() const { return frames_; }
  const std::string& path() const { return path_; }

 private:
  void append(double time, std::vector<std::string> grids);  ///< checks and appends, writes nothing
  void write() const;
  void write_or_restore(std::vector<SeriesFrame> old);  ///< writes; on failure the frames go back to `old`

  std::string path_;
  std::vector<SeriesFrame> frames_;
};

}  // namespace liquid::io
