#include "hooke/parallel/thread_policy.hpp"

#include <cstdlib>

#if defined(__linux__)
#include <unistd.h>
#endif

namespace hooke {

void adopt_thread_policy(char** argv) {
#if defined(__linux__)
  if (!argv || !argv[0]) return;
  bool set = false;
#if defined(_OPENMP)
  if (!std::getenv("GOMP_SPINCOUNT") && !std::getenv("OMP_WAIT_POLICY"))
    set = setenv("GOMP_SPINCOUNT", kGompSpinCount, 0) == 0 || set;
#endif
  if (!std::getenv("OPENBLAS_THREAD_TIMEOUT"))
    set = setenv("OPENBLAS_THREAD_TIMEOUT", kOpenBlasThreadTimeout, 0) == 0 || set;
  // Returns only if nothing was set or the execution failed: the run then goes on with the
  // libraries' defaults, the variables left set, so that programs this one starts take the policy.
  if (set) execv("/proc/self/exe", argv);
#else
  (void)argv;
#endif
}

}  // namespace hooke
