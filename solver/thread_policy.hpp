#pragma once
/// libgomp's wait policy for hooke's programs, chosen for shared machines.

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

/// Call first thing in main(), before any OpenMP region. When neither OMP_WAIT_POLICY nor
/// GOMP_SPINCOUNT is set, sets GOMP_SPINCOUNT = kGompSpinCount and executes the program again
/// with the same arguments: libgomp reads its environment once, when it is loaded, before main,
/// so only a new image of the program sees the value. Returns without doing anything when either
/// variable is set (the user's choice wins; the executed image finds it set) or on a system
/// without /proc/self/exe, and returns after a failed execution (the run then keeps libgomp's
/// default).
void adopt_thread_policy(char** argv);

}  // namespace hooke
