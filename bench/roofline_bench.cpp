// Roofline accounting of hooke's hot kernels at 1M springs (the benchmark cloth of
// cloth_fixture.hpp: 408 x 408 particles, structural, shear and flexion springs), on 1 and 2
// threads (the argument), next to a STREAM-style triad measured in the same binary. For each
// kernel: the minimum bytes it must move and the flops it must do per call (counted from the data
// structures, formulas below), and the achieved GB/s, GFLOP/s and fraction of the triad's GB/s.
// See bench/README.md.
//   build/bench/hooke_bench_roofline --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_main.hpp"
#include "bench/busy_core.hpp"
#include "bench/cloth_fixture.hpp"
#include "bench/implicit_operator.hpp"
#include "bench/triad.hpp"
#include "hooke/integrators/reduced_matrix.hpp"
#include "hooke/linear/cholmod/cholmod_solver.hpp"
#include "hooke/linear/cholmod/supernodal_solve.hpp"
#include "hooke/linear/iterative_common.hpp"
#include "hooke/sparse/symmetric_product.hpp"
#include "hooke/whole_step/fast_mass_spring.hpp"

namespace {

constexpr long long kSprings = 1000000;
constexpr double kH = 1.0 / 60.0;

/// Triad GB/s per thread count, measured by BM_Triad (registered first) and read by the kernels.
std::map<int, double>& triad() { return hooke::bench::triad_rates(); }

/// One cloth and everything the kernels need, built once.
struct Fixture {
  hooke::Scene scene = hooke::bench::make_cloth(kSprings);              // with dampers
  hooke::Scene undamped = hooke::bench::make_cloth(kSprings, "", 0.0);  // fast-mass-spring's
  hooke::Jacobians J = scene.system->make_jacobians();
  std::unique_ptr<hooke::ReducedMatrix> reduced;
  hooke::linear_detail::CsrMirror csr;
  hooke::SymmetricProduct sym;  // what CG runs
  std::unique_ptr<hooke::FastMassSpringStepper> fms;
  std::unique_ptr<hooke::CholmodSolver> chol;
  std::unique_ptr<hooke::SupernodalSolver> sn, sn_single;
  Fixture() {
    const auto& sys = *scene.system;
    sys.assemble_jacobians(scene.initial.x, scene.initial.v, J);
    reduced = std::make_unique<hooke::ReducedMatrix>(sys);
    reduced->assemble(J, kH, kH * kH);  // A = M - h D - h^2 K on the free particles
    csr.build(reduced->matrix());
    csr.refresh(reduced->matrix());
    sym.analyze(reduced->matrix());
    hooke::FastMassSpringOptions o;
    o.iterations = 1;
    fms = std::make_unique<hooke::FastMassSpringStepper>(*undamped.system, o);
    hooke::State s1;
    fms->step(undamped.initial, kH, s1);
    hooke::CholmodOptions metis;
    metis.ordering = hooke::CholmodOrdering::Metis;
    chol = std::make_unique<hooke::CholmodSolver>(metis);
    chol->analyze(fms->global_matrix());
    chol->factor(fms->global_matrix());
    sn = std::make_unique<hooke::SupernodalSolver>(3);
    sn->bind(chol->supernodal_view());
    sn_single =
        std::make_unique<hooke::SupernodalSolver>(3, hooke::SupernodalSolver::Precision::Single);
    sn_single->bind(chol->supernodal_view());
  }
};
Fixture& fixture() {
  static Fixture f;
  return f;
}

/// The triad's GB/s just before the running case's loop (threads() measures it), per thread count.
std::map<int, double>& triad_before() {
  static std::map<int, double> rates;
  return rates;
}
constexpr int kTriadCalls = 5;  // per measurement next to a kernel: about 60 ms on one thread

/// Sets the thread count of this case, measures the triad on it (for report()) and returns it.
int threads(benchmark::State& state) {
  const int t = int(state.range(0));
  omp_set_num_threads(t);
  triad_before()[t] = hooke::bench::measure_triad(t, kTriadCalls);
  return t;
}

/// Reports the case's bandwidth and flop rate and its fraction of the adjacent triad, which it
/// returns (GB/s).
double report(benchmark::State& state, double bytes, double flops, int t) {
  state.counters["MB"] = bytes / 1e6;
  state.counters["Mflop"] = flops / 1e6;
  state.counters["GB/s"] =
      benchmark::Counter(bytes / 1e9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops / 1e9, benchmark::Counter::kIsIterationInvariantRate);
  // The fraction of the triad at the same thread count (issue 18), measured next to the kernel:
  // the mean of the triad just before its loop and just after. The triad cases' own figure,
  // measured once at the start, is printed beside it (first_triad_GB/s).
  const double adjacent = 0.5 * (triad_before()[t] + hooke::bench::measure_triad(t, kTriadCalls));
  state.counters["triad_GB/s"] = adjacent;
  state.counters["of_triad"] =
      benchmark::Counter(bytes / 1e9 / adjacent, benchmark::Counter::kIsIterationInvariantRate);
  const auto tr = triad().find(t);
  if (tr != triad().end()) state.counters["first_triad_GB/s"] = tr->second;
  return adjacent;
}

/// STREAM triad a = b + s c on 3 x 2^24 doubles (384 MB), 24 bytes and 2 flops per element.
void BM_Triad(benchmark::State& state) {
  const int t = threads(state);
  hooke::bench::run_triad(state, t);
  report(state, 24.0 * double(1LL << 24), 2.0 * double(1LL << 24), t);
}

/// Forces of every spring and damper, gravity: reads x, v (2 x 3n doubles), writes f (3n),
/// streams each spring's two ids and stiffness, rest length (and the damper's ids and
/// coefficient): 24 + 16 bytes per spring and set. About 40 flops per spring (difference, length
/// with a square root, force, scatter) and 20 per damper.
void BM_ForceEvaluation(benchmark::State& state) {
  const int t = threads(state);
  Fixture& fx = fixture();
  const auto& sys = *fx.scene.system;
  hooke::Vec f(sys.dofs());
  for (auto _ : state) {
    sys.compute_forces(fx.scene.initial.x, fx.scene.initial.v, f);
    benchmark::DoNotOptimize(f.data());
  }
  const double springs = double(fx.scene.edges.size()), dofs = double(sys.dofs());
  report(state, 3.0 * 8 * dofs + 2 * 24.0 * springs, 60.0 * springs, t);
}

/// K = df/dx and D = df/dv values into their fixed patterns. Charged as a zero-then-add assembly
/// (issue 18's baseline): both value arrays zeroed, then each spring's and damper's blocks added,
/// at least 2 x 8 bytes per stored entry, plus the springs' data. About 60 flops per spring block
/// set. hooke's assembly writes each value once (through a ring of blocks in cache,
/// MassSpringSystem::assemble_jacobians): `once_of_triad` is the fraction of the triad against
/// that minimum (8 bytes per stored entry, the springs' data, x and v read).
void BM_JacobianAssembly(benchmark::State& state) {
  const int t = threads(state);
  Fixture& fx = fixture();
  const auto& sys = *fx.scene.system;
  for (auto _ : state) {
    sys.assemble_jacobians(fx.scene.initial.x, fx.scene.initial.v, fx.J);
    benchmark::DoNotOptimize(fx.J.K.valuePtr());
  }
  const double springs = double(fx.scene.edges.size()), nnz = double(fx.J.K.nonZeros());
  const double triad_rate =
      report(state, 2.0 * 2 * 8 * nnz + 2 * 24.0 * springs, 2 * 60.0 * springs, t);
  const double once = 2 * 8.0 * nnz + 2 * 24.0 * springs + 2 * 8.0 * double(sys.dofs());
  state.counters["once_of_triad"] =
      benchmark::Counter(once / 1e9 / triad_rate, benchmark::Counter::kIsIterationInvariantRate);
}

/// The implicit-step operator y = A x with A = M - h D - h^2 K (3n x 3n) by a row-major copy
/// (CsrMirror, what Jacobi and Gauss-Seidel run, and CG did before SymmetricProduct): 12 bytes per
/// stored entry (value and column), the row starts, x read and y written;
/// 2 flops per entry.
void BM_OperatorProduct(benchmark::State& state) {
  const int t = threads(state);
  Fixture& fx = fixture();
  const hooke::Index n = fx.reduced->matrix().rows();
  const hooke::Vec x = hooke::Vec::Ones(n);
  hooke::Vec y(n);
  for (auto _ : state) {
    fx.csr.multiply(x, y);
    benchmark::DoNotOptimize(y.data());
  }
  const double nnz = double(fx.csr.value.size());
  report(state, 12.0 * nnz + 4.0 * double(n) + 2 * 8.0 * double(n), 2.0 * nnz, t);
}

/// The same product as CG runs it (SymmetricProduct): A's own compressed-column arrays read as
/// rows, one row index per 3x3 block: 8 bytes per entry, 4 per block, the block column starts, x
/// read and y written; 2 flops per entry.
void BM_SymmetricProduct(benchmark::State& state) {
  const int t = threads(state);
  Fixture& fx = fixture();
  const hooke::SparseMatrix& A = fx.reduced->matrix();
  const hooke::Index n = A.rows();
  const hooke::Vec x = hooke::Vec::Ones(n);
  hooke::Vec y(n);
  for (auto _ : state) {
    fx.sym.multiply(A, x, y);
    benchmark::DoNotOptimize(y.data());
  }
  const double nnz = double(A.nonZeros()), blocks = double(fx.sym.num_blocks());
  report(state, 8.0 * nnz + 4.0 * blocks + 4.0 * double(n) / 3 + 2 * 8.0 * double(n), 2.0 * nnz, t);
}

/// The same operator matrix-free (ImplicitOperator: each spring's and damper's Jacobian blocks
/// recomputed from x and v and applied to p): x, v and p read and y written (3n doubles each),
/// plus the scatter into the full-length scratch and back (4 x 3n), and 24 bytes of data per spring
/// and per damper. About 60 flops per spring (its block and the product) and 40 per damper.
void BM_MatrixFreeOperator(benchmark::State& state) {
  const int t = threads(state);
  Fixture& fx = fixture();
  hooke::ImplicitOperator op(*fx.scene.system);
  hooke::JacobianOptions opt;
  opt.damping_position_terms = false;  // what the implicit steps on SPD backends use
  op.set(fx.scene.initial.x, fx.scene.initial.v, kH, kH * kH, opt);
  const hooke::Vec x = hooke::Vec::Ones(op.free_dofs());
  hooke::Vec y(op.free_dofs());
  for (auto _ : state) {
    op.apply(x, y);
    benchmark::DoNotOptimize(y.data());
  }
  const double springs = double(fx.scene.edges.size()), dofs = double(fx.scene.system->dofs());
  report(state, 8 * 8.0 * dofs + 2 * 24.0 * springs, 100.0 * springs, t);
}

/// One Jacobi-PCG iteration on A: the operator product (SymmetricProduct, as CG runs it) plus z =
/// D^-1 r and the vector updates (x, r, p updates and two dot products): the product's bytes plus 9
/// vectors of 3n doubles moved; its flops plus 12 per row.
void BM_PcgIteration(benchmark::State& state) {
  const int t = threads(state);
  Fixture& fx = fixture();
  const hooke::Index n = fx.reduced->matrix().rows();
  hooke::Vec x = hooke::Vec::Zero(n), r = hooke::Vec::Ones(n), z(n), p = hooke::Vec::Ones(n), Ap(n);
  hooke::Vec inv_diag = fx.reduced->matrix().diagonal().cwiseInverse();
  double rz = r.dot(r);
  const hooke::SparseMatrix& A = fx.reduced->matrix();
  for (auto _ : state) {
    fx.sym.multiply(A, p, Ap);
    const double alpha = rz / p.dot(Ap);
    x.noalias() += alpha * p;
    r.noalias() -= alpha * Ap;
    z = inv_diag.cwiseProduct(r);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
    benchmark::DoNotOptimize(x.data());
  }
  const double nnz = double(A.nonZeros()), blocks = double(fx.sym.num_blocks());
  report(state, 8.0 * nnz + 4.0 * blocks + 4.0 * double(n) / 3 + 11 * 8.0 * double(n),
         2.0 * nnz + 12.0 * double(n), t);
}

/// One forward and back substitution with 3 right-hand sides (x, y, z) on the fast-mass-spring
/// factor (n x n, METIS), by SupernodalSolver: its packed factor (inverted diagonal blocks and
/// off-diagonal blocks, 4-column panels) is read once per sweep, 8 bytes an entry (4 for
/// .../Single, the factor rounded to float); 2 flops per entry and right-hand side per sweep.
void triangular_solves(benchmark::State& state, hooke::SupernodalSolver& sn, double entry_bytes) {
  const int t = threads(state);
  Fixture& fx = fixture();
  const hooke::Index n = fx.fms->global_matrix().rows();
  const hooke::Vec b = hooke::Vec::Ones(3 * n);
  hooke::Vec x(3 * n);
  for (auto _ : state) {
    sn.solve(b.data(), x.data());
    benchmark::DoNotOptimize(x.data());
  }
  const auto shape = sn.shape();
  const double entries = shape.diagonal_entries + shape.off_diagonal_entries;
  report(state, 2 * entry_bytes * entries + 4 * 8.0 * 3 * double(n), 2 * 2 * 3 * entries, t);
  state.counters["factor_entries"] = entries;
  state.counters["packed_entries"] = shape.packed_entries;
  state.counters["supernodes"] = double(shape.supernodes);
  state.counters["top_fraction"] = shape.top_fraction;  // the serial part of the tree split
}
void BM_TriangularSolves3(benchmark::State& state) { triangular_solves(state, *fixture().sn, 8.0); }
/// The same with a competing process spinning on the last core (busy_core.hpp; the triad is
/// measured beside it too): two threads are the caller and SupernodalSolver's helper thread.
/// helper_bins and taken_over: per solve, the bins whose results the helper computed and those the
/// caller took over from it.
void BM_TriangularSolves3Busy(benchmark::State& state) {
  const hooke::bench::BusyCore busy(true);
  hooke::SupernodalSolver& sn = *fixture().sn;
  const auto before = sn.helped();
  triangular_solves(state, sn, 8.0);
  const double solves = double(std::max<benchmark::IterationCount>(1, state.iterations()));
  state.counters["helper_bins"] = double(sn.helped().helper_bins - before.helper_bins) / solves;
  state.counters["taken_over"] = double(sn.helped().taken_over - before.taken_over) / solves;
}
void BM_TriangularSolves3Single(benchmark::State& state) {
  triangular_solves(state, *fixture().sn_single, 4.0);
}

/// One local/global iteration of fast-mass-spring (local step over the springs, then the global
/// solve above): the springs' data and positions, the right-hand side, and the solve's bytes.
/// .../single:1 reads the factor rounded to float (factor_precision = "single") and adds the
/// residual's product with the global matrix (12 bytes per stored entry) and its vectors.
void BM_LocalGlobalIteration(benchmark::State& state) {
  const int t = threads(state);
  const bool single = state.range(1) != 0;
  Fixture& fx = fixture();
  hooke::FastMassSpringOptions o;
  o.iterations = 10;
  if (single) o.factor_precision = hooke::FactorPrecision::Single;
  hooke::FastMassSpringStepper fms(*fx.undamped.system, o);
  hooke::State s0 = fx.undamped.initial, s1;
  fms.step(s0, kH, s1);  // factors
  std::swap(s0, s1);
  for (auto _ : state) {
    const double t0 = omp_get_wtime();
    fms.step(s0, kH, s1);
    state.SetIterationTime((omp_get_wtime() - t0) / o.iterations);
    std::swap(s0, s1);
  }
  const auto shape = fx.sn->shape();
  const double entries = shape.diagonal_entries + shape.off_diagonal_entries;
  const double springs = double(fx.undamped.edges.size()), n = double(fms.global_matrix().rows());
  const double nnz = double(fms.global_matrix().nonZeros());
  const double residual_bytes = single ? 12.0 * nnz + 3 * 8.0 * 3 * n : 0.0;
  report(state,
         2 * (single ? 4.0 : 8.0) * entries + 4 * 8.0 * 3 * n + 24.0 * springs + 6 * 8.0 * 3 * n +
             residual_bytes,
         2 * 2 * 3 * entries + 40.0 * springs + (single ? 6.0 * nnz : 0.0), t);
}

const int registered = [] {
  for (const char* v : {"OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"}) {
    const char* value = std::getenv(v);
    benchmark::AddCustomContext(v, value ? value : "(unset)");
  }
  auto both = [](benchmark::internal::Benchmark* b) {
    b->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();
  };
  both(benchmark::RegisterBenchmark("Roofline/Triad", BM_Triad));
  both(benchmark::RegisterBenchmark("Roofline/ForceEvaluation", BM_ForceEvaluation));
  both(benchmark::RegisterBenchmark("Roofline/JacobianAssembly", BM_JacobianAssembly));
  both(benchmark::RegisterBenchmark("Roofline/OperatorProduct", BM_OperatorProduct));
  both(benchmark::RegisterBenchmark("Roofline/SymmetricProduct", BM_SymmetricProduct));
  both(benchmark::RegisterBenchmark("Roofline/MatrixFreeOperator", BM_MatrixFreeOperator));
  both(benchmark::RegisterBenchmark("Roofline/PcgIteration", BM_PcgIteration));
  both(benchmark::RegisterBenchmark("Roofline/TriangularSolves3", BM_TriangularSolves3));
  both(benchmark::RegisterBenchmark("Roofline/TriangularSolves3Busy", BM_TriangularSolves3Busy));
  both(
      benchmark::RegisterBenchmark("Roofline/TriangularSolves3Single", BM_TriangularSolves3Single));
  benchmark::RegisterBenchmark("Roofline/LocalGlobalIteration", BM_LocalGlobalIteration)
      ->Args({1, 0})
      ->Args({2, 0})
      ->Args({1, 1})
      ->Args({2, 1})
      ->ArgNames({"threads", "single"})
      ->Unit(benchmark::kMillisecond)
      ->UseManualTime()
      ->Iterations(3);
  return 0;
}();

}  // namespace

HOOKE_BENCHMARK_MAIN();
