#include "experiments/run/run_group.hpp"

#include <algorithm>
#include <cstdlib>

#include "hooke/config.hpp"
#include "problems/input_error.hpp"

namespace hooke {

int launched_rank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
    if (const char* rank = std::getenv(name)) return std::atoi(rank);
  return 0;
}

int launched_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* size = std::getenv(name)) return std::max(1, std::atoi(size));
  return 1;
}

RunGroup::RunGroup() = default;
RunGroup::~RunGroup() = default;

std::unique_ptr<RunGroup> RunGroup::for_launch(const MassSpringSystem& global) {
  auto group = std::make_unique<RunGroup>();
#if HOOKE_WITH_PETSC
  if (mpi_world_size() > 1) {
    group->m_model = std::make_unique<DistributedModel>(global);
    group->m_rank = group->m_model->rank();
  }
#else
  (void)global;
  if (launched_size() > 1)
    throw SetupError(
        "this hooke was built without PETSc (HOOKE_WITH_PETSC=OFF), which runs one simulation "
        "across MPI processes: build it with petsc-dev installed, or run one process");
#endif
  return group;
}

#if HOOKE_WITH_PETSC
int RunGroup::size() const { return m_model ? m_model->size() : 1; }
const MassSpringSystem& RunGroup::stepped(const MassSpringSystem& global) const {
  return m_model ? m_model->local() : global;
}
State RunGroup::local_state(const State& global) const {
  return m_model ? m_model->local_state(global) : global;
}
const State& RunGroup::whole(const State& local) {
  if (!m_model) return local;
  m_model->gather(local, m_whole);
  return root() ? m_whole : local;
}
FramePiece RunGroup::frame_piece(const FrameMesh& mesh) const {
  HOOKE_ASSERT(m_model, "a frame piece of a serial run");
  return make_frame_piece(mesh, m_model->index(), m_model->starts(), m_rank);
}
RunGroup::Traffic RunGroup::traffic() const { return m_model ? m_model->traffic() : Traffic{}; }
bool RunGroup::all(bool value) const { return m_model ? m_model->all(value) : value; }
long long RunGroup::max(long long value) const { return m_model ? m_model->max(value) : value; }
double RunGroup::from_root(double value) const {
  return m_model ? m_model->broadcast(value) : value;
}
int RunGroup::first(bool here, std::string& text) const {
  if (!m_model) return here ? 0 : (text.clear(), -1);
  const int r = m_model->first_with(here);
  text = r < 0 ? std::string() : m_model->broadcast(text, r);
  return r;
}
#else
int RunGroup::size() const { return 1; }
const MassSpringSystem& RunGroup::stepped(const MassSpringSystem& global) const { return global; }
State RunGroup::local_state(const State& global) const { return global; }
const State& RunGroup::whole(const State& local) { return local; }
FramePiece RunGroup::frame_piece(const FrameMesh&) const {
  HOOKE_ASSERT(false, "a frame piece of a serial run");
  return {};
}
RunGroup::Traffic RunGroup::traffic() const { return {}; }
bool RunGroup::all(bool value) const { return value; }
long long RunGroup::max(long long value) const { return value; }
double RunGroup::from_root(double value) const { return value; }
int RunGroup::first(bool here, std::string& text) const {
  if (!here) text.clear();
  return here ? 0 : -1;
}
#endif

int RunGroup::exit_code_of(const std::exception_ptr& e) {
  try {
    std::rethrow_exception(e);
  } catch (const InputError&) {
    return 2;
  } catch (const PeerFailure& p) {
    return p.code();
  } catch (...) {
    return 1;
  }
}

}  // namespace hooke
