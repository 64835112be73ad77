#include "hooke/distributed/distributed_model.hpp"

#include <petscvec.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <stdexcept>

#include "hooke/linear/petsc/petsc_runtime.hpp"

namespace hooke {

namespace {

/// A failed PETSc or MPI call of the distributed model: a broken run, not bad input.
void check(int code, const char* call) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(PetscErrorCode(code), &text, nullptr);
  throw std::runtime_error(std::string("distributed model: ") + call +
                           " failed: " + (text ? text : "error " + std::to_string(code)));
}

MPI_Comm world() { return PETSC_COMM_WORLD; }

}  // namespace

int mpi_world_size() {
  // Open MPI, MPICH / Hydra and Slurm's PMI name the process count in the environment: read it
  // before starting MPI, so a run outside any launcher never starts it.
  const char* size = nullptr;
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if ((size = std::getenv(name)) != nullptr) break;
  if (size == nullptr || std::atoi(size) <= 1) return 1;
  start_petsc();
  int n = 1;
  MPI_Comm_size(world(), &n);
  return n;
}

/// The piece's Distribution: the ghost exchange is a ghosted PETSc vector of block size 3, owned
/// particles then ghosts in its local form, exactly the local particle order.
class DistributedModel::Exchange final : public Distribution {
 public:
  Exchange(const LocalIndex& index, const std::vector<PetscInt>& ghosts)
      : m_index(index), m_owned(index.num_owned) {
    check(VecCreateGhostBlock(world(), 3, PetscInt(3 * m_owned), PETSC_DECIDE,
                              PetscInt(ghosts.size()), ghosts.data(), &m_vec),
          "VecCreateGhostBlock");
  }
  ~Exchange() override {
    PetscBool finalized = PETSC_FALSE;
    PetscFinalized(&finalized);
    if (!finalized) VecDestroy(&m_vec);
  }
  Exchange(const Exchange&) = delete;
  Exchange& operator=(const Exchange&) = delete;

  const LocalIndex& index() const override { return m_index; }
  double max(double value) const override {
    double out = 0.0;
    check(MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MAX, world()), "MPI_Allreduce");
    return out;
  }
  void complete(VecRef f) const override {
    const Index owned = 3 * m_owned;
    ::Vec local = nullptr;
    PetscScalar* a = nullptr;
    check(VecGetArray(m_vec, &a), "VecGetArray");
    std::copy(f.data(), f.data() + owned, a);
    check(VecRestoreArray(m_vec, &a), "VecRestoreArray");
    check(VecGhostUpdateBegin(m_vec, INSERT_VALUES, SCATTER_FORWARD), "VecGhostUpdateBegin");
    check(VecGhostUpdateEnd(m_vec, INSERT_VALUES, SCATTER_FORWARD), "VecGhostUpdateEnd");
    check(VecGhostGetLocalForm(m_vec, &local), "VecGhostGetLocalForm");
    const PetscScalar* b = nullptr;
    check(VecGetArrayRead(local, &b), "VecGetArrayRead");
    std::copy(b + owned, b + f.size(), f.data() + owned);
    check(VecRestoreArrayRead(local, &b), "VecRestoreArrayRead");
    check(VecGhostRestoreLocalForm(m_vec, &local), "VecGhostRestoreLocalForm");
  }

 private:
  const LocalIndex& m_index;
  Index m_owned;
  ::Vec m_vec = nullptr;
};

DistributedModel::DistributedModel(const MassSpringSystem& global) {
  start_petsc();
  check(MPI_Comm_rank(world(), &m_rank), "MPI_Comm_rank");
  check(MPI_Comm_size(world(), &m_size), "MPI_Comm_size");
  const Index n = global.num_particles();
  if (n < m_size)
    throw SetupError("a system of " + std::to_string(n) + " particles cannot be split between " +
                     std::to_string(m_size) + " processes");
  m_starts.resize(size_t(m_size) + 1);
  for (int r = 0; r <= m_size; ++r) m_starts[size_t(r)] = n * r / m_size;
  for (int r = 0; r < m_size; ++r) {
    m_gather_counts.push_back(int(3 * (m_starts[size_t(r) + 1] - m_starts[size_t(r)])));
    m_gather_displs.push_back(int(3 * m_starts[size_t(r)]));
  }
  const Index begin = m_starts[size_t(m_rank)], end = m_starts[size_t(m_rank) + 1];

  m_index = global.local_index(begin, end);
  // The partition is contiguous: PETSc's block id of a particle is its global id.
  const std::vector<PetscInt> ghost_blocks(m_index.global.begin() + m_index.num_owned,
                                           m_index.global.end());
  m_local = global.localize(m_index);
  m_exchange = std::make_shared<Exchange>(m_index, ghost_blocks);
  m_local->set_distribution(m_exchange);
}

DistributedModel::~DistributedModel() = default;

State DistributedModel::local_state(const State& global) const {
  HOOKE_ASSERT(global.x.size() == 3 * num_global(),
               "local_state of " << global.x.size() / 3 << " particles, system " << num_global());
  State s(m_index.num_local(), global.t);
  for (Index l = 0; l < m_index.num_local(); ++l) {
    const Index g = m_index.global[size_t(l)];
    s.x.segment<3>(3 * l) = global.x.segment<3>(3 * g);
    s.v.segment<3>(3 * l) = global.v.segment<3>(3 * g);
  }
  return s;
}

void DistributedModel::gather(const State& local, State& global) const {
  if (m_rank == 0) {
    if (global.x.size() != 3 * num_global()) global = State(num_global());  // once
    global.t = local.t;
  }
  const int owned = int(3 * m_index.num_owned);
  for (const auto part : {&State::x, &State::v})
    check(MPI_Gatherv((local.*part).data(), owned, MPI_DOUBLE,
                      m_rank == 0 ? (global.*part).data() : nullptr, m_gather_counts.data(),
                      m_gather_displs.data(), MPI_DOUBLE, 0, world()),
          "MPI_Gatherv");
}

DistributedModel::Traffic DistributedModel::traffic() const {
  // The owner of ghost g is the process whose range holds it; ghosts are ascending, so owners are.
  long long here[3] = {m_index.num_local() - m_index.num_owned, 0, 0};
  int last = -1;
  for (Index l = m_index.num_owned; l < m_index.num_local(); ++l) {
    const Index g = m_index.global[size_t(l)];
    const int owner =
        int(std::upper_bound(m_starts.begin(), m_starts.end(), g) - m_starts.begin()) - 1;
    if (owner != last) ++here[1], last = owner;
  }
  here[2] = 24 * here[0];
  long long sum[3] = {0, 0, 0}, most = 0;
  check(MPI_Allreduce(here, sum, 3, MPI_LONG_LONG, MPI_SUM, world()), "MPI_Allreduce");
  check(MPI_Allreduce(&here[0], &most, 1, MPI_LONG_LONG, MPI_MAX, world()), "MPI_Allreduce");
  return {sum[0], sum[1], sum[2], most};
}

bool DistributedModel::all(bool value) const {
  int in = value ? 1 : 0, out = 0;
  check(MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_LAND, world()), "MPI_Allreduce");
  return out != 0;
}

long long DistributedModel::max(long long value) const {
  long long out = 0;
  check(MPI_Allreduce(&value, &out, 1, MPI_LONG_LONG, MPI_MAX, world()), "MPI_Allreduce");
  return out;
}

double DistributedModel::broadcast(double value) const {
  check(MPI_Bcast(&value, 1, MPI_DOUBLE, 0, world()), "MPI_Bcast");
  return value;
}

int DistributedModel::first_with(bool value) const {
  int in = value ? m_rank : INT_MAX, out = INT_MAX;
  check(MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_MIN, world()), "MPI_Allreduce");
  return out == INT_MAX ? -1 : out;
}

std::string DistributedModel::broadcast(const std::string& text, int root) const {
  long long length = m_rank == root ? (long long)text.size() : 0;
  check(MPI_Bcast(&length, 1, MPI_LONG_LONG, root, world()), "MPI_Bcast");
  std::string out = m_rank == root ? text : std::string(size_t(length), '\0');
  check(MPI_Bcast(out.data(), int(length), MPI_CHAR, root, world()), "MPI_Bcast");
  return out;
}

}  // namespace hooke
