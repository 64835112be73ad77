#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "problems/builders/mesh_build.hpp"

namespace hooke {

double read_particle_mass(TableReader& mesh, Index n, double default_total) {
  if (mesh.has("mass") && mesh.has("total_mass"))
    mesh.fail("total_mass", "give either mass (each particle) or total_mass, not both");
  if (mesh.has("mass")) return mesh.positive("mass");
  return mesh.positive("total_mass", default_total) / static_cast<double>(n);
}

void pin_ids(TableReader& mesh, const std::string& key, const std::vector<long long>& ids,
             MeshBuild& out) {
  const long long n = out.num_particles();
  for (size_t k = 0; k < ids.size(); ++k) {
    long long id = ids[k];
    if (id < 0) id += n;
    if (id < 0 || id >= n)
      mesh.fail(key + "[" + std::to_string(k) + "]", "particle id " + std::to_string(ids[k]) +
                                                         " out of range [0, " + std::to_string(n) +
                                                         ") (negative ids count from the end)");
    out.pinned[static_cast<size_t>(id)] = 1;
  }
}

namespace {
constexpr double kGiB = double(1ull << 30);

/// The processes of this MPI launch that share this machine (1 outside one), from the launcher's
/// environment: every process of a run across processes builds the whole scene (issue 17), so
/// each may take only its share of the machine's memory.
long processes_on_this_machine() {
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS", "PMIX_LOCAL_SIZE"})
    if (const char* value = std::getenv(name)) return std::max(1L, std::atol(value));
  return 1;
}

double default_memory_limit() {
  if (const char* env = std::getenv("HOOKE_MAX_MEMORY_GIB")) {
    char* end = nullptr;
    const double gib = std::strtod(env, &end);
    if (end != env && *end == '\0' && std::isfinite(gib) && gib > 0.0) return gib * kGiB;
    throw InputError("<environment>", "HOOKE_MAX_MEMORY_GIB",
                     std::string("must be a number of GiB > 0, got '") + env + "'");
  }
  double limit = 64.0 * kGiB;
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0)
    limit = std::min(limit, double(pages) * double(page) / double(processes_on_this_machine()));
  return limit;
}

double& memory_limit_slot() {
  static double limit = 0.0;  // 0: not yet decided
  return limit;
}
}  // namespace

double scene_memory_limit() {
  double& limit = memory_limit_slot();
  if (limit <= 0.0) limit = default_memory_limit();
  set_memory_budget(limit);  // the solvers check their own large allocations against it
  return limit;
}

void set_scene_memory_limit(double bytes) {
  HOOKE_ASSERT(bytes > 0.0 && std::isfinite(bytes), "memory limit must be > 0, got " << bytes);
  memory_limit_slot() = bytes;
  set_memory_budget(bytes);
}

void check_size(TableReader& mesh, const std::string& key, double particles, double springs) {
  // Rough resident memory of a run: state and scratch (~20 doubles per particle), spring arrays
  // (~60 bytes), and two 3n x 3n Jacobians with 4 blocks per spring plus diagonals (12 bytes per
  // stored scalar each). Called before anything of that size is allocated.
  const double bytes = particles * 20 * 8 + springs * 60 + 2 * 12.0 * 9 * (4 * springs + particles);
  const double limit = scene_memory_limit();
  // Particle ids are ints in the spring arrays: more than 2^31 - 1 particles cannot be indexed.
  if (particles > 2147483647.0 || bytes > limit) {
    std::ostringstream os;
    os.precision(3);
    os << "a mesh of " << particles << " particles and " << springs << " springs would need about "
       << bytes / kGiB << " GiB, above the memory budget of " << limit / kGiB
       << " GiB (default: the smaller of 64 GiB and physical memory";
    if (const long p = processes_on_this_machine(); p > 1)
      os << " divided among the " << p << " processes of this MPI run on this machine";
    os << "; HOOKE_MAX_MEMORY_GIB sets it"
       << (processes_on_this_machine() > 1 ? " per process" : "") << ")";
    if (particles > 2147483647.0) os << " and above 2^31 - 1 particles";
    throw MemoryBudgetError(mesh.file(), mesh.path(key), os.str(), particles, springs, bytes);
  }
}

}  // namespace hooke
