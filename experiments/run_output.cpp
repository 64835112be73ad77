#include "experiments/run_output.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "experiments/output/png_writer.hpp"
#include "experiments/output/vtk_writer.hpp"

namespace hooke {

namespace fs = std::filesystem;

CsvFile::CsvFile(const std::string& path, bool append)
    : m_f(std::fopen(path.c_str(), append ? "a" : "w")) {
  if (!m_f) throw std::runtime_error("cannot write " + path);
}

CsvFile::~CsvFile() {
  if (m_f) std::fclose(m_f);
}

void write_resolved_scene(const Scene& scene, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# Resolved scene: " << scene.file
      << " with every default filled in (written by hooke run).\n"
      << scene.resolved << "\n";
}

namespace {

/// DIR/log.csv, cut back to the checkpointed step on a resume (rows after it are written again).
std::string prepare_log(const std::string& dir, const Checkpoint* resume) {
  const std::string path = dir + "/log.csv";
  if (resume) {
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (ec || static_cast<long long>(size) < resume->log_bytes)
      throw InputError(path, "log",
                       "is shorter than the checkpoint says (" + std::to_string(resume->log_bytes) +
                           " bytes): it was "
                           "changed after the run stopped");
    fs::resize_file(path, static_cast<std::uintmax_t>(resume->log_bytes));
  }
  return path;
}

void write_final_csv(const std::string& path, const State& s) {
  {
    CsvFile f(path + ".tmp");
    std::fprintf(f.get(), "id,x,y,z,vx,vy,vz\n");
    for (Index i = 0; i < s.num_particles(); ++i)
      std::fprintf(f.get(), "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", (long long)i, s.x[3 * i],
                   s.x[3 * i + 1], s.x[3 * i + 2], s.v[3 * i], s.v[3 * i + 1], s.v[3 * i + 2]);
  }
  fs::rename(path + ".tmp", path);
}

}  // namespace

RunOutput::RunOutput(const Scene& scene, std::string dir, const Checkpoint* resume)
    : m_scene(scene),
      m_dir(std::move(dir)),
      m_frames_dir(m_dir + "/frames"),
      m_log(prepare_log(m_dir, resume), resume != nullptr),
      m_exact(scene.initial) {
  if (resume) {
    m_frames = resume->frames;
  } else {
    fs::remove(checkpoint_path());  // a stale checkpoint of an earlier run must not be resumed
    std::fprintf(m_log.get(),
                 "step,t,kinetic,potential,total,max_strain,iterations,residual,wall_time%s\n",
                 scene.exact ? ",error" : "");
  }
  prepare_frames(resume);
}

void RunOutput::prepare_frames(const Checkpoint* resume) {
  if (!m_scene.output.vtk) return;
  fs::create_directories(m_frames_dir);
  // A fresh run removes every frame; a resumed one those written after its checkpoint.
  for (const auto& e : fs::directory_iterator(m_frames_dir)) {
    if (e.path().extension() != ".vtk") continue;
    const std::string stem = e.path().stem().string();
    const long long frame_step = stem.rfind("frame_", 0) == 0 ? std::atoll(stem.c_str() + 6) : -1;
    if (!resume || frame_step > resume->step) fs::remove(e.path());
  }
}

double RunOutput::log_row(long long step, const State& s, int iterations, double residual,
                          double wall) {
  const MassSpringSystem& sys = *m_scene.system;
  const double K = sys.kinetic_energy(s.v), U = sys.potential_energy(s.x);
  FILE* f = m_log.get();
  std::fprintf(f, "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%.6g,%.6g", step, s.t, K, U, K + U,
               sys.max_strain(s.x), iterations, residual, wall);
  if (m_scene.exact) {
    m_scene.exact(s.t, m_exact);
    std::fprintf(f, ",%.17g", (s.x - m_exact.x).lpNorm<Eigen::Infinity>());
  }
  std::fprintf(f, "\n");
  return K + U;
}

void RunOutput::frame(long long step, const State& s) {
  if (!m_scene.output.vtk) return;
  char name[64];
  std::snprintf(name, sizeof name, "frame_%08lld.vtk", step);
  write_vtk_frame(m_frames_dir + "/" + name, s, m_scene.system->pinned(), m_scene.edges);
  m_frames.emplace_back(s.t, std::string("frames/") + name);
  write_pvd(m_dir + "/frames.pvd", m_frames);
}

void RunOutput::checkpoint(Checkpoint c) {
  flush();
  c.log_bytes = std::ftell(m_log.get());
  c.frames = m_frames;
  write_checkpoint(checkpoint_path(), c);
}

void RunOutput::flush() { std::fflush(m_log.get()); }

void RunOutput::finish(const State& s) {
  flush();
  write_final_csv(m_dir + "/final.csv", s);
  fs::remove(checkpoint_path());
  if (m_scene.output.png)
    write_png_picture(m_dir + "/final.png", s, m_scene.system->pinned(), m_scene.edges,
                      m_scene.edge_rest);
}

}  // namespace hooke
