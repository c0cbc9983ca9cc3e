#pragma once
// What the PIC and the SPH runners share: their clock (the step size, the end, the frame
// cadence), their file names, and in checkpoints the command line's overrides, the run's settings
// and the frames of the time series written so far.

#include <memory>
#include <string>
#include <vector>

#include "liquid/io/archive.hpp"
#include "liquid/io/series.hpp"
#include "liquid/scene/runner.hpp"

namespace liquid::scene::detail {

/// The next step: the solver's stable step clamped to [dt_min, dt_max], landing on the end time (no
/// sliver step after it) when the run goes by time.
double next_step(const SceneTime& time, double stable, double now);
/// Whether a run at (step, now) has reached its end.
bool run_done(const SceneTime& time, long step, double now);
/// Whether a frame is due after a step that reached `now` (next_frame: from next_frame_time()).
bool frame_due(const SceneOutput& output, double now, double next_frame);
/// When the frame after one written at `now` is due (infinity without output.every).
double next_frame_time(const SceneOutput& output, double now);
/// Creates settings.out when it is set (throws naming it when it cannot), and returns the writer of
/// its series OUT/NAME.xmf when frames are written (else null).
std::unique_ptr<io::SeriesWriter> open_output(const RunSettings& settings, const std::string& name);
/// OUT/NAME_WHAT_IIIIII
std::string file_stem(const std::string& out, const std::string& name, const char* what, long index);

/// Writes the scene path, the overrides and the checkpoint interval under scene/, overrides/, run/.
void put_run_settings(io::ArchiveWriter& w, const RunSettings& settings, const std::string& scene_path);
/// Reads what put_run_settings() wrote into `settings` (the interval only when settings has none).
void get_run_settings(const io::ArchiveReader& r, RunSettings& settings);
/// The frames of a series under run/series/; get_series() leads the frames' file references from
/// `out` (the resumed run's folder) to the checkpoint's folder when the two differ.
void put_series(io::ArchiveWriter& w, const io::SeriesWriter* series);
std::vector<io::SeriesFrame> get_series(const io::ArchiveReader& r, const std::string& out);
/// Restores into `series` the frames get_series() reads; a damaged frame is refused naming the
/// checkpoint (r.path()) and run/series.
void restore_series(const io::ArchiveReader& r, const std::string& out, io::SeriesWriter& series);

}  // namespace liquid::scene::detail
