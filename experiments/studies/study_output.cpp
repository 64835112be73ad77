#include "experiments/studies/study_output.hpp"

#include <cstdio>

namespace hooke {

std::string partial_name(const std::string& name) {
  const std::size_t dot = name.rfind('.');
  return dot == std::string::npos ? name + ".partial"
                                  : name.substr(0, dot) + ".partial" + name.substr(dot);
}

StudyOutput::StudyOutput(std::string dir, std::string study, const std::vector<std::string>& files)
    : m_study(std::move(study)), m_dir(std::move(dir), "hooke " + m_study) {
  std::vector<std::string> stale = {"status.txt"};
  for (const std::string& f : files) stale.insert(stale.end(), {f, partial_name(f), f + ".tmp"});
  m_dir.remove_files(stale);
  m_dir.set_status("running");
  for (const std::string& f : files)
    m_files.emplace_back(f, std::make_unique<OutputFile>(OutputFile::replace(m_dir.file(f))));
}

StudyOutput::~StudyOutput() {
  if (!m_ended) m_dir.mark_failed("hooke " + m_study + " ended with an error (see its stderr)");
}

OutputFile& StudyOutput::file(const std::string& name) {
  for (auto& [n, f] : m_files)
    if (n == name) return *f;
  throw std::logic_error("StudyOutput: " + name + " is not one of the study's files");
}

int StudyOutput::interrupted(const std::string& progress) {
  const int sig = stop_signal();
  if (sig == 0) return 0;
  std::string kept;
  for (auto& [name, f] : m_files) {
    f->commit_as(m_dir.file(partial_name(name)));
    kept += (kept.empty() ? "" : ", ") + m_dir.file(partial_name(name));
  }
  const std::string what = std::string("interrupted by ") + signal_name(sig) + " after " +
                           progress + "; kept the rows so far in " + kept +
                           " (incomplete); run the study again for complete results";
  m_ended = true;
  try {
    m_dir.set_status("stopped", what);
  } catch (const OutputError&) {  // the partial files are what matters; they are written
  }
  std::fprintf(stderr, "%s: %s\n", m_study.c_str(), what.c_str());
  return exit_code_for_signal(sig);
}

std::string StudyOutput::finish(const std::string& summary) {
  std::string names;
  for (auto& [name, f] : m_files) {
    f->commit();
    names += (names.empty() ? "" : ",") + name;
  }
  m_ended = true;
  m_dir.set_status("finished", summary);
  return dir() + "/{" + names + "}";
}

}  // namespace hooke
