#include "hooke/thread_policy.hpp"

#include <cstdlib>

#if defined(__linux__)
#include <unistd.h>
#endif

namespace hooke {

void adopt_thread_policy(char** argv) {
#if defined(__linux__) && defined(_OPENMP)
  if (std::getenv("GOMP_SPINCOUNT") || std::getenv("OMP_WAIT_POLICY") || !argv || !argv[0]) return;
  if (setenv("GOMP_SPINCOUNT", kGompSpinCount, 0) != 0) return;
  execv("/proc/self/exe", argv);
  // Only reached if the execution failed: go on with libgomp's default, but leave the variable
  // set, so that programs this one starts take the policy.
#else
  (void)argv;
#endif
}

}  // namespace hooke
