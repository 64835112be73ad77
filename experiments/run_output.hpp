#pragma once
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "experiments/checkpoint.hpp"
#include "problems/scene.hpp"

namespace hooke {

/// A file written with stdio that is closed (flushed) on destruction, so an interrupted or
/// diverged run keeps what it wrote. Throws std::runtime_error if the file cannot be opened.
class CsvFile {
 public:
  explicit CsvFile(const std::string& path, bool append = false);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  FILE* get() { return m_f; }

 private:
  FILE* m_f;
};

/// Writes the scene with every default filled in (DIR/scene.toml): rerunnable as is.
void write_resolved_scene(const Scene& scene, const std::string& path);

/// The files of one mass-spring run in its output directory, over their whole life: a fresh run
/// removes a stale checkpoint and old frames and starts log.csv; a resumed one cuts log.csv back to
/// the checkpointed step and removes the frames written after it. Then one row per logged step,
/// VTK frames with their frames.pvd, checkpoints, and at the end final.csv and final.png. Every
/// file of a run is opened, written and named here and nowhere else.
class RunOutput {
 public:
  /// scene must outlive the object. resume: the checkpoint a resumed run continues from, or null.
  /// Throws InputError for a log.csv shorter than the checkpoint says, std::runtime_error when a
  /// file cannot be written.
  RunOutput(const Scene& scene, std::string dir, const Checkpoint* resume);

  const std::string& dir() const { return m_dir; }
  std::string checkpoint_path() const { return m_dir + "/checkpoint.bin"; }
  /// Frames written so far: (t, path relative to dir).
  const std::vector<std::pair<double, std::string>>& frames() const { return m_frames; }

  /// Appends the log row of `step` at state s; returns the total energy (J) it logged.
  double log_row(long long step, const State& s, int iterations, double residual, double wall);
  /// Writes frame `step` (if [output] vtk) and rewrites frames.pvd.
  void frame(long long step, const State& s);
  /// Writes DIR/checkpoint.bin atomically from c, with the log position and frames filled in.
  void checkpoint(Checkpoint c);
  /// Flushes log.csv, so that it is complete up to the last row when the run stops.
  void flush();
  /// The end of a complete run: writes final.csv (and final.png if [output] png) from s and
  /// removes the checkpoint (nothing is left to resume).
  void finish(const State& s);

 private:
  void prepare_frames(const Checkpoint* resume);

  const Scene& m_scene;
  std::string m_dir, m_frames_dir;
  std::vector<std::pair<double, std::string>> m_frames;
  CsvFile m_log;
  State m_exact;  // scratch for the exact solution's column
};

}  // namespace hooke
