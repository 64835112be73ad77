#include "hooke/linear/petsc/petsc_solver.hpp"

#include <petscksp.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "hooke/linear/petsc/petsc_runtime.hpp"
#include "hooke/parallel/loops.hpp"

namespace hooke {

namespace {

/// A PETSc call that failed: what() is PETSc's own first message (e.g. "Unknown type. Check for
/// miss-spelling or missing package: ... no_such_pc").
class PetscFailure : public std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The first message of the error being raised, recorded by the handler below.
thread_local std::string g_first_message;

extern "C" PetscErrorCode record_error(MPI_Comm, int, const char*, const char*, PetscErrorCode n,
                                       PetscErrorType p, const char* mess, void*) {
  if (p == PETSC_ERROR_INITIAL) g_first_message = mess ? mess : "";
  return n;
}

/// Clears the recorded message before a sequence of PETSc calls. The handler itself is pushed
/// once, when PETSc is initialised (pushing per call would allocate in the step loop): every
/// PETSc error in the process returns its code with its message recorded, never printing or
/// aborting (PetscReturnErrorHandler semantics).
class ErrorScope {
 public:
  ErrorScope() { g_first_message.clear(); }
};

void check(PetscErrorCode ierr, const char* call) {
  if (ierr == 0) return;
  std::string text = g_first_message;
  if (text.empty()) {
    const char* generic = nullptr;
    PetscErrorMessage(ierr, &generic, nullptr);
    text = generic ? generic : "error " + std::to_string(int(ierr));
  }
  throw PetscFailure(std::string(call) + ": " + text);
}

/// True if MPI allows calls from several threads at once (MPI_THREAD_MULTIPLE): the concurrent
/// split (ConcurrentSplit) calls hypre, which may call MPI, from two threads.
bool g_mpi_thread_multiple = false;

/// PETSc is initialised once, on first use, with no arguments (PETSC_OPTIONS is read by each
/// solver itself, see Impl::options), and finalised at exit; MPI is started first, asking for
/// MPI_THREAD_MULTIPLE, unless the host program started it.
void ensure_petsc() {
  static const bool done = [] {
    int mpi_up = 0;
    MPI_Initialized(&mpi_up);
    int provided = MPI_THREAD_SINGLE;
    if (!mpi_up) {
      // Started here rather than by PetscInitialize (which asks for a single thread), and
      // finalised after PETSc (atexit handlers run in reverse order of registration).
      if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_MULTIPLE, &provided) != MPI_SUCCESS)
        throw std::runtime_error("MPI_Init_thread failed");
      std::atexit([] {
        int finalized = 0;
        MPI_Finalized(&finalized);
        if (!finalized) MPI_Finalize();
      });
    } else {
      MPI_Query_thread(&provided);
    }
    g_mpi_thread_multiple = provided >= MPI_THREAD_MULTIPLE;
    PetscBool already = PETSC_FALSE;
    PetscInitialized(&already);
    if (!already) {
      if (PetscInitializeNoArguments() != 0) throw std::runtime_error("PetscInitialize failed");
      // PETSc's own handlers for SIGSEGV, SIGTERM, ... would replace the host's (hooke run's
      // checkpoint on SIGTERM, the sanitizers' reports).
      PetscPopSignalHandler();
      std::atexit([] { PetscFinalize(); });
    }
    PetscPushErrorHandler(record_error, nullptr);
    return true;
  }();
  (void)done;
}

/// True if PETSc solves span the processes of an MPI run (a distributed system's solver exists):
/// -log_view's summary is then collective, printed once by rank 0.
bool g_log_world = false;

/// Starts PETSc's event logging and prints its summary on stdout at exit (before PetscFinalize,
/// whose own atexit handler was registered first and so runs after this one): this process's, or
/// in an MPI run the whole run's, once, by rank 0.
void log_view_at_exit(bool world) {
  g_log_world = g_log_world || world;
  static const bool done = [] {
    PetscLogDefaultBegin();
    std::atexit(
        [] { PetscLogView(g_log_world ? PETSC_VIEWER_STDOUT_WORLD : PETSC_VIEWER_STDOUT_SELF); });
    return true;
  }();
  (void)done;
}

bool finalized() {
  PetscBool f = PETSC_FALSE;
  PetscFinalized(&f);
  return f == PETSC_TRUE;
}

/// Makes `options` the database PETSc objects read while this is alive.
class OptionsScope {
 public:
  explicit OptionsScope(PetscOptions options) { check(PetscOptionsPush(options), "options"); }
  ~OptionsScope() { PetscOptionsPop(); }
  OptionsScope(const OptionsScope&) = delete;
  OptionsScope& operator=(const OptionsScope&) = delete;
};

/// y = A x for the MATSHELL operator of the Krylov method: hooke's own product on A's arrays,
/// row-parallel over the threads hooke runs on (PETSc's AIJ product is serial within a rank).
/// A is symmetric, so its compressed columns are read as compressed rows.
extern "C" PetscErrorCode shell_mult(Mat shell, ::Vec in, ::Vec out) {
  const SparseMatrix* A = nullptr;
  PetscCall(MatShellGetContext(shell, &A));
  const PetscScalar* x = nullptr;
  PetscScalar* y = nullptr;
  PetscCall(VecGetArrayRead(in, &x));
  PetscCall(VecGetArray(out, &y));
  const int* start = A->outerIndexPtr();
  const int* col = A->innerIndexPtr();
  const double* a = A->valuePtr();
  parallel_for(A->rows(), 4096, [&](long long i) {
    double s = 0.0;
    for (int k = start[i]; k < start[i + 1]; ++k) s += a[k] * x[col[k]];
    y[i] = s;
  });
  PetscCall(VecRestoreArray(out, &y));
  PetscCall(VecRestoreArrayRead(in, &x));
  return 0;
}

/// The default preconditioner's three splits (x, y and z: an additive PCFIELDSPLIT with block size
/// 3 and one preconditioner application per split) applied concurrently on hooke's threads: the
/// splits are independent, and hypre's V-cycle is serial (Debian's hypre has no OpenMP), so
/// PCFIELDSPLIT, which applies them one after another, leaves the second core idle for most of a
/// Krylov iteration. The PCFIELDSPLIT object still owns the splits (their options, set-up and
/// reuse); this PCSHELL only replaces its apply. Each split's result is the same whichever thread
/// computes it, so results do not depend on the thread count.
struct ConcurrentSplit {
  PC split = nullptr;  // the PCFIELDSPLIT (a reference held here)
  PC sub[3] = {nullptr, nullptr, nullptr};
  ::Vec in[3] = {nullptr, nullptr, nullptr}, out[3] = {nullptr, nullptr, nullptr};

  void destroy() {
    for (int i = 0; i < 3; ++i) {
      if (in[i]) VecDestroy(&in[i]);
      if (out[i]) VecDestroy(&out[i]);
      sub[i] = nullptr;
    }
    if (split) PCDestroy(&split);
  }
};

extern "C" PetscErrorCode split_setup(PC pc) {
  ConcurrentSplit* c = nullptr;
  PetscCall(PCShellGetContext(pc, &c));
  Mat A = nullptr, P = nullptr;
  PetscCall(PCGetOperators(pc, &A, &P));
  PetscCall(PCSetOperators(c->split, A, P));
  PetscCall(PCSetUp(c->split));
  // The splits' own set-up (hypre's hierarchies), which PCFIELDSPLIT leaves to PCSetUpOnBlocks: a
  // PCSHELL has no blocks, so it would otherwise happen inside the first apply, on two threads.
  PetscCall(PCSetUpOnBlocks(c->split));
  return 0;
}

extern "C" PetscErrorCode split_apply(PC pc, ::Vec x, ::Vec y) {
  ConcurrentSplit* c = nullptr;
  PetscCall(PCShellGetContext(pc, &c));
  PetscInt m = 0;
  PetscCall(VecGetLocalSize(c->in[0], &m));
  const PetscScalar* xa = nullptr;
  PetscCall(VecGetArrayRead(x, &xa));
  for (int i = 0; i < 3; ++i) {
    PetscScalar* v = nullptr;
    PetscCall(VecGetArray(c->in[i], &v));
    for (PetscInt k = 0; k < m; ++k) v[k] = xa[3 * k + i];
    PetscCall(VecRestoreArray(c->in[i], &v));
  }
  PetscCall(VecRestoreArrayRead(x, &xa));
  // PCApply sets a preconditioner up first if its matrix changed: never on the worker threads
  // (PETSc and hypre set-ups are not thread-safe), so here, one after another (a no-op when the
  // splits are current, as split_setup leaves them).
  for (int i = 0; i < 3; ++i) PetscCall(PCSetUp(c->sub[i]));
  PetscErrorCode err[3] = {0, 0, 0};
  std::string message[3];  // an error's message is recorded on the thread that raised it
  auto run = [&](int i) {
    err[i] = PCApply(c->sub[i], c->in[i], c->out[i]);
    if (err[i] != 0) message[i] = g_first_message;
  };
  // PETSc's event log is not thread-safe: with -log_view the splits run one after another.
  PetscBool logging = PETSC_FALSE;
  PetscCall(PetscLogIsActive(&logging));
  if (run_parallel(3, 2) && !logging) {
    // Dynamic: whichever thread finishes its split first takes the third, so the two costly
    // splits of a cloth (the two in-plane coordinates) overlap whatever its orientation.
#pragma omp parallel for num_threads(2) schedule(dynamic, 1)
    for (int i = 0; i < 3; ++i) run(i);
  } else {
    for (int i = 0; i < 3; ++i) run(i);
  }
  for (int i = 0; i < 3; ++i)
    if (err[i] != 0) {
      g_first_message = message[i];
      return err[i];
    }
  PetscScalar* ya = nullptr;
  PetscCall(VecGetArray(y, &ya));
  for (int i = 0; i < 3; ++i) {
    const PetscScalar* v = nullptr;
    PetscCall(VecGetArrayRead(c->out[i], &v));
    for (PetscInt k = 0; k < m; ++k) ya[3 * k + i] = v[k];
    PetscCall(VecRestoreArrayRead(c->out[i], &v));
  }
  PetscCall(VecRestoreArray(y, &ya));
  return 0;
}

extern "C" PetscErrorCode split_view(PC pc, PetscViewer viewer) {
  ConcurrentSplit* c = nullptr;
  PetscCall(PCShellGetContext(pc, &c));
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "hooke: the additive fieldsplit below, its 3 splits applied concurrently\n"));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PCView(c->split, viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  return 0;
}

/// True if pc is an additive PCFIELDSPLIT of a block-size-3 matrix into the strides x, y and z,
/// each split one preconditioner application (KSPPREONLY): the case ConcurrentSplit applies.
bool is_coordinate_split(PC pc) {
  PetscBool is = PETSC_FALSE;
  check(PetscObjectTypeCompare(reinterpret_cast<PetscObject>(pc), PCFIELDSPLIT, &is),
        "PetscObjectTypeCompare");
  if (!is) return false;
  PCCompositeType type;
  check(PCFieldSplitGetType(pc, &type), "PCFieldSplitGetType");
  if (type != PC_COMPOSITE_ADDITIVE) return false;
  PetscInt count = 0;
  KSP* subs = nullptr;
  check(PCFieldSplitGetSubKSP(pc, &count, &subs), "PCFieldSplitGetSubKSP");
  bool ok = count == 3;
  for (PetscInt i = 0; ok && i < count; ++i) {
    PetscBool preonly = PETSC_FALSE;
    check(PetscObjectTypeCompare(reinterpret_cast<PetscObject>(subs[i]), KSPPREONLY, &preonly),
          "PetscObjectTypeCompare");
    IS is_i = nullptr;
    check(PCFieldSplitGetISByIndex(pc, i, &is_i), "PCFieldSplitGetISByIndex");
    PetscBool stride = PETSC_FALSE;
    check(PetscObjectTypeCompare(reinterpret_cast<PetscObject>(is_i), ISSTRIDE, &stride),
          "PetscObjectTypeCompare");
    PetscInt first = -1, step = 0;
    if (stride) check(ISStrideGetInfo(is_i, &first, &step), "ISStrideGetInfo");
    ok = preonly && stride && first == i && step == 3;
  }
  PetscFree(subs);
  return ok;
}

}  // namespace

void start_petsc() { ensure_petsc(); }

struct PetscSolver::Impl {
  PetscSolverOptions settings;
  PetscOptions options = nullptr;  // this solver's own database: defaults, scene, environment
  Mat M = nullptr;                 // A for the preconditioner (AIJ on A's arrays)
  Mat shell = nullptr;             // A for the Krylov method (MATSHELL: hooke's threaded product)
  KSP ksp = nullptr;
  ::Vec b = nullptr, x = nullptr, coords = nullptr;  // PETSc vectors (hooke::Vec is Eigen's)
  ConcurrentSplit split;  // in use if split.split (adopt_concurrent_split)
  const SparseMatrix* A = nullptr;
  // The arrays M stores (wrap()): A's own, so values assembled into A are M's values.
  const void* wrapped[3] = {nullptr, nullptr, nullptr};
  std::vector<PetscInt> rows, cols;  // only if PetscInt is not Eigen's index type (64-bit PETSc)
  Index n = 0;
  // A distributed system (settings.distribution): M is an MPI AIJ matrix of this process's owned
  // rows, the first n_owned of A (see distribute()), in compressed rows with global columns sorted
  // within each row (csr_start, csr_col); entry p of them is A's entry csr_from[p], copied into
  // csr_value by factor().
  Index n_owned = 0;
  std::vector<PetscInt> csr_start, csr_col;
  std::vector<int> csr_from;
  std::vector<double> csr_value;
  hooke::Vec coordinates;  // positions of the unknowns (set_coordinates), for the near-null space
  bool user_rtol = false, user_max_it = false, user_divtol = false;
  bool view_pending = false;      // -ksp_view was given: KSPView after the first solve
  bool rigid_body_modes = false;  // -hooke_rigid_body_modes: near-null space from the coordinates
  double setup_cost = kSetupCostInIterations;  // -hooke_setup_cost
  // Renewal rule (see the class comment), in Krylov iterations.
  double cost_since = 0.0;
  int solves_since = 0, last_iterations = 0;
  bool rebuild = true;
  long long builds = 0;

  void destroy() {
    if (finalized()) return;  // PETSc is gone (exit): the process frees everything
    if (ksp) KSPDestroy(&ksp);
    split.destroy();
    if (M) MatDestroy(&M);
    if (shell) MatDestroy(&shell);
    for (::Vec* v : {&b, &x, &coords})
      if (*v) VecDestroy(v);
    if (options) PetscOptionsDestroy(&options);
  }

  /// Back to the state before analyze(), keeping the settings and the coordinates.
  void reset() {
    destroy();
    ksp = nullptr;
    M = nullptr;
    shell = nullptr;
    b = x = coords = nullptr;
    options = nullptr;
    A = nullptr;
    std::fill(std::begin(wrapped), std::end(wrapped), nullptr);
    n = 0;
    cost_since = 0.0;
    solves_since = last_iterations = 0;
    rebuild = true;
    builds = 0;
    view_pending = false;
  }

  void make_options() {
    check(PetscOptionsCreate(&options), "PetscOptionsCreate");
    check(PetscOptionsInsertString(options, kPetscDefaultOptions), "default options");
    check(PetscOptionsInsertString(options, settings.options.c_str()), "petsc_options");
    if (const char* env = std::getenv("PETSC_OPTIONS"))
      check(PetscOptionsInsertString(options, env), "PETSC_OPTIONS");
    PetscBool has = PETSC_FALSE;
    check(PetscOptionsHasName(options, nullptr, "-ksp_rtol", &has), "options");
    user_rtol = has == PETSC_TRUE;
    check(PetscOptionsHasName(options, nullptr, "-ksp_max_it", &has), "options");
    user_max_it = has == PETSC_TRUE;
    check(PetscOptionsHasName(options, nullptr, "-ksp_divtol", &has), "options");
    user_divtol = has == PETSC_TRUE;
    PetscBool rigid = PETSC_FALSE;
    check(PetscOptionsGetBool(options, nullptr, "-hooke_rigid_body_modes", &rigid, nullptr),
          "-hooke_rigid_body_modes");
    rigid_body_modes = rigid == PETSC_TRUE;
    PetscReal cost = kSetupCostInIterations;
    check(PetscOptionsGetReal(options, nullptr, "-hooke_setup_cost", &cost, nullptr),
          "-hooke_setup_cost");
    if (!(cost >= 0.0))
      throw PetscFailure("-hooke_setup_cost " + std::to_string(cost) +
                         ": the cost of a preconditioner set-up in Krylov iterations must be >= 0");
    setup_cost = double(cost);
    // -ksp_view would print at every solve (every step): taken out, printed once by solve().
    check(PetscOptionsHasName(options, nullptr, "-ksp_view", &has), "options");
    view_pending = has == PETSC_TRUE && settings.view;
    if (has) check(PetscOptionsClearValue(options, "-ksp_view"), "options");
    // -log_view: PETSc's performance summary of the whole process, printed once at exit.
    check(PetscOptionsHasName(options, nullptr, "-log_view", &has), "options");
    if (has) {
      check(PetscOptionsClearValue(options, "-log_view"), "options");
      if (settings.view) log_view_at_exit(settings.distribution != nullptr);
    }
  }

  /// Makes M a PETSc AIJ matrix on A's own arrays (no copy: for a symmetric A, Eigen's compressed
  /// columns are the compressed rows PETSc stores), of block size 3, marked SPD. A must outlive M
  /// or the next wrap(); the LinearSolver contract keeps it alive until the next factor().
  void wrap(const SparseMatrix& A) {
    static_assert(std::is_same_v<PetscScalar, double>, "PETSc must be built with real doubles");
    PetscInt *r = nullptr, *c = nullptr;
    if constexpr (std::is_same_v<PetscInt, SparseMatrix::StorageIndex>) {
      r = const_cast<PetscInt*>(A.outerIndexPtr());
      c = const_cast<PetscInt*>(A.innerIndexPtr());
    } else {
      rows.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.rows() + 1);
      cols.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
      r = rows.data();
      c = cols.data();
    }
    for (Mat* old : {&M, &shell})
      if (*old) MatDestroy(old);
    check(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, PetscInt(n), PetscInt(n), r, c,
                                    const_cast<double*>(A.valuePtr()), &M),
          "MatCreateSeqAIJWithArrays");
    if (n % 3 == 0) check(MatSetBlockSize(M, 3), "MatSetBlockSize");
    check(MatSetOption(M, MAT_SPD, PETSC_TRUE), "MatSetOption");
    check(MatCreateShell(PETSC_COMM_SELF, PetscInt(n), PetscInt(n), PetscInt(n), PetscInt(n),
                         const_cast<SparseMatrix*>(&A), &shell),
          "MatCreateShell");
    check(MatShellSetOperation(shell, MATOP_MULT, reinterpret_cast<void (*)(void)>(shell_mult)),
          "MatShellSetOperation");
    if (n % 3 == 0) check(MatSetBlockSize(shell, 3), "MatSetBlockSize");
    check(MatSetOption(shell, MAT_SPD, PETSC_TRUE), "MatSetOption");
    wrapped[0] = A.outerIndexPtr();
    wrapped[1] = A.innerIndexPtr();
    wrapped[2] = A.valuePtr();
  }

  bool wraps(const SparseMatrix& A) const {
    return wrapped[0] == A.outerIndexPtr() && wrapped[1] == A.innerIndexPtr() &&
           wrapped[2] == A.valuePtr();
  }

  bool distributed() const { return settings.distribution != nullptr; }
  /// What the Krylov method multiplies by: hooke's threaded product on one process, PETSc's MPI
  /// AIJ product across processes.
  Mat krylov_operator() const { return distributed() ? M : shell; }

  /// A distributed system's M (analyze): an MPI AIJ matrix of block size 3 over the process's
  /// owned rows, preallocated from A's pattern. Owned particles come first in the piece (A's first
  /// n_owned rows and columns) and a piece holds every spring of an owned particle, so their rows
  /// are complete; A is symmetric, so its compressed columns are those rows. Global indices follow
  /// the distribution's global ids, whose contiguous ranges per rank are PETSc's ownership ranges.
  void distribute(const SparseMatrix& A) {
    const LocalIndex& index = settings.distribution->index();
    n_owned = 3 * index.num_owned;
    const auto global = [&](Index q) { return PetscInt(3 * index.global[size_t(q / 3)] + q % 3); };
    const int* start = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const size_t nnz = size_t(start[n_owned]);
    csr_start.assign(start, start + n_owned + 1);
    csr_col.resize(nnz);
    csr_from.resize(nnz);
    csr_value.assign(nnz, 0.0);
    for (Index r = 0; r < n_owned; ++r) {
      std::iota(csr_from.begin() + start[r], csr_from.begin() + start[r + 1], start[r]);
      std::sort(csr_from.begin() + start[r], csr_from.begin() + start[r + 1],
                [&](int a, int b) { return global(inner[a]) < global(inner[b]); });
      for (int p = start[r]; p < start[r + 1]; ++p)
        csr_col[size_t(p)] = global(inner[csr_from[size_t(p)]]);
    }
    check(MatCreate(PETSC_COMM_WORLD, &M), "MatCreate");
    check(MatSetSizes(M, PetscInt(n_owned), PetscInt(n_owned), PETSC_DETERMINE, PETSC_DETERMINE),
          "MatSetSizes");
    check(MatSetBlockSize(M, 3), "MatSetBlockSize");
    check(MatSetType(M, MATMPIAIJ), "MatSetType");
    check(MatMPIAIJSetPreallocationCSR(M, csr_start.data(), csr_col.data(), nullptr),
          "MatMPIAIJSetPreallocationCSR");
    check(MatSetOption(M, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "MatSetOption");
    check(MatSetOption(M, MAT_NO_OFF_PROC_ENTRIES, PETSC_TRUE), "MatSetOption");
    check(MatSetOption(M, MAT_SPD, PETSC_TRUE), "MatSetOption");
    for (::Vec* v : {&b, &x})
      check(VecCreateMPIWithArray(PETSC_COMM_WORLD, 3, PetscInt(n_owned), PETSC_DECIDE, nullptr, v),
            "VecCreateMPIWithArray");
  }

  /// The 2-norm of a distributed system's vector over the owned rows of every process.
  double owned_norm(ConstRef v) {
    check(VecPlaceArray(b, v.data()), "VecPlaceArray");
    PetscReal norm = 0.0;
    const PetscErrorCode ierr = VecNorm(b, NORM_2, &norm);
    VecResetArray(b);
    check(ierr, "VecNorm");
    return double(norm);
  }

  /// A distributed system's new values (factor): A's owned rows into M, in M's order.
  void copy_owned_rows(const SparseMatrix& A) {
    const double* a = A.valuePtr();
    parallel_ranges(Index(csr_value.size()), [&](long long lo, long long hi) {
      for (long long p = lo; p < hi; ++p) csr_value[size_t(p)] = a[csr_from[size_t(p)]];
    });
    check(MatUpdateMPIAIJWithArray(M, csr_value.data()), "MatUpdateMPIAIJWithArray");
  }

  /// After the first set-up: if the KSP's preconditioner is the coordinate split (the default)
  /// and there are threads to share it, the splits are applied concurrently from now on
  /// (ConcurrentSplit): the PCFIELDSPLIT moves behind a PCSHELL that the KSP uses instead.
  void adopt_concurrent_split() {
    if (split.split || distributed() || !run_parallel(3, 2) || !g_mpi_thread_multiple) return;
    PC pc = nullptr;
    check(KSPGetPC(ksp, &pc), "KSPGetPC");
    if (!is_coordinate_split(pc)) return;
    PetscInt count = 0;
    KSP* subs = nullptr;
    check(PCFieldSplitGetSubKSP(pc, &count, &subs), "PCFieldSplitGetSubKSP");
    for (int i = 0; i < 3; ++i) {
      PetscErrorCode ierr = KSPGetPC(subs[i], &split.sub[i]);
      if (ierr == 0) ierr = VecCreateSeq(PETSC_COMM_SELF, PetscInt(n / 3), &split.in[i]);
      if (ierr == 0) ierr = VecCreateSeq(PETSC_COMM_SELF, PetscInt(n / 3), &split.out[i]);
      if (ierr != 0) PetscFree(subs);
      check(ierr, "concurrent split");
    }
    PetscFree(subs);
    check(PetscObjectReference(reinterpret_cast<PetscObject>(pc)), "PetscObjectReference");
    split.split = pc;
    PC shell_pc = nullptr;
    check(PCCreate(PETSC_COMM_SELF, &shell_pc), "PCCreate");
    PetscErrorCode ierr = PCSetType(shell_pc, PCSHELL);
    if (ierr == 0) ierr = PCShellSetContext(shell_pc, &split);
    if (ierr == 0) ierr = PCShellSetName(shell_pc, "hooke concurrent fieldsplit");
    if (ierr == 0) ierr = PCShellSetSetUp(shell_pc, split_setup);
    if (ierr == 0) ierr = PCShellSetApply(shell_pc, split_apply);
    if (ierr == 0) ierr = PCShellSetView(shell_pc, split_view);
    if (ierr == 0) ierr = KSPSetPC(ksp, shell_pc);  // the KSP takes its own reference
    PCDestroy(&shell_pc);
    check(ierr, "concurrent split");
    check(KSPSetOperators(ksp, shell, M), "KSPSetOperators");
    check(KSPSetUp(ksp), "KSPSetUp");  // the shell's set-up: the split is already set up
  }

  /// The rigid-body modes of the free particles at `coordinates` as A's near-null space.
  void near_null_space() {
    if (!rigid_body_modes || coordinates.size() != n || n % 3 != 0) return;
    const Index rows = distributed() ? n_owned : n;
    if (!coords) {
      if (distributed())
        check(VecCreateMPI(PETSC_COMM_WORLD, PetscInt(rows), PETSC_DECIDE, &coords),
              "VecCreateMPI");
      else
        check(VecCreateSeq(PETSC_COMM_SELF, PetscInt(rows), &coords), "VecCreateSeq");
    }
    check(VecSetBlockSize(coords, 3), "VecSetBlockSize");
    PetscScalar* c = nullptr;
    check(VecGetArray(coords, &c), "VecGetArray");
    std::memcpy(c, coordinates.data(), sizeof(double) * size_t(rows));
    check(VecRestoreArray(coords, &c), "VecRestoreArray");
    MatNullSpace nsp = nullptr;
    check(MatNullSpaceCreateRigidBody(coords, &nsp), "MatNullSpaceCreateRigidBody");
    check(MatSetNearNullSpace(M, nsp), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&nsp);
  }
};

std::string petsc_options_problem(const std::string& options) {
  // An 8 x 8 grid of particles joined to their neighbours (M + the graph Laplacian per
  // coordinate): SPD with 3 x 3 blocks like the real systems, and large enough for GAMG to build
  // levels, so that options of the level smoothers are read.
  constexpr int g = 8, np = g * g, n = 3 * np;
  std::vector<Eigen::Triplet<double>> t;
  Vec x(n);
  for (int p = 0; p < np; ++p) {
    x.segment<3>(3 * p) = Vec3(p % g, p / g, 0.0);
    const int nbrs[2] = {p % g + 1 < g ? p + 1 : -1, p + g < np ? p + g : -1};
    for (int c = 0; c < 3; ++c) t.emplace_back(3 * p + c, 3 * p + c, 1e-3);
    for (int q : nbrs)
      if (q >= 0)
        for (int c = 0; c < 3; ++c) {
          t.emplace_back(3 * p + c, 3 * p + c, 1.0);
          t.emplace_back(3 * q + c, 3 * q + c, 1.0);
          t.emplace_back(3 * p + c, 3 * q + c, -1.0);
          t.emplace_back(3 * q + c, 3 * p + c, -1.0);
        }
  }
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  // PETSc skips a leading word without a dash silently ("ksp_type cg" sets nothing).
  std::istringstream words(options);
  if (std::string first; words >> first && first[0] != '-')
    return "petsc: '" + first + "' is not an option: PETSc options start with '-' (-ksp_type cg)";
  PetscSolverOptions o;
  o.options = options;
  o.view = false;
  try {
    PetscSolver s(o);
    s.set_coordinates(x);
    if (const LinearSummary r = s.analyze(A); r.status == Status::Fatal) return r.message;
    if (const LinearSummary r = s.factor(A); r.status == Status::Fatal) return r.message;
    Vec b = Vec::Ones(n), y = Vec::Zero(n);
    const LinearSummary r = s.solve(b, y, LinearSolveOptions{});
    if (r.status == Status::Fatal) return r.message;
    if (const std::string unused = s.unused_options(); !unused.empty())
      return "petsc: no PETSc object read " + unused +
             " (misspelt, or an option of a type not chosen); the options in force come from the "
             "defaults '" +
             kPetscDefaultOptions + "', petsc_options and PETSC_OPTIONS";
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

PetscSolver::PetscSolver(PetscSolverOptions options) : m(std::make_unique<Impl>()) {
  ensure_petsc();
  m->settings = std::move(options);
}

PetscSolver::~PetscSolver() { m->destroy(); }

long long PetscSolver::factorizations() const { return m->builds; }

std::string PetscSolver::unused_options() const {
  if (!m->options) return "";
  PetscInt count = 0;
  char **names = nullptr, **values = nullptr;
  if (PetscOptionsLeftGet(m->options, &count, &names, &values) != 0) return "";
  std::istringstream defaults(kPetscDefaultOptions);
  std::vector<std::string> ours;
  for (std::string token; defaults >> token;)
    if (token.size() > 1 && token[0] == '-') ours.push_back(token.substr(1));
  std::string s;
  for (PetscInt k = 0; k < count; ++k)
    if (std::find(ours.begin(), ours.end(), names[k]) == ours.end())
      s += (s.empty() ? "-" : " -") + std::string(names[k]);
  PetscOptionsLeftRestore(m->options, &count, &names, &values);
  return s;
}

void PetscSolver::set_coordinates(ConstRef x) { m->coordinates = x; }

LinearSummary PetscSolver::analyze(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  HOOKE_ASSERT(A.isCompressed() && A.rows() == A.cols(),
               "petsc: analyze needs a compressed square A");
  m->reset();
  m->A = &A;
  m->n = A.rows();
  try {
    const ErrorScope errors;
    m->make_options();
    if (m->n > 0 && m->distributed()) {
      const OptionsScope scope(m->options);
      m->distribute(A);
      check(KSPCreate(PETSC_COMM_WORLD, &m->ksp), "KSPCreate");
      check(KSPSetOperators(m->ksp, m->M, m->M), "KSPSetOperators");
      check(KSPSetFromOptions(m->ksp), "KSPSetFromOptions");
    } else if (m->n > 0) {
      const OptionsScope scope(m->options);
      m->wrap(A);
      check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, PetscInt(m->n), nullptr, &m->b),
            "VecCreateSeqWithArray");
      check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, PetscInt(m->n), nullptr, &m->x),
            "VecCreateSeqWithArray");
      check(KSPCreate(PETSC_COMM_SELF, &m->ksp), "KSPCreate");
      check(KSPSetOperators(m->ksp, m->shell, m->M), "KSPSetOperators");
      check(KSPSetFromOptions(m->ksp), "KSPSetFromOptions");
    }
  } catch (const PetscFailure& e) {
    s.status = Status::Fatal;
    s.message = std::string("petsc: ") + e.what();
  }
  s.analyze_seconds = seconds_since(t0);
  return s;
}

LinearSummary PetscSolver::factor(const SparseMatrix& A) {
  const auto t0 = Clock::now();
  LinearSummary s;
  HOOKE_ASSERT(A.rows() == m->n, "petsc: factor on a matrix of another size than analysed");
  m->A = &A;
  if (m->n == 0) return s;
  if (!m->ksp) {  // analyze() failed (its summary said why)
    s.status = Status::Fatal;
    s.message = "petsc: factor() without a successful analyze()";
    return s;
  }
  try {
    const ErrorScope errors;
    const OptionsScope scope(m->options);
    if (m->distributed()) {
      m->copy_owned_rows(A);
    } else if (!m->wraps(A)) {  // another matrix than the last one (same pattern): wrap it instead
      m->wrap(A);
      m->rebuild = true;
    }
    // A's new values are M's. Assembly tells every cache (SOR's and point-block Jacobi's
    // diagonals) that they changed.
    check(MatAssemblyBegin(m->M, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
    check(MatAssemblyEnd(m->M, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
    // Renewal rule: keep the hierarchy while the last solve cost no more than the average solve
    // since the last build, the build included.
    if (m->solves_since > 0 && double(m->last_iterations) * m->solves_since > m->cost_since)
      m->rebuild = true;
    if (m->rebuild) {
      m->near_null_space();
      check(KSPSetReusePreconditioner(m->ksp, PETSC_FALSE), "KSPSetReusePreconditioner");
      check(KSPSetOperators(m->ksp, m->krylov_operator(), m->M), "KSPSetOperators");
      check(KSPSetUp(m->ksp), "KSPSetUp");
      m->adopt_concurrent_split();
      check(KSPSetReusePreconditioner(m->ksp, PETSC_TRUE), "KSPSetReusePreconditioner");
      ++m->builds;
      m->cost_since = m->setup_cost;
      m->solves_since = 0;
      m->rebuild = false;
    } else {
      check(KSPSetOperators(m->ksp, m->krylov_operator(), m->M), "KSPSetOperators");
    }
  } catch (const PetscFailure& e) {
    s.status = Status::Fatal;
    s.message = std::string("petsc: ") + e.what();
  }
  s.factor_seconds = seconds_since(t0);
  return s;
}

LinearSummary PetscSolver::solve(ConstRef b, VecRef x, const LinearSolveOptions& options) {
  const auto t0 = Clock::now();
  LinearSummary s;
  HOOKE_ASSERT(b.size() == m->n && x.size() == m->n, "petsc: size mismatch");
  if (m->n == 0) return s;
  if (!m->ksp) {
    s.status = Status::Fatal;
    s.message = "petsc: solve() without a successful analyze()";
    return s;
  }
  try {
    const ErrorScope errors;
    // Over the owned rows of every process for a distributed system (its other rows are partial).
    const double bnorm = m->distributed() ? m->owned_norm(b) : b.norm();
    if (bnorm == 0.0) {  // the exact solution, whatever the tolerance or the warm start
      x.setZero();
      return s;
    }
    const OptionsScope scope(m->options);
    if (!options.warm_start) x.setZero();
    check(KSPSetInitialGuessNonzero(m->ksp, options.warm_start ? PETSC_TRUE : PETSC_FALSE),
          "KSPSetInitialGuessNonzero");
    // No divergence test on ||r|| / ||b|| unless asked (-ksp_divtol): a warm start from the
    // previous Newton correction can start far above a small right-hand side.
    check(KSPSetTolerances(m->ksp, m->user_rtol ? PETSC_DEFAULT : options.tolerance,
                           m->user_rtol ? PETSC_DEFAULT : 0.0,
                           m->user_divtol ? PETSC_DEFAULT : PETSC_MAX_REAL,
                           m->user_max_it ? PETSC_DEFAULT : PetscInt(options.max_iterations)),
          "KSPSetTolerances");
    check(VecPlaceArray(m->b, b.data()), "VecPlaceArray");
    check(VecPlaceArray(m->x, x.data()), "VecPlaceArray");
    const PetscErrorCode ierr = KSPSolve(m->ksp, m->b, m->x);
    VecResetArray(m->b);
    VecResetArray(m->x);
    check(ierr, "KSPSolve");
    // The ghosts' unknowns from their owners: every process then holds the same x for a particle.
    if (m->distributed()) m->settings.distribution->complete(x);
    if (m->view_pending) {
      m->view_pending = false;
      check(
          KSPView(m->ksp, m->distributed() ? PETSC_VIEWER_STDOUT_WORLD : PETSC_VIEWER_STDOUT_SELF),
          "KSPView");
    }
    PetscInt its = 0;
    KSPConvergedReason reason;
    PetscReal rnorm = 0.0;
    check(KSPGetIterationNumber(m->ksp, &its), "KSPGetIterationNumber");
    check(KSPGetConvergedReason(m->ksp, &reason), "KSPGetConvergedReason");
    check(KSPGetResidualNorm(m->ksp, &rnorm), "KSPGetResidualNorm");
    s.iterations = int(its);
    s.residual = bnorm > 0 ? double(rnorm) / bnorm : double(rnorm);
    m->last_iterations = int(its);
    m->cost_since += double(its);
    ++m->solves_since;
    if (reason < 0) {
      std::ostringstream os;
      // CG stops on negative curvature (INDEFINITE_MAT / _PC); a preconditioner whose set-up
      // fails (PC_FAILED: a zero or negative pivot in its factorizations) is also what an A that
      // is not positive definite does to this SPD-only backend.
      s.not_positive_definite = reason == KSP_DIVERGED_INDEFINITE_PC ||
                                reason == KSP_DIVERGED_INDEFINITE_MAT ||
                                reason == KSP_DIVERGED_PC_FAILED;
      // BoomerAMG does not report a failed set-up: on an indefinite A its smoothers divide by
      // zero or negative diagonals and CG sees NaN or infinity. With finite A and b that is what
      // NANORINF means here.
      if (reason == KSP_DIVERGED_NANORINF && b.allFinite() && m->A != nullptr &&
          Eigen::Map<const hooke::Vec>(m->A->valuePtr(), m->A->nonZeros()).allFinite())
        s.not_positive_definite = true;
      os << "petsc: KSP " << KSPConvergedReasons[reason] << " after " << its
         << " iterations (relative residual " << s.residual << ", tolerance " << options.tolerance
         << ")"
         << (s.not_positive_definite ? ": A (or its preconditioner) is not positive definite" : "");
      s.message = os.str();
      s.status = reason == KSP_DIVERGED_ITS ? Status::NotConverged : Status::BrokeDown;
      m->rebuild = true;  // a failed solve is not worth reusing its hierarchy for
    }
  } catch (const PetscFailure& e) {
    s.status = Status::Fatal;
    s.message = std::string("petsc: ") + e.what();
  }
  s.solve_seconds = seconds_since(t0);
  return s;
}

}  // namespace hooke
