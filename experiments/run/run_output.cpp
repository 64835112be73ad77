#include "experiments/run/run_output.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "experiments/output/png_writer.hpp"
#include "experiments/output/vtk_writer.hpp"
#include "experiments/output/vtu_writer.hpp"
#include "experiments/plot_script.hpp"
#include "hooke/config.hpp"

namespace hooke {

namespace fs = std::filesystem;

std::string resolved_scene_text(const Scene& scene) {
  std::ostringstream os;
  os << scene.resolved << "\n";
  return os.str();
}

void write_resolved_scene(const Scene& scene, const std::string& path) {
  write_file(path, "# Resolved scene: " + scene.file +
                       " with every default filled in (written by hooke run).\n" +
                       resolved_scene_text(scene));
}

namespace {
/// frame_STEP, the stem of frame `step`'s files.
std::string frame_stem(long long step) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%08lld", step);
  return name;
}

/// DIR/log.csv of a resumed run, cut back to the checkpointed step (rows after it are written
/// again) and opened for appending.
std::unique_ptr<OutputFile> reopen_log(const std::string& path, const Checkpoint& resume) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec || static_cast<long long>(size) < resume.log_bytes)
    throw InputError(path, "log",
                     "is shorter than the checkpoint says (" + std::to_string(resume.log_bytes) +
                         " bytes): it was changed after the run stopped");
  fs::resize_file(path, static_cast<std::uintmax_t>(resume.log_bytes), ec);
  if (ec) throw OutputError(path, "shorten", ec.value());
  return std::make_unique<OutputFile>(OutputFile::stream(path, true));
}

/// The particles of final.csv: a fluid's own (boundary particles left out), or all.
Index listed_particles(const Scene& scene) {
  return scene.is_fluid() ? scene.system->fluid()->num_fluid() : scene.system->num_particles();
}

void write_final_csv(const std::string& path, const State& s, Index n) {
  OutputFile f = OutputFile::replace(path);
  f.print("id,x,y,z,vx,vy,vz\n");
  for (Index i = 0; i < n; ++i)
    f.print("%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", (long long)i, s.x[3 * i], s.x[3 * i + 1],
            s.x[3 * i + 2], s.v[3 * i], s.v[3 * i + 1], s.v[3 * i + 2]);
  f.commit();
}

}  // namespace

RunOutput::RunOutput(const Scene& scene, std::unique_ptr<OutputDir> dir, const Checkpoint* resume,
                     bool force, std::vector<std::string> figure_columns)
    : m_scene(scene),
      m_dir(std::move(dir)),
      m_frames_dir(m_dir->file("frames")),
      m_exact(scene.initial),
      m_figure_columns(std::move(figure_columns)) {
  if (resume) {
    m_log = reopen_log(m_dir->file("log.csv"), *resume);
    m_frames = resume->frames;
    m_dir->set_status("running", "resumed at step " + std::to_string(resume->step));
  } else {
    start_fresh(force);
  }
  prepare_frames(resume);
}

void check_no_stopped_run(const OutputDir& dir, bool force) {
  std::error_code ec;
  const std::string path = dir.file("checkpoint.bin");
  if (fs::exists(path, ec) && !force)
    throw InputError(path, "checkpoint",
                     "this folder holds a stopped run that `hooke resume " + dir.path() +
                         "` continues; to start this run over it instead (deleting the "
                         "checkpoint), pass --force, or choose another folder with --out");
}

void RunOutput::start_fresh(bool force) {
  check_no_stopped_run(*m_dir, force);
  // Everything an earlier run left, its mark of completion first: final.csv must exist only for
  // a run that finished. Removed before status.txt is written, which frees the space it needs.
  m_dir->remove_files({"final.csv", "status.txt", "final.png", "final.vtk", "checkpoint.bin",
                       "frames.pvd", "log.csv", "final.csv.tmp", "final.png.tmp", "final.vtk.tmp",
                       "checkpoint.bin.tmp", "frames.pvd.tmp", "scene.toml.tmp", "status.txt.tmp"});
  remove_checkpoint_pieces(-1, 0);
  m_dir->set_status("running");
  write_resolved_scene(m_scene, m_dir->file("scene.toml"));
  m_log = std::make_unique<OutputFile>(OutputFile::stream(m_dir->file("log.csv")));
  m_log->print("step,t,kinetic,potential,total,max_strain,iterations,residual,wall_time%s%s",
               m_scene.exact ? ",error" : "",
               m_scene.integrator.adaptive ? ",h,accepted,rejected" : "");
  for (const std::string& column : m_figure_columns) m_log->print(",%s", column.c_str());
  m_log->print("\n");
}

void RunOutput::prepare_frames(const Checkpoint* resume) {
  std::error_code ec;
  if (!fs::is_directory(m_frames_dir, ec)) {
    if (m_scene.output.vtk) {
      fs::create_directories(m_frames_dir, ec);
      if (ec) throw OutputError(m_frames_dir, "create", ec.value());
    }
    return;
  }
  // A fresh run removes every frame; a resumed one those written after its checkpoint.
  for (const auto& e : fs::directory_iterator(m_frames_dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("frame_", 0) != 0) continue;
    const long long frame_step = std::atoll(name.c_str() + 6);
    const std::string ext = e.path().extension().string();
    if (!resume || frame_step > resume->step ||
        (ext != ".vtk" && ext != ".pvtu" && ext != ".vtu")) {
      fs::remove(e.path(), ec);
      if (ec) throw OutputError(e.path().string(), "remove", ec.value());
    }
  }
}

double RunOutput::log_row(long long step, const State& s, int iterations, double residual,
                          double wall, const ControlColumns* control,
                          const std::vector<StepFigure>& figures) {
  HOOKE_ASSERT((control != nullptr) == m_scene.integrator.adaptive,
               "error-control columns exactly for adaptive scenes");
  HOOKE_ASSERT(figures.size() == m_figure_columns.size(),
               figures.size() << " step figures for " << m_figure_columns.size() << " columns");
  const MassSpringSystem& sys = *m_scene.system;
  const double K = sys.kinetic_energy(s.v), U = sys.potential_energy(s.x);
  m_log->print("%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%.6g,%.6g", step, s.t, K, U, K + U,
               sys.max_strain(s.x), iterations, residual, wall);
  if (m_scene.exact) {
    m_scene.exact(s.t, m_exact);
    m_log->print(",%.17g", (s.x - m_exact.x).lpNorm<Eigen::Infinity>());
  }
  if (control) m_log->print(",%.17g,%lld,%lld", control->h, control->accepted, control->rejected);
  for (size_t k = 0; k < figures.size(); ++k) {
    HOOKE_ASSERT(m_figure_columns[k] == figures[k].name,
                 "step figure " << figures[k].name << " in column " << m_figure_columns[k]);
    m_log->print(",%.*g", figures[k].digits, figures[k].value);
  }
  m_log->print("\n");
  return K + U;
}

void RunOutput::frame(long long step, const State& s, const std::vector<ParticleField>& fields) {
  if (!m_scene.output.vtk) return;
  const std::string name = frame_stem(step) + ".vtk";
  // Frames of fixed steps carry the step's nominal time (0.1, not a sum of steps
  // 0.10000000000000002); error control lands on its frame times exactly.
  const double t = m_scene.integrator.adaptive ? s.t : m_scene.step_plan().time_at(step);
  write_vtk_frame(m_frames_dir + "/" + name, s, t, frame_mesh(fields));
  m_frames.emplace_back(t, std::string("frames/") + name);
  write_pvd(m_dir->file("frames.pvd"), m_frames);
}

std::string RunOutput::frame_piece_path(const std::string& dir, long long step, int rank) {
  return dir + "/frames/" + frame_stem(step) + "_" + std::to_string(rank) + ".vtu";
}

void RunOutput::parallel_frame(long long step, double t, int pieces) {
  if (!m_scene.output.vtk) return;
  const std::string stem = frame_stem(step);
  std::vector<std::string> names;
  for (int r = 0; r < pieces; ++r) names.push_back(stem + "_" + std::to_string(r) + ".vtu");
  write_pvtu(m_frames_dir + "/" + stem + ".pvtu", names);
  m_frames.emplace_back(t, "frames/" + stem + ".pvtu");
  write_pvd(m_dir->file("frames.pvd"), m_frames);
}

void RunOutput::checkpoint(Checkpoint c) {
  m_log->sync();
  c.log_bytes = m_log->tell();
  c.frames = m_frames;
  identify(c, m_scene);
  write_checkpoint(checkpoint_path(), c);
}

void RunOutput::identify(Checkpoint& c, const Scene& scene) {
  c.version = HOOKE_VERSION;
  c.scene = resolved_scene_text(scene);
  c.initial_hash = initial_state_hash(scene.initial, scene.system->pinned());
}

std::string RunOutput::checkpoint_piece_path(const std::string& dir, long long step, int rank,
                                             int size) {
  return dir + "/checkpoint." + std::to_string(step) + "." + std::to_string(rank) + "-of-" +
         std::to_string(size) + ".bin";
}

void RunOutput::remove_checkpoint_pieces(long long keep_step, int keep_size) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(m_dir->path(), ec)) {
    const std::string name = e.path().filename().string();
    long long step = -1;
    int rank = -1, size = -1, end = 0;
    // checkpoint.STEP.RANK-of-SIZE.bin, or its .tmp
    if (std::sscanf(name.c_str(), "checkpoint.%lld.%d-of-%d.bin%n", &step, &rank, &size, &end) !=
            3 ||
        (name.size() != size_t(end) && name.substr(size_t(end)) != ".tmp"))
      continue;
    if (step == keep_step && size == keep_size && name.size() == size_t(end)) continue;
    std::error_code removed;
    fs::remove(e.path(), removed);
    if (removed) throw OutputError(e.path().string(), "remove", removed.value());
  }
  if (ec) throw OutputError(m_dir->path(), "list", ec.value());
}

void RunOutput::flush() { m_log->sync(); }

void RunOutput::stopped(const std::string& detail) { m_dir->set_status("stopped", detail); }

bool RunOutput::failed(const std::string& why) noexcept {
  try {
    m_log->sync();
  } catch (...) {  // the reason for failing may be this very file: keep its complete rows only
    m_log->abandon();
  }
  return m_dir->mark_failed(why);
}

FrameMesh RunOutput::frame_mesh(const std::vector<ParticleField>& fields) const {
  return FrameMesh{m_scene.edges,
                   m_scene.edge_rest,
                   m_scene.triangles,
                   m_scene.system->pinned(),
                   m_scene.system->masses(),
                   fields};
}

std::vector<std::string> RunOutput::finish(const State& s, const std::string& summary,
                                           const std::vector<ParticleField>& fields) {
  std::vector<std::string> written = {"scene.toml", "log.csv"};
  m_log->commit();
  if (m_scene.output.vtk) written.insert(written.end(), {"frames/", "frames.pvd"});
  if (m_scene.output.png) {
    // The final state as a frame (ParaView opens it too), drawn by experiments/plot/final.py with
    // matplotlib: axes in metres, the time, a strain colour bar, the colliders. Without Python or
    // matplotlib, the built-in renderer still leaves a picture.
    write_vtk_frame(m_dir->file("final.vtk"), s, s.t, frame_mesh(fields));
    written.push_back("final.vtk");
    if (run_plot_script("final.py", m_dir->path(), false) != 0) {
      std::fprintf(stderr,
                   "warning: experiments/plot/final.py failed (it needs /usr/bin/python3 with "
                   "python3-matplotlib; HOOKE_PLOT_DIR finds the script): final.png is drawn by "
                   "the built-in renderer instead, without axes or colour bar\n");
      write_png_picture(m_dir->file("final.png"), s, m_scene.system->pinned(), m_scene.edges,
                        m_scene.edge_rest);
    }
    written.push_back("final.png");
  }
  // final.csv last: its presence says the run finished, so nothing may fail after it.
  write_final_csv(m_dir->file("final.csv"), s, listed_particles(m_scene));
  written.push_back("final.csv");
  try {
    std::error_code ec;
    fs::remove(checkpoint_path(), ec);
    if (ec) throw OutputError(checkpoint_path(), "remove", ec.value());
    remove_checkpoint_pieces(-1, 0);
    m_dir->set_status("finished", summary);
  } catch (...) {
    std::error_code ignored;
    fs::remove(m_dir->file("final.csv"), ignored);
    throw;
  }
  return written;
}

}  // namespace hooke
