#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "experiments/output/output_dir.hpp"
#include "experiments/output/output_file.hpp"
#include "experiments/output/vtk_writer.hpp"
#include "experiments/run/checkpoint.hpp"
#include "hooke/integrators/stepper.hpp"
#include "problems/scene.hpp"

namespace hooke {

/// The resolved scene as text (what DIR/scene.toml holds below its comment line).
std::string resolved_scene_text(const Scene& scene);

/// Writes the scene with every default filled in (DIR/scene.toml): rerunnable as is.
void write_resolved_scene(const Scene& scene, const std::string& path);

/// Refuses (InputError) a fresh run into a folder that holds a resumable checkpoint, unless
/// force: the stopped run would be lost without a word.
void check_no_stopped_run(const OutputDir& dir, bool force);

/// The files of one mass-spring run in its locked output folder (OutputDir), over their whole
/// life. A fresh run refuses a folder that holds a resumable checkpoint (unless forced), marks the
/// folder "running" in status.txt, removes every output of an earlier run (final.csv, final.png,
/// final.vtk, checkpoint.bin and its pieces, frames) and writes scene.toml and a new log.csv. A
/// resumed run cuts log.csv back to the checkpointed step and removes the frames written after it.
/// Then one row per logged step, VTK frames (an MPI run's as .pvtu with one .vtu piece per process)
/// with their frames.pvd, checkpoints, and at the end final.vtk, final.png and final.csv, after
/// which status.txt says "finished". final.csv lists the fluid particles only in a fluid scene (its
/// boundary particles are the tank and obstacles, in the frames with pinned = 1). Every file of a
/// run is opened, written and named here and nowhere else, through OutputFile (a failed write
/// throws OutputError), except final.png, which experiments/plot/final.py draws from final.vtk and
/// writes just as atomically (common.save_figure), or the built-in renderer if it cannot.
class RunOutput {
 public:
  /// scene must outlive the object. resume: the checkpoint a resumed run continues from, or
  /// null. force: a fresh run may replace a resumable checkpoint. Throws InputError for a folder
  /// that holds a checkpoint (fresh run, not forced) or a log.csv shorter than the checkpoint says;
  /// OutputError when a file cannot be written. figure_columns: the names of the stepper's step
  /// figures (Stepper::step_figures), log.csv's last columns.
  RunOutput(const Scene& scene, std::unique_ptr<OutputDir> dir, const Checkpoint* resume,
            bool force, std::vector<std::string> figure_columns = {});

  const std::string& dir() const { return m_dir->path(); }
  std::string checkpoint_path() const { return m_dir->file("checkpoint.bin"); }
  /// Frames written so far: (t, path relative to dir).
  const std::vector<std::pair<double, std::string>>& frames() const { return m_frames; }

  /// What an error-controlled run (integrator.adaptive) adds to each log.csv row, in columns h,
  /// accepted, rejected: the last step's size (s) and the cumulative counts of accepted steps and
  /// rejected attempts.
  struct ControlColumns {
    double h = 0.0;
    long long accepted = 0, rejected = 0;
  };
  /// Appends the log row of `step` at state s; returns the total energy (J) it logged. control:
  /// the error control's columns, given exactly for adaptive scenes. figures: the stepper's
  /// figures of the step (Stepper::step_figures), one per figure column, in their order (an SPH
  /// stepper's: max_density_error, mean_density_error, pressure_iterations, substeps, front and
  /// lost).
  double log_row(long long step, const State& s, int iterations, double residual, double wall,
                 const ControlColumns* control = nullptr,
                 const std::vector<StepFigure>& figures = {});
  /// Writes frame `step` (if [output] vtk) and rewrites frames.pvd; fields: the stepper's
  /// (Stepper::output_fields).
  void frame(long long step, const State& s, const std::vector<ParticleField>& fields = {});
  /// Where process `rank` of an MPI run writes its piece of frame `step` (write_vtu_piece) in the
  /// run folder `dir`: DIR/frames/frame_STEP_RANK.vtu.
  static std::string frame_piece_path(const std::string& dir, long long step, int rank);
  /// Frame `step` of an MPI run of `pieces` processes, whose pieces are written: writes its
  /// frames/frame_STEP.pvtu, which lists them, and rewrites frames.pvd. t: the frame's time.
  void parallel_frame(long long step, double t, int pieces);
  /// Makes log.csv durable and writes DIR/checkpoint.bin from c, with the log position, frames
  /// and the scene's identity (identify) filled in.
  void checkpoint(Checkpoint c);
  /// Fills in what ties a checkpoint to its run: hooke's version, the resolved scene and the
  /// initial-state hash.
  static void identify(Checkpoint& c, const Scene& scene);
  /// Where process `rank` of an MPI run of `size` processes writes its piece of the checkpoint of
  /// step `step` (its local state and stepper history, in write_checkpoint's format) in the run
  /// folder `dir`: DIR/checkpoint.STEP.RANK-of-SIZE.bin. The pieces of a step are written before
  /// rank 0 commits checkpoint.bin (the whole state) for that step, and the older pieces removed
  /// after it (remove_checkpoint_pieces), so checkpoint.bin always has its complete set.
  static std::string checkpoint_piece_path(const std::string& dir, long long step, int rank,
                                           int size);
  /// Removes every checkpoint piece in the folder but those of step `keep_step` written by
  /// `keep_size` processes (all of them for keep_step < 0).
  void remove_checkpoint_pieces(long long keep_step, int keep_size);
  /// Flushes log.csv to disk, so that it is complete up to the last row when the run stops.
  void flush();
  /// The run stopped with a checkpoint (signal or --stop-after): status.txt says "stopped".
  void stopped(const std::string& detail);
  /// The run failed (exit 3, or an error): status.txt says "failed" with why, and log.csv keeps
  /// its complete rows. Never throws; returns false if status.txt could not be written.
  bool failed(const std::string& why) noexcept;
  /// The end of a complete run: writes final.csv (and final.vtk, final.png if [output] png) from s,
  /// removes the checkpoint (nothing is left to resume) and marks the folder finished. Returns the
  /// names of the files the run wrote, for the end-of-run line.
  std::vector<std::string> finish(const State& s, const std::string& summary,
                                  const std::vector<ParticleField>& fields = {});

 private:
  void start_fresh(bool force);
  FrameMesh frame_mesh(const std::vector<ParticleField>& fields) const;
  void prepare_frames(const Checkpoint* resume);

  const Scene& m_scene;
  std::unique_ptr<OutputDir> m_dir;
  std::string m_frames_dir;
  std::vector<std::pair<double, std::string>> m_frames;
  std::unique_ptr<OutputFile> m_log;
  State m_exact;  // scratch for the exact solution's column
  const std::vector<std::string> m_figure_columns;
};

}  // namespace hooke
