#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "experiments/output/output_dir.hpp"
#include "experiments/output/output_file.hpp"
#include "experiments/run/stop_signals.hpp"

namespace hooke {

/// The output folder of a study (stability, workprecision, resolution, scaling, step-convergence,
/// crosscheck) for the study's whole life: locked (OutputDir), its earlier results and partial
/// results removed at the start, status.txt "running" until finish() says "finished". Each
/// result file is written under NAME.tmp as its rows arrive and renamed to NAME only by finish(),
/// so a complete-looking file is always a complete one. SIGINT / SIGTERM are caught for the
/// study's life and polled between rows with interrupted(): the rows so far are kept as
/// NAME.partial.EXT, status.txt says "stopped", and the study returns 130 / 143. Destroyed
/// without finish() (an error), status.txt says "failed" and no NAME.tmp is left.
class StudyOutput {
 public:
  /// study: the command's name for messages ("stability"); files: the result files it writes.
  StudyOutput(std::string dir, std::string study, const std::vector<std::string>& files);
  ~StudyOutput();
  StudyOutput(const StudyOutput&) = delete;
  StudyOutput& operator=(const StudyOutput&) = delete;

  /// The result file `name` (one of the constructor's files), open for writing.
  OutputFile& file(const std::string& name);
  const std::string& dir() const { return m_dir.path(); }
  /// 0 to go on; after a stop signal, keeps the partial files, says so on stderr (progress:
  /// how far the study got, e.g. "3 of 12 cases") and returns the exit code to stop with.
  int interrupted(const std::string& progress);
  /// Commits every file and marks the folder finished; returns "DIR/{a,b}" for the final line.
  std::string finish(const std::string& summary);

 private:
  std::string m_study;
  OutputDir m_dir;
  std::vector<std::pair<std::string, std::unique_ptr<OutputFile>>> m_files;
  StopSignals m_signals;
  bool m_ended = false;
};

/// "name.partial.ext" for "name.ext": where an interrupted study keeps its rows.
std::string partial_name(const std::string& name);

}  // namespace hooke
