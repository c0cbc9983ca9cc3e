#pragma once
// What the PIC and the SPH runners' checkpoints share: the command line's overrides, the run's
// settings and the frames of the time series written so far.

#include <string>
#include <vector>

#include "liquid/io/archive.hpp"
#include "liquid/io/series.hpp"
#include "liquid/scene/runner.hpp"

namespace liquid::detail {

/// Writes the scene path, the overrides and the checkpoint interval under scene/, overrides/, run/.
void put_run_settings(io::ArchiveWriter& w, const RunSettings& settings, const std::string& scene_path);
/// Reads what put_run_settings() wrote into `settings` (the interval only when settings has none).
void get_run_settings(const io::ArchiveReader& r, RunSettings& settings);
/// The frames of a series under run/series/.
void put_series(io::ArchiveWriter& w, const io::SeriesWriter* series);
std::vector<io::SeriesFrame> get_series(const io::ArchiveReader& r);

}  // namespace liquid::detail
