#include <cmath>
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
      mesh.fail(key + "[" + std::to_string(k) + "]",
                "particle id " + std::to_string(ids[k]) + " out of range [0, " + std::to_string(n) +
                    ") (negative ids count from the end)");
    out.pinned[static_cast<size_t>(id)] = 1;
  }
}

void check_size(TableReader& mesh, const std::string& key, double particles, double springs) {
  // Rough resident memory of a run: state and scratch (~20 doubles per particle), spring arrays
  // (~60 bytes), and two 3n x 3n Jacobians with 4 blocks per spring plus diagonals (12 bytes per
  // stored scalar each).
  const double bytes = particles * 20 * 8 + springs * 60 + 2 * 12.0 * 9 * (4 * springs + particles);
  const double limit = 64.0 * (1ull << 30);  // far above any machine this targets
  if (particles > 2e9 || bytes > limit) {
    std::ostringstream os;
    os.precision(3);
    os << "a mesh of " << particles << " particles and " << springs << " springs would need about "
       << bytes / double(1ull << 30) << " GiB; refusing sizes above 64 GiB";
    mesh.fail(key, os.str());
  }
}

}  // namespace hooke
