// [bending]: angle-based bending (solver/forces/bending.hpp) over a built mesh, as one element set
// beside the mesh's springs: rod on the strands of chain and hair meshes, dihedral and quadratic
// across the interior edges of grid and obj cloth, shell on their triangles.
#include "hooke/forces/bending.hpp"

#include <cmath>
#include <memory>
#include <sstream>
#include <vector>

#include "hooke/forces/element_force.hpp"
#include "hooke/model/mass_spring_system.hpp"
#include "problems/builders/mesh_build.hpp"

namespace hooke {

namespace {

bool is_strand(const std::string& type) { return type == "chain" || type == "hair"; }
bool is_cloth(const std::string& type) { return type == "grid" || type == "obj"; }

/// One set, as the vector of sets add_bending takes.
std::vector<std::unique_ptr<ElementSet>> one_set(std::unique_ptr<ElementSet> set) {
  std::vector<std::unique_ptr<ElementSet>> sets;
  sets.push_back(std::move(set));
  return sets;
}

std::vector<std::unique_ptr<ElementSet>> strand_bending(TableReader& bending, const MeshBuild& b,
                                                        double EI) {
  const bool straight =
      bending.choice("rest", std::string("initial"), {"initial", "straight"}) == "straight";
  const int n = static_cast<int>(b.num_particles());
  if (n < 3)
    bending.fail("model", "a strand of " + std::to_string(n) +
                              " particles has no interior particle to bend at (mesh.n >= 3)");
  auto rod = std::make_unique<RodBending>();
  for (int q = 1; q + 1 < n; ++q) rod->add(q - 1, q, q + 1, EI, b.x, straight);
  return one_set(std::move(rod));
}

/// bending.projection, Gauss-Newton by default: on the draped cloth_dihedral under Newton (50
/// steps, D = 1e-4 to 1e-1 N m) it took as many or fewer iterations as the eigenvalue clamp (274
/// against 275, 266 against 287, 250 against 286) at 0.55-0.6x the run time.
bool gauss_newton(TableReader& bending) {
  return bending.choice("projection", std::string("gauss-newton"),
                        {"gauss-newton", "eigenvalues"}) == "gauss-newton";
}

/// The shell model's sets: one per number of interior edges of a triangle (1 to 3).
std::vector<std::unique_ptr<ElementSet>> shell_bending(TableReader& bending, const MeshBuild& b,
                                                       double D, bool flat) {
  const double nu = bending.number("poisson", 0.0);
  if (!(nu > -1.0 && nu <= 0.5))
    bending.fail("poisson", "the Poisson ratio of an isotropic plate lies in (-1, 0.5], not " +
                                std::to_string(nu));
  return shell_bending_sets(b.triangles, D, nu, b.x, flat, gauss_newton(bending));
}

std::vector<std::unique_ptr<ElementSet>> cloth_bending(TableReader& bending,
                                                       const std::string& model, const MeshBuild& b,
                                                       double D) {
  const bool flat = bending.choice("rest", std::string("initial"), {"initial", "flat"}) == "flat";
  size_t non_manifold = 0;
  const auto hinges = interior_hinges(b.triangles, &non_manifold);
  if (hinges.empty())
    bending.fail("model", "the mesh has no interior edge (an edge of two triangles) to bend at");
  if (non_manifold > 0)
    bending.warn("model", std::to_string(non_manifold) +
                              " edges of three or more triangles (non-manifold) carry no bending");
  for (const auto& h : hinges)
    if (!DihedralBending::rest_ok(h, b.x)) {
      std::ostringstream os;
      os << "the edge (" << h[1] << ", " << h[2] << ") lies on a degenerate triangle (no area) at "
         << "rest, so it has no bending angle";
      bending.fail("model", os.str());
    }
  if (model == "dihedral") {
    auto set = std::make_unique<DihedralBending>(gauss_newton(bending));
    for (const auto& h : hinges) set->add(h, D, b.x, flat);
    return one_set(std::move(set));
  }
  if (model == "shell") return shell_bending(bending, b, D, flat);
  // quadratic: its rest is the flat development of each hinge.
  if (!flat) {
    // The largest rest angle that is flat but for round-off of the positions.
    constexpr double kFlat = 1e-6;
    for (const auto& h : hinges) {
      const double theta = DihedralBending::angle(b.x, h);
      if (std::abs(theta) > kFlat) {
        std::ostringstream os;
        os << "the quadratic model rests flat, but the initial shape is bent by " << theta
           << " rad at the edge (" << h[1] << ", " << h[2]
           << "): set bending.rest = 'flat' to take its flat development as the rest shape, or use "
              "model = 'dihedral' to keep the initial shape";
        bending.fail("rest", os.str());
      }
    }
  }
  auto set = std::make_unique<QuadraticBending>();
  for (const auto& h : hinges) set->add(h, D, b.x);
  return one_set(std::move(set));
}

}  // namespace

void add_bending(TableReader& bending, const MeshBuild& b, MassSpringSystem& sys) {
  const std::string model =
      bending.choice("model", std::nullopt, {"rod", "dihedral", "quadratic", "shell"});
  bending.set_variant(model);
  if (model == "rod" && !is_strand(b.type))
    bending.fail("model", "'rod' bends strands (mesh.type = 'chain' or 'hair'); this mesh is '" +
                              b.type + "'" +
                              (is_cloth(b.type) ? ": use 'dihedral', 'quadratic' or 'shell'" : ""));
  if (model != "rod" && !is_cloth(b.type))
    bending.fail("model", "'" + model +
                              "' bends cloth (mesh.type = 'grid' or 'obj'); this mesh is '" +
                              b.type + "'" + (is_strand(b.type) ? ": use 'rod'" : ""));
  const double stiffness = bending.positive("stiffness");
  // Rayleigh damping on the bending rates (ElementForce): every model has the form.
  const double damping = bending.non_negative("damping", 0.0);
  auto sets = model == "rod" ? strand_bending(bending, b, stiffness)
                             : cloth_bending(bending, model, b, stiffness);
  for (auto& set : sets) {
    auto force = std::make_unique<ElementForce>(std::move(set));
    if (damping > 0.0) {
      auto dampers = std::make_unique<ElementDamping>(force->set(), damping);
      sys.add_force(std::move(force));
      sys.add_force(std::move(dampers));
    } else {
      sys.add_force(std::move(force));
    }
  }
}

}  // namespace hooke
