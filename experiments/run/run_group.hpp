#pragma once
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>

#include "experiments/output/vtu_writer.hpp"
#include "hooke/distributed/distributed_model.hpp"  // declarations only: no PETSc needed
#include "hooke/model/mass_spring_system.hpp"
#include "hooke/model/state.hpp"

namespace hooke {

/// Thrown on the processes of an MPI run other than the one that met an error, so that every
/// process stops with the same exit code while only rank 0 prints the message (main catches it
/// and exits with code() silently).
class PeerFailure : public std::exception {
 public:
  explicit PeerFailure(int code) : m_code(code) {}
  int code() const { return m_code; }
  const char* what() const noexcept override { return "another process of the run failed"; }

 private:
  int m_code;
};

/// Rank of this process in an MPI launch, read from the launcher's environment (0 outside one),
/// without starting MPI: main prints errors on rank 0 only.
int launched_rank();
/// Number of processes of this MPI launch, from the launcher's environment (1 outside one).
int launched_size();

/// The processes one `hooke run` spans (issue 17): this process alone (a serial run), or every
/// process of an MPI launch, each stepping its piece of the system (DistributedModel). The run loop
/// asks it for what the processes must agree on: the whole state at output times (gathered on
/// rank 0, which alone prints and writes the run's files but for the pieces each process writes
/// of frames and checkpoints), the step's outcome, stop requests and the
/// figures rank 0 decides. In a serial run every call is trivial. Calls marked collective must be
/// made by all processes together.
class RunGroup {
 public:
  /// A serial run.
  RunGroup();
  /// The processes of this MPI launch if there are more than one (mpi_world_size), splitting
  /// `global` between them; else a serial run. Throws SetupError for a system that cannot be
  /// split, and for a build without PETSc under a multi-process launch.
  static std::unique_ptr<RunGroup> for_launch(const MassSpringSystem& global);
  ~RunGroup();

  bool distributed() const { return m_model != nullptr; }
  /// Rank 0, or the process of a serial run: the one that writes files and prints.
  bool root() const { return m_rank == 0; }
  int rank() const { return m_rank; }
  int size() const;
  /// The system this process steps: its piece of `global`, or `global` itself.
  const MassSpringSystem& stepped(const MassSpringSystem& global) const;
  /// This process's part of a state of the whole system.
  State local_state(const State& global) const;
  /// The whole system's state from this process's `local` one: `local` itself in a serial run; on
  /// rank 0 of a distributed run, the gathered state (valid until the next call), elsewhere
  /// `local`. Collective.
  const State& whole(const State& local);
  /// What this process writes of a frame of the whole system's `mesh` (make_frame_piece). Only
  /// for a distributed run.
  FramePiece frame_piece(const FrameMesh& mesh) const;
  /// The ghost traffic of one exchange (DistributedModel::Traffic); all zero in a serial run.
  /// Collective.
  using Traffic = DistributedModel::Traffic;
  Traffic traffic() const;
  /// True if `value` is true everywhere. Collective.
  bool all(bool value) const;
  /// The largest value. Collective.
  long long max(long long value) const;
  /// Rank 0's value. Collective.
  double from_root(double value) const;
  /// The lowest rank where `here` is true, and that process's `text`, everywhere; -1 and "" if
  /// none. Collective.
  int first(bool here, std::string& text) const;
  /// Runs f() on rank 0 only; if it throws there, rethrows on rank 0 and throws PeerFailure(code)
  /// elsewhere (code: what main returns for the exception, 2 for InputError, else 1). Collective.
  template <typename F>
  void on_root(F&& f) {
    std::exception_ptr error;
    int code = 0;
    if (root()) {
      try {
        f();
      } catch (...) {
        error = std::current_exception();
        code = exit_code_of(error);
      }
    }
    code = int(max(code));
    if (error) std::rethrow_exception(error);
    if (code != 0) throw PeerFailure(code);
  }
  /// Runs f() on every process (e.g. each writing its piece of a frame). If it throws anywhere,
  /// every process stops together: rank 0 rethrows its own exception, or else throws
  /// std::runtime_error with the message of the lowest rank that failed (so that rank 0 alone
  /// says why, as for its own errors), and the others throw PeerFailure with the exit code main
  /// gives that exception. Collective.
  template <typename F>
  void on_every(F&& f) {
    std::exception_ptr error;
    std::string text;
    int code = 0;
    try {
      f();
    } catch (const std::exception& e) {
      error = std::current_exception();
      text = e.what();
    } catch (...) {
      error = std::current_exception();
      text = "unknown error";
    }
    if (error) code = exit_code_of(error);
    code = int(max(code));
    if (code == 0) return;
    first(error != nullptr, text);
    if (!root()) throw PeerFailure(code);
    if (error) std::rethrow_exception(error);
    throw std::runtime_error(text);
  }

 private:
  static int exit_code_of(const std::exception_ptr& e);
  int m_rank = 0;
  std::unique_ptr<DistributedModel> m_model;
  State m_whole;
};

}  // namespace hooke
