#pragma once
/// The wait policies of libgomp's and OpenBLAS's idle threads for hooke's programs, chosen for
/// shared machines.

namespace hooke {

/// The spin count hooke's programs give libgomp (GOMP_SPINCOUNT): how long a thread that waits
/// for work (at the end of a parallel region, at a barrier) spins before it sleeps. libgomp's
/// default, 300000, keeps an idle thread spinning for milliseconds after each region. On a machine
/// where another process holds one core, that spinning thread takes CPU time from the one doing
/// the work, so a two-thread run becomes slower than a one-thread run even when it has gone back
/// to one thread (AdaptiveTeam). Measured on the 411 x 411 local/global iteration with a busy
/// core (bench/targets_bench.cpp): one thread 32.5 ms; two threads 36.3 ms with the default,
/// 33.0 ms with 10000; on a quiet machine the 2D dam break's 20k-particle WCSPH step (many short
/// regions) takes the same time with either (5.6-6.4 ms, within the machine's noise).
inline constexpr const char* kGompSpinCount = "10000";

/// The spin time hooke's programs give OpenBLAS's idle threads (OPENBLAS_THREAD_TIMEOUT: 2^20
/// time-stamp cycles, 0.4 ms at 2.6 GHz, about the spin count above). OpenBLAS's default, 2^28
/// (0.1 s), keeps its worker thread spinning on sched_yield for a tenth of a second after every
/// multithreaded BLAS call, that is after every CHOLMOD factorization: the OpenMP thread that
/// shares a core with it then runs at a fraction of its speed. Measured on the 411 x 411
/// local/global iteration on two threads (bench/targets_bench.cpp, quiet machine; the repetitions'
/// times printed by a temporary trace in AdaptiveTeam::record): AdaptiveTeam's first two-thread
/// repetitions, right after the warm-up step's factorization, took 17.0-18.2 ms
/// against 13.0-14.0 ms on one thread whenever they overlapped that spin, so the team chose one
/// thread for the rest of the run (2 of 8 runs, 13.0 and 13.4 ms per iteration; 8.3-8.8 ms
/// otherwise); with 2^20, 8 of 8 runs 8.2-9.2 ms. The 256 x 256 backward-Euler step that refactors
/// every step took the same time with either (1622-1644 against 1622-1692 ms).
inline constexpr const char* kOpenBlasThreadTimeout = "20";

/// Call first thing in main(), before any OpenMP region or BLAS call. Sets GOMP_SPINCOUNT =
/// kGompSpinCount unless OMP_WAIT_POLICY or GOMP_SPINCOUNT is set, and OPENBLAS_THREAD_TIMEOUT =
/// kOpenBlasThreadTimeout unless it is set; when it set either, executes the program again with
/// the same arguments: libgomp and OpenBLAS read their environment once, when they are loaded,
/// before main, so only a new image of the program sees the values. Returns without doing anything
/// when the user set them (the user's choice wins; the executed image finds them set) or on a
/// system without /proc/self/exe, and returns after a failed execution (the run then keeps the
/// libraries' defaults).
void adopt_thread_policy(char** argv);

}  // namespace hooke
