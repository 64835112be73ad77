#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "experiments/checkpoint.hpp"
#include "experiments/output/output_dir.hpp"
#include "experiments/output/output_file.hpp"
#include "experiments/output/vtk_writer.hpp"
#include "hooke/sph/fluid_model.hpp"
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
/// final.vtk, checkpoint.bin, frames) and writes scene.toml and a new log.csv. A resumed run cuts
/// log.csv back to the checkpointed step and removes the frames written after it. Then one row per
/// logged step, VTK frames with their frames.pvd, checkpoints, and at the end final.vtk,
/// final.png and final.csv, after which status.txt says "finished". final.csv lists the fluid
/// particles only in a fluid scene (its boundary particles are the tank and obstacles, in the
/// frames with pinned = 1). Every file of a run is
/// opened, written and named here and nowhere else, through OutputFile (a failed write throws
/// OutputError), except final.png, which experiments/plot/final.py draws from final.vtk and
/// writes just as atomically (common.save_figure), or the built-in renderer if it cannot.
class RunOutput {
 public:
  /// scene must outlive the object. resume: the checkpoint a resumed run continues from, or
  /// null. force: a fresh run may replace a resumable checkpoint. Throws InputError for a folder
  /// that holds a checkpoint (fresh run, not forced) or a log.csv shorter than the checkpoint says;
  /// OutputError when a file cannot be written.
  RunOutput(const Scene& scene, std::unique_ptr<OutputDir> dir, const Checkpoint* resume,
            bool force);

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
  /// What a fluid run adds to its frames: the density at the frame's state (kg/m^3) and the
  /// pressures of the last step (Pa), one entry per fluid particle.
  struct FluidFields {
    const Vec* density = nullptr;
    const Vec* pressure = nullptr;
  };
  /// Appends the log row of `step` at state s; returns the total energy (J) it logged. control:
  /// the error control's columns, given exactly for adaptive scenes. fluid: the step's figures,
  /// given exactly for fluid scenes, in columns max_density_error, mean_density_error,
  /// pressure_iterations, substeps, front (the largest x of a fluid particle, m) and lost (fluid
  /// particles that have left the walls' domain so far, SphStepper).
  double log_row(long long step, const State& s, int iterations, double residual, double wall,
                 const ControlColumns* control = nullptr, const FluidStepStats* fluid = nullptr);
  /// Writes frame `step` (if [output] vtk) and rewrites frames.pvd; fluid: a fluid's fields.
  void frame(long long step, const State& s, const FluidFields* fluid = nullptr);
  /// Makes log.csv durable and writes DIR/checkpoint.bin from c, with the log position, frames
  /// and the scene's identity (version, resolved scene, initial-state hash) filled in.
  void checkpoint(Checkpoint c);
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
                                  const FluidFields* fluid = nullptr);

 private:
  void start_fresh(bool force);
  FrameMesh frame_mesh(const FluidFields* fluid) const;
  void prepare_frames(const Checkpoint* resume);

  const Scene& m_scene;
  std::unique_ptr<OutputDir> m_dir;
  std::string m_frames_dir;
  std::vector<std::pair<double, std::string>> m_frames;
  std::unique_ptr<OutputFile> m_log;
  State m_exact;  // scratch for the exact solution's column
};

}  // namespace hooke
