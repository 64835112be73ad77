#include "problems/scene_keys.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <mutex>
#include <sstream>

#include "problems/methods/method_family.hpp"
#include "problems/scene_key_builder.hpp"

namespace hooke {

namespace {

using K = SceneKeyBuilder;
using T = KeyType;
constexpr double kMaxCount = 1e9;  // nx, ny, n: the builders' bound

const std::vector<std::string> kLattices = {"grid", "cantilever"};
const std::vector<std::string> kLines = {"chain", "hair"};
const std::string kSpread = "mass spread evenly over the particles; give this or mesh.mass";
const std::string kEach = "mass of each particle; give this or mesh.total_mass";

/// Adds the [mesh] type and the keys of grid and cantilever.
void add_mesh_lattice_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  // [mesh]: one builder per type (problems/builders/).
  add(K("mesh.type", T::String)
          .choices({"grid", "cantilever", "chain", "hair", "damped-springs", "two-particle",
                    "particles", "obj"})
          .example("'grid'")
          .meaning("the mesh builder; the other [mesh] and [springs] keys depend on it"));
  add(K("mesh.nx", T::Integer)
          .in({"grid"})
          .def("20")
          .between(2, kMaxCount)
          .meaning("particles along the width (x)"));
  add(K("mesh.ny", T::Integer)
          .in({"grid"})
          .def("20")
          .between(2, kMaxCount)
          .meaning("particles along the height (z when horizontal, -y when vertical)"));
  add(K("mesh.width", T::Number)
          .in({"grid"})
          .unit("m")
          .def("1")
          .positive()
          .meaning("extent along x"));
  add(K("mesh.height", T::Number)
          .in({"grid"})
          .unit("m")
          .def("1")
          .positive()
          .meaning("extent along z (horizontal) or -y (vertical)"));
  add(K("mesh.orientation", T::String)
          .in({"grid"})
          .def("'horizontal'")
          .choices({"horizontal", "vertical"})
          .meaning("horizontal: in the x-z plane at y = 0; vertical: in the x-y plane, hanging "
                   "down from y = 0"));
  add(K("mesh.diagonals", T::String)
          .in({"grid"})
          .def("'alternating'")
          .choices({"alternating", "one-way"})
          .meaning("how each cell of the cloth's surface (frames, [bending]) is split into two "
                   "triangles: alternating diagonals (a checkerboard) or all one way (every edge's "
                   "two triangles a parallelogram, where bending.model = 'shell' is exact in "
                   "twist too; the hinge models then couple bending to twist)"));
  add(K("mesh.layers", T::Integer)
          .in({"grid"})
          .def("1")
          .between(1, 1000)
          .meaning("sheets stacked layer_spacing apart along the normal (+y horizontal, +z "
                   "vertical): one body, its sheets colliding under [contact] self"));
  add(K("mesh.layer_spacing", T::Number)
          .in({"grid"})
          .unit("m")
          .def("0.01")
          .positive()
          .meaning("distance between the stacked sheets (mesh.layers)"));
  add(K("mesh.flexion_stride", T::Integer)
          .in({"grid"})
          .def("1")
          .between(1, 2)
          .meaning("flexion springs start at every stride-th particle (2: the non-overlapping "
                   "bending springs "
                   "of public local/global demos)"));
  add(K("mesh.pins", T::Rows)
          .in({"grid"})
          .def("[[0, 0], [-1, 0]]")
          .meaning("pinned particles as grid coordinates [i, j]; negative values count from the "
                   "end (the default: the two corners of row 0)"));
  add(K("mesh.nx", T::Integer)
          .in({"cantilever"})
          .def("21")
          .between(2, kMaxCount)
          .meaning("particles along the beam (x); the column x = 0 is clamped"));
  add(K("mesh.ny", T::Integer)
          .in({"cantilever"})
          .def("3")
          .between(2, kMaxCount)
          .meaning("particles across the beam (-y)"));
  add(K("mesh.length", T::Number)
          .in({"cantilever"})
          .unit("m")
          .def("1")
          .positive()
          .meaning("length of the beam along x"));
  add(K("mesh.thickness", T::Number)
          .in({"cantilever"})
          .unit("m")
          .def("0.1")
          .positive()
          .meaning("thickness of the beam along -y"));
  for (const char* kind : {"structural", "shear", "flexion"}) {
    const std::string what = kind == std::string("structural") ? "(i+1, j) and (i, j+1)"
                             : kind == std::string("shear")    ? "along the cell diagonals"
                                                               : "(i+2, j) and (i, j+2)";
    add(K(std::string("mesh.") + kind, T::Boolean)
            .in(kLattices)
            .def("true")
            .meaning(std::string("add the ") + kind + " springs, " + what));
  }
}

/// Adds the [mesh] keys of chain, hair and the masses of the lattices and lines.
void add_mesh_line_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("mesh.n", T::Integer)
          .in(kLines)
          .def("20")
          .between(2, kMaxCount)
          .meaning("number of particles along the line"));
  add(K("mesh.length", T::Number)
          .in(kLines)
          .unit("m")
          .def("1")
          .positive()
          .meaning("length of the line"));
  add(K("mesh.direction", T::Vector3)
          .in(kLines)
          .def("[1, 0, 0]")
          .meaning("direction of the line from start (any nonzero length)"));
  add(K("mesh.start", T::Vector3)
          .in(kLines)
          .unit("m")
          .def("[0, 0, 0]")
          .meaning("position of particle 0"));
  add(K("mesh.pins", T::Integers)
          .in(kLines)
          .def("[0]")
          .meaning("ids of the pinned particles; negative ids count from the end"));
  add(K("mesh.curl_radius", T::Number)
          .in({"hair"})
          .unit("m")
          .def("0")
          .non_negative()
          .meaning("radius of the helix of curly hair (0: straight)"));
  add(K("mesh.curl_turns", T::Number)
          .in({"hair"})
          .def("0")
          .non_negative()
          .meaning("turns of the helix over the strand's length (0: straight)"));
  add(K("mesh.total_mass", T::Number)
          .in(kLattices)
          .unit("kg")
          .def("1")
          .positive()
          .meaning(kSpread));
  add(K("mesh.total_mass", T::Number)
          .in(kLines)
          .unit("kg")
          .computed("0.1 * mesh.n")
          .positive()
          .meaning(kSpread));
  add(K("mesh.mass", T::Number)
          .in({"grid", "cantilever", "chain", "hair", "obj"})
          .unit("kg")
          .computed("mesh.total_mass / particles")
          .positive()
          .example("0.01")
          .meaning(kEach));
}

/// Adds the [mesh] keys of obj, the oscillators and particles.
void add_mesh_other_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  // obj: a Wavefront file.
  add(K("mesh.file", T::String)
          .in({"obj"})
          .example("'meshes/square.obj'")
          .meaning("Wavefront OBJ file (v and f lines), relative to the scene file's folder"));
  add(K("mesh.scale", T::Number)
          .in({"obj"})
          .def("1")
          .positive()
          .meaning("factor applied to the OBJ coordinates"));
  add(K("mesh.translate", T::Vector3)
          .in({"obj"})
          .unit("m")
          .def("[0, 0, 0]")
          .meaning("shift added after scaling"));
  add(K("mesh.total_mass", T::Number).in({"obj"}).unit("kg").def("1").positive().meaning(kSpread));
  add(K("mesh.pins", T::Integers)
          .in({"obj", "particles"})
          .def("[]")
          .meaning("ids of the pinned particles (0-based; OBJ vertex k is id k - 1); negative ids "
                   "count from "
                   "the end"));
  add(K("mesh.pinned", T::Integers)
          .in({"obj", "particles"})
          .def("[]")
          .example("[0]")
          .replaced_by("mesh.pins")
          .meaning("the old name of mesh.pins"));
  // two-particle, damped-springs: oscillators with known behaviour.
  add(K("mesh.mass", T::Number)
          .in({"two-particle", "damped-springs", "particles"})
          .unit("kg")
          .def("1")
          .positive()
          .meaning("mass of each particle"));
  add(K("mesh.rest_length", T::Number)
          .in({"two-particle", "damped-springs"})
          .unit("m")
          .def("1")
          .positive()
          .meaning("rest length of the springs"));
  add(K("mesh.stretch", T::Number)
          .in({"two-particle"})
          .unit("m")
          .computed("0.1 * mesh.rest_length")
          .example("0.05")
          .meaning("initial extension of the spring (rest_length + stretch > 0)"));
  add(K("mesh.count", T::Integer)
          .in({"damped-springs"})
          .def("5")
          .between(1, 1e7)
          .meaning("number of oscillators, each a particle hanging from a pinned anchor"));
  add(K("mesh.spacing", T::Number)
          .in({"damped-springs"})
          .unit("m")
          .def("0.5")
          .positive()
          .meaning("distance between neighbouring anchors along x"));
  add(K("mesh.displacement", T::Number)
          .in({"damped-springs"})
          .unit("m")
          .def("0.2")
          .meaning("initial extension of every spring (rest_length + displacement > 0)"));
  // particles: written out by hand.
  add(K("mesh.positions", T::Rows)
          .in({"particles"})
          .unit("m")
          .example("[[0, 5, 0], [1, 5, 0], [0, 6, 0]]")
          .meaning("initial positions [x, y, z], one row per particle"));
  add(K("mesh.masses", T::Numbers)
          .in({"particles"})
          .unit("kg")
          .computed("mesh.mass for every particle")
          .example("[1, 2, 3]")
          .meaning("mass of each particle, one entry per particle; give this or mesh.mass"));
  add(K("mesh.velocities", T::Rows)
          .in({"particles"})
          .unit("m/s")
          .computed("all zero")
          .example("[[0, 0, 0], [0, 1, 0], [0, 0, 0]]")
          .meaning("initial velocities [vx, vy, vz], one row per particle"));
  add(K("mesh.springs", T::Rows)
          .in({"particles"})
          .def("[]")
          .example("[[0, 1, 100], [1, 2, 100, 1.5, 0.1]]")
          .meaning("springs [i, j, k] | [i, j, k, L] | [i, j, k, L, c]: ids, stiffness (N/m), rest "
                   "length (m; default: the initial distance), damping (N s/m; default: "
                   "springs.damping)"));
}

/// Adds [springs].
void add_springs_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  // [springs]: stiffness and damping of the springs each mesh type builds.
  add(K("springs.stiffness", T::Number)
          .in({"grid"})
          .unit("N/m")
          .def("1000")
          .non_negative()
          .meaning("stiffness of each spring kind whose own *_stiffness key is not given"));
  add(K("springs.stiffness", T::Number)
          .in({"cantilever", "two-particle"})
          .unit("N/m")
          .def("10000")
          .non_negative()
          .meaning("stiffness of each spring kind whose own *_stiffness key is not given"));
  add(K("springs.damping", T::Number)
          .in({"grid", "cantilever"})
          .unit("N s/m")
          .def("0")
          .non_negative()
          .meaning("axial damping of each spring kind whose own *_damping key is not given"));
  for (const char* kind : {"structural", "shear", "flexion"}) {
    add(K(std::string("springs.") + kind + "_stiffness", T::Number)
            .in(kLattices)
            .unit("N/m")
            .computed("springs.stiffness")
            .non_negative()
            .example("500")
            .meaning(std::string("stiffness of the ") + kind + " springs"));
    add(K(std::string("springs.") + kind + "_damping", T::Number)
            .in(kLattices)
            .unit("N s/m")
            .computed("springs.damping")
            .non_negative()
            .example("0.5")
            .meaning(std::string("axial damping of the ") + kind + " springs"));
  }
  add(K("springs.stiffness", T::Number)
          .in({"chain", "hair", "obj"})
          .unit("N/m")
          .def("1000")
          .non_negative()
          .meaning("stiffness of the stretch springs (chain and hair: i to i+1; obj: the edges)"));
  add(K("springs.damping", T::Number)
          .in({"chain", "hair", "obj", "two-particle"})
          .unit("N s/m")
          .def("0")
          .non_negative()
          .meaning("axial damping of the stretch springs"));
  add(K("springs.bend_stiffness", T::Number)
          .in({"hair"})
          .unit("N/m")
          .def("100")
          .non_negative()
          .meaning("stiffness of the bending springs, i to i+2"));
  add(K("springs.bend_stiffness", T::Number)
          .in({"obj"})
          .unit("N/m")
          .computed("0.1 * springs.stiffness")
          .non_negative()
          .example("50")
          .meaning("stiffness of the bending springs across each interior edge (between the two "
                   "opposite vertices); 0 with bend_damping = 0: none"));
  add(K("springs.bend_damping", T::Number)
          .in({"hair", "obj"})
          .unit("N s/m")
          .def("0")
          .non_negative()
          .meaning("axial damping of the bending springs"));
  add(K("springs.stiffness", T::Number)
          .in({"damped-springs"})
          .unit("N/m")
          .def("100")
          .non_negative()
          .meaning("stiffness of every oscillator's spring"));
  add(K("springs.max_damping", T::Number)
          .in({"damped-springs"})
          .unit("N s/m")
          .computed("2 sqrt(springs.stiffness * mesh.mass), critical damping")
          .non_negative()
          .example("5")
          .meaning("damping of the last oscillator; it grows linearly from 0 on the first"));
  add(K("springs.damping", T::Number)
          .in({"particles"})
          .unit("N s/m")
          .def("0")
          .non_negative()
          .meaning("damping of the mesh.springs rows that give none"));
}

/// Adds [[collision.mesh]] and [contact]: barrier contact (solver/contact/, docs/contact.md).
void add_contact_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  // [[collision.mesh]]: triangle-mesh obstacles, under [contact] only.
  const std::vector<std::string> contact_needs = {"contact.distance=0.001",
                                                  "integrator.method=implicit"};
  std::vector<std::string> mesh_needs = contact_needs;
  mesh_needs.push_back("collision.mesh.file='meshes/box.obj'");
  add(K("collision.mesh.file", T::String)
          .example("'meshes/box.obj'")
          .needs(contact_needs)
          .meaning("Wavefront OBJ file of the obstacle (v and f lines), relative to the scene "
                   "file's folder; needs [contact]"));
  add(K("collision.mesh.scale", T::Number)
          .def("1")
          .positive()
          .needs(mesh_needs)
          .meaning("factor applied to the OBJ coordinates"));
  add(K("collision.mesh.translate", T::Vector3)
          .unit("m")
          .def("[0, 0, 0]")
          .needs(mesh_needs)
          .meaning("offset added after scaling"));
  add(K("collision.mesh.friction", T::Number)
          .def("0")
          .non_negative()
          .needs(mesh_needs)
          .meaning("Coulomb friction coefficient of the contact"));
  add(K("collision.mesh.velocity", T::Vector3)
          .unit("m/s")
          .def("[0, 0, 0]")
          .needs(mesh_needs)
          .meaning("translation velocity of the obstacle's rigid motion (as [[pin_motion]])"));
  add(K("collision.mesh.angular_velocity", T::Vector3)
          .unit("rad/s")
          .def("[0, 0, 0]")
          .needs(mesh_needs)
          .meaning("angular velocity of its rigid motion, about center"));
  add(K("collision.mesh.center", T::Vector3)
          .unit("m")
          .computed("the centre of the obstacle's bounding box")
          .needs(mesh_needs)
          .meaning("centre of the rotation at start"));
  add(K("collision.mesh.start", T::Number)
          .unit("s")
          .def("0")
          .non_negative()
          .needs(mesh_needs)
          .meaning("time the motion starts"));
  add(K("collision.mesh.stop", T::Number)
          .unit("s")
          .computed("never")
          .positive()
          .example("0.5")
          .needs(mesh_needs)
          .meaning("time the motion stops (after start)"));

  // [contact]: barrier contact (solver/contact/, docs/contact.md).
  add(K("contact.distance", T::Number)
          .needs({"integrator.method=implicit"})
          .unit("m")
          .def("0.001")
          .positive()
          .meaning("dhat: gaps below it are in contact and feel the barrier kappa b(d), b IPC's "
                   "clamped log barrier on the gap"));
  add(K("contact.stiffness", T::Number)
          .needs({"integrator.method=implicit"})
          .unit("N/m")
          .def("0")
          .non_negative()
          .meaning("kappa, the barrier's stiffness; 0 chooses it from the masses, gravity and "
                   "dt and doubles it when a gap falls below 0.05 dhat (up to 1000 times)"));
  add(K("contact.friction_velocity", T::Number)
          .needs({"integrator.method=implicit"})
          .unit("m/s")
          .def("0.001")
          .positive()
          .meaning("epsilon_v: slip speeds below it are smoothed static friction"));
  add(K("contact.thickness", T::Number)
          .needs({"integrator.method=implicit"})
          .unit("m")
          .def("0")
          .non_negative()
          .meaning("gaps are measured from this offset of the cloth's surface (a thickness; "
                   "between two parts of the cloth under self, 2 thickness)"));
  add(K("contact.self", T::Boolean)
          .needs({"integrator.method=implicit"})
          .def("false")
          .meaning("self-contact: the barrier also acts between the cloth's own triangles and "
                   "edges (point-triangle and edge-edge pairs sharing no particle)"));
  add(K("contact.friction", T::Number)
          .needs({"integrator.method=implicit", "contact.self=true"})
          .def("0")
          .non_negative()
          .meaning("mu, Coulomb friction between parts of the cloth (with self)"));
}

/// Adds [forces] and [collision.*].
void add_scene_part_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  // [forces]: each present only when given.
  add(K("forces.gravity", T::Vector3)
          .unit("m/s^2")
          .computed("none (no gravity force)")
          .example("[0, -9.81, 0]")
          .meaning("gravitational acceleration; every particle feels m g"));
  add(K("forces.drag", T::Number)
          .unit("kg/s")
          .def("0")
          .non_negative()
          .meaning("air drag per particle: f = -drag (v - wind)"));
  add(K("forces.wind", T::Vector3)
          .unit("m/s")
          .def("[0, 0, 0]")
          .meaning("air velocity that the drag pulls towards; needs forces.drag > 0"));

  // [collision.*]: one table or an array of tables ([[collision.ground]]) per kind.
  add(K("collision.ground.normal", T::Vector3)
          .def("[0, 1, 0]")
          .meaning("normal of the plane, pointing to the free side (any nonzero length)"));
  add(K("collision.ground.height", T::Number)
          .unit("m")
          .def("0")
          .meaning("the plane is n . x = height (n the unit normal); particles stay at n . x >= "
                   "height"));
  add(K("collision.ground.friction", T::Number)
          .def("0")
          .non_negative()
          .meaning("Coulomb friction coefficient of the contact"));
  add(K("collision.sphere.center", T::Vector3)
          .unit("m")
          .def("[0, 0, 0]")
          .meaning("centre of the sphere"));
  add(K("collision.sphere.radius", T::Number)
          .unit("m")
          .def("0.5")
          .positive()
          .meaning("radius of the sphere"));
  add(K("collision.sphere.friction", T::Number)
          .def("0")
          .non_negative()
          .meaning("Coulomb friction coefficient of the contact"));
  add(K("collision.sphere.velocity", T::Vector3)
          .unit("m/s")
          .def("[0, 0, 0]")
          .needs({"contact.distance=0.001", "integrator.method=implicit"})
          .meaning("the sphere's centre moves at this velocity from t = 0 (needs [contact])"));
  add(K("collision.sphere.angular_velocity", T::Vector3)
          .unit("rad/s")
          .def("[0, 0, 0]")
          .needs({"contact.distance=0.001", "integrator.method=implicit"})
          .meaning("the sphere spins about its centre (a vector along the axis, right-handed); "
                   "friction drags the cloth with its surface (needs [contact])"));
  add_contact_keys(t);
}

/// Adds [bending]: angle-based bending as element sets (solver/forces/bending.hpp); its keys'
/// variants are the model.
void add_bending_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("bending.model", T::String)
          .choices({"rod", "dihedral", "quadratic", "shell"})
          .example("'dihedral'")
          .meaning("rod: discrete elastic rods' curvature at every interior particle of a chain "
                   "or hair; dihedral: the hinge angle of discrete shells across every interior "
                   "edge of a grid or obj cloth; quadratic: the isometric quadratic model there "
                   "(constant Hessian, flat rest); shell: a plate's shape operator per triangle "
                   "from its edges' hinge angles, which converges to the Kirchhoff plate where "
                   "the hinge models stay mesh dependent (on the alternating grid a pure twist "
                   "is 2x stiff: mesh.diagonals = 'one-way' makes it exact); beside the spring "
                   "meshes' own bending springs"));
  add(K("bending.stiffness", T::Number)
          .in({"rod"})
          .unit("N m^2")
          .positive()
          .example("1e-3")
          .meaning("the strand's bending rigidity EI: a bend of curvature kappa stores 1/2 EI "
                   "kappa^2 per unit length"));
  add(K("bending.stiffness", T::Number)
          .in({"dihedral", "quadratic", "shell"})
          .unit("N m")
          .positive()
          .example("1e-3")
          .meaning("the sheet's bending rigidity D: a cylindrical bend of curvature kappa about "
                   "a grid axis stores 1/2 D kappa^2 per unit area"));
  add(K("bending.damping", T::Number)
          .in({"rod", "dihedral", "quadratic", "shell"})
          .unit("s")
          .def("0")
          .non_negative()
          .meaning("Rayleigh damping beta on the bending rates: each element dissipates beta/2 "
                   "times its energy's quadratic form on the rates of its angles (the rate of the "
                   "curvature for rod), so a small bending oscillation of angular frequency omega "
                   "is damped with ratio beta omega / 2 and no rigid motion is damped; the "
                   "implicit family, explicit steppers, cvode, ida and vbd take it; xpbd, "
                   "fast-mass-spring and ceres-implicit refuse it"));
  add(K("bending.rest", T::String)
          .in({"rod"})
          .def("'initial'")
          .choices({"initial", "straight"})
          .meaning("the rest curvature: the initial shape's (a curly hair keeps its curl) or "
                   "none"));
  add(K("bending.rest", T::String)
          .in({"dihedral", "shell"})
          .def("'initial'")
          .choices({"initial", "flat"})
          .meaning("the rest angles: the initial shape's or flat"));
  add(K("bending.projection", T::String)
          .in({"dihedral", "shell"})
          .def("'gauss-newton'")
          .choices({"gauss-newton", "eigenvalues"})
          .meaning("how the implicit family (with integrator.clamp_compressed) and vbd make each "
                   "element's Hessian PSD: gauss-newton keeps only the angles' gradients' term (k "
                   "grad theta grad theta^T for a hinge), PSD by construction and exact at rest; "
                   "eigenvalues clamps the exact Hessian's negative eigenvalues, 2-7x the "
                   "assembly's cost (on a draped cloth Newton took as many iterations or more "
                   "with it)"));
  add(K("bending.poisson", T::Number)
          .in({"shell"})
          .def("0")
          .meaning("the plate's Poisson ratio nu in (-1, 0.5]: a bend stores D/2 [(1 - nu) "
                   "|S|^2 + nu (tr S)^2] per unit area (S the shape operator), so 0 makes a "
                   "strip the Euler-Bernoulli beam of rigidity D times its width"));
  add(K("bending.rest", T::String)
          .in({"quadratic"})
          .def("'initial'")
          .choices({"initial", "flat"})
          .meaning("flat either way (the model's rest is flat): 'initial' refuses a mesh whose "
                   "initial shape is bent at some edge, 'flat' takes its flat development"));
}

/// Adds [[pin_motion]], [strain_limit] and [ode].
void add_pin_strain_ode_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  // [[pin_motion]]: scripted pins, one table (or array element) per rigid motion.
  add(K("pin_motion.box", T::Rows)
          .unit("m")
          .computed("every pinned particle")
          .example("[[-1, 4, -1], [0.5, 5.5, 1]]")
          .meaning("[[xmin, ymin, zmin], [xmax, ymax, zmax]]: the pinned particles whose initial "
                   "position lies inside follow this motion (each pin follows one motion)"));
  add(K("pin_motion.velocity", T::Vector3)
          .unit("m/s")
          .def("[0, 0, 0]")
          .meaning("translation velocity u: x(t) = c + u tau + R(w tau) (X - c), tau = t - start"));
  add(K("pin_motion.angular_velocity", T::Vector3)
          .unit("rad/s")
          .def("[0, 0, 0]")
          .meaning("rotation w: axis times rate, about the centre c (which moves with u)"));
  add(K("pin_motion.center", T::Vector3)
          .unit("m")
          .computed("mean initial position of the pins it moves")
          .example("[0, 5, 0]")
          .meaning("centre c of the rotation at the start"));
  add(K("pin_motion.start", T::Number)
          .unit("s")
          .def("0")
          .non_negative()
          .meaning("the pins rest until this time"));
  add(K("pin_motion.stop", T::Number)
          .unit("s")
          .computed("never")
          .positive()
          .example("0.5")
          .meaning("the pins stop here and stay (must be after start)"));

  // [strain_limit]: Provot's strain limiting after each step.
  add(K("strain_limit.max_strain", T::Number)
          .def("0.1")
          .positive()
          .meaning("largest relative stretch (l - L) / L of the structural, shear, stretch and "
                   "edge springs"));
  add(K("strain_limit.passes", T::Integer)
          .def("10")
          .between(1, 1e6)
          .meaning("most Gauss-Seidel passes over the springs per step"));

  // [ode]: a scalar or planar test equation instead of a mesh.
  add(K("ode.problem", T::String)
          .choices({"decay", "circle"})
          .example("'decay'")
          .meaning("decay: x' = -rate x; circle: (x, y)' = (-y, x)"));
  add(K("ode.rate", T::Number)
          .in({"decay"})
          .unit("1/s")
          .def("1")
          .meaning("decay rate (negative: growth)"));
  add(K("ode.x0", T::Number).in({"decay"}).def("1").meaning("initial value"));
  add(K("ode.x0", T::Numbers).in({"circle"}).def("[1, 0]").meaning("initial point [x, y]"));
}

/// Adds [fluid]: SPH particles in blocks, a tank and obstacles.
void add_fluid_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::string layers =
      "layers of boundary particles (the dummy particles of Adami et al. 2012, mass rho0 "
      "dx^dimension) inside its surface, at least ceil(fluid.support_factor)";
  add(K("fluid.dimension", T::Integer)
          .def("3")
          .between(2, 3)
          .meaning("2: particles in one plane z = const (the validation cases; every box corner "
                   "has that z), 3: space"));
  add(K("fluid.spacing", T::Number)
          .unit("m")
          .positive()
          .example("0.02")
          .meaning("particle spacing dx: each fluid particle stands for a cube (2D: square) of "
                   "side dx, of mass rest_density dx^dimension"));
  add(K("fluid.rest_density", T::Number)
          .unit("kg/m^3")
          .def("1000")
          .positive()
          .meaning("rest density rho0 of the fluid (water: 1000)"));
  add(K("fluid.kernel", T::String)
          .def("'cubic-spline'")
          .choices({"cubic-spline", "wendland-c2"})
          .meaning("SPH kernel: the cubic B-spline (Monaghan 1992) or Wendland's C2"));
  add(K("fluid.support_factor", T::Number)
          .def("2")
          .between(1.5, 4)
          .meaning("kernel support radius in spacings (2: about 13 neighbours in 2D, 33 in 3D)"));
  add(K("fluid.viscosity", T::Number)
          .unit("m^2/s")
          .def("0")
          .non_negative()
          .meaning("kinematic viscosity nu between fluid particles (Morris et al. 1997); the "
                   "walls slip"));
  add(K("fluid.gradient_correction", T::Boolean)
          .def("true")
          .meaning("divide the pressure forces by the kernel gradient's mean first moment over "
                   "the particles with a full kernel, so that a linear pressure field has its "
                   "true slope (still water's pressure is otherwise 1.5-2% steeper than rho0 g "
                   "with the cubic spline); one factor for the whole fluid, so momentum is "
                   "conserved"));
  add(K("fluid.block.lower", T::Vector3)
          .unit("m")
          .example("[0, 0, 0]")
          .meaning("lower corner of a block of water ([[fluid.block]], one or more, disjoint), "
                   "filled on the lattice of spacing dx"));
  add(K("fluid.block.upper", T::Vector3)
          .unit("m")
          .example("[0.1, 0.2, 0.1]")
          .meaning("upper corner of the block of water"));
  add(K("fluid.tank.lower", T::Vector3)
          .unit("m")
          .example("[0, 0, 0]")
          .meaning("lower corner of the inside of the tank: walls at x (and z in 3D) and a "
                   "floor below y, open at the top; the water must lie inside"));
  add(K("fluid.tank.upper", T::Vector3)
          .unit("m")
          .example("[0.4, 0.3, 0.1]")
          .meaning("upper corner of the inside of the tank (the walls' height is its y)"));
  add(K("fluid.tank.layers", T::Integer)
          .computed("ceil(fluid.support_factor)")
          .between(2, 10)
          .example("3")
          .meaning("layers of boundary particles (the dummy particles of Adami et al. 2012, mass "
                   "rho0 dx^dimension) in the walls and floor, at least "
                   "ceil(fluid.support_factor)"));
  add(K("fluid.obstacle.lower", T::Vector3)
          .unit("m")
          .example("[0.3, 0, 0]")
          .meaning("lower corner of a solid box in the fluid ([[fluid.obstacle]], any number)"));
  add(K("fluid.obstacle.upper", T::Vector3)
          .unit("m")
          .example("[0.34, 0.06, 0.1]")
          .meaning("upper corner of the solid box"));
  add(K("fluid.obstacle.layers", T::Integer)
          .computed("ceil(fluid.support_factor)")
          .between(2, 10)
          .example("3")
          .meaning(layers + " (all of it when thinner)"));
}

/// Adds [time], [output] and [run].
void add_run_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  // [time], [output], [run]: every scene has them.
  add(K("time.dt", T::Number).unit("s").def("0.001").positive().meaning("time step"));
  add(K("time.duration", T::Number)
          .unit("s")
          .def("1")
          .non_negative()
          .meaning("simulated time; the last step is shortened to end on it"));
  add(K("output.dir", T::String)
          .computed("'out/<scene file name without .toml>'")
          .example("'out/walk'")
          .meaning("output folder, relative to the current folder (not the scene file's)"));
  add(K("output.every", T::Integer)
          .computed("steps / 50, at least 1")
          .between(0, kMaxSteps)
          .example("5")
          .meaning("a frame every this many steps; 0: none; give this or output.interval"));
  add(K("output.interval", T::Number)
          .unit("s")
          .computed("none (frames by output.every)")
          .positive()
          .example("0.1")
          .meaning("a frame every this much simulated time; give this or output.every"));
  add(K("output.log_every", T::Integer)
          .computed("steps / 10000, at least 1")
          .between(1, kMaxSteps)
          .example("5")
          .meaning("a log.csv row every this many steps"));
  add(K("output.vtk", T::Boolean).def("true").meaning("write frames as legacy VTK for ParaView"));
  add(K("output.png", T::Boolean)
          .def("true")
          .meaning("write final.vtk and draw final.png at the end of the run"));
  add(K("run.energy_growth_limit", T::Number)
          .def("10")
          .positive()
          .meaning(
              "stop (exit 3) once total energy grows by this many times the scene's energy scale"));
  add(K("run.allow_not_converged", T::Boolean)
          .def("false")
          .meaning("accept steps that miss their tolerance (with a warning) instead of stopping"));
  add(K("run.max_step_halvings", T::Integer)
          .def("0")
          .between(0, 30)
          .meaning("retry a failed step as two half steps, down to h / 2^this"));
  add(K("run.checkpoint_every", T::Integer)
          .def("0")
          .between(0, kMaxSteps)
          .meaning("write checkpoint.bin every this many steps; 0: not by count"));
  add(K("run.checkpoint_seconds", T::Number)
          .unit("s")
          .def("300")
          .positive()
          .meaning("write checkpoint.bin when this much wall time has passed since the last"));
}

std::vector<SceneKey> make_table() {
  std::vector<SceneKey> t;
  for (auto section :
       {add_mesh_lattice_keys, add_mesh_line_keys, add_mesh_other_keys, add_springs_keys,
        add_scene_part_keys, add_bending_keys, add_pin_strain_ode_keys, add_integrator_keys})
    section(t);
  // [integrator]: each method family's keys (problems/methods/<family>.cpp), in table order.
  for (const MethodFamily& family : method_families())
    if (family.add_keys) family.add_keys(t);
  add_fluid_keys(t);
  add_run_keys(t);
  return t;
}

bool applies(const SceneKey& k, const std::string& variant) {
  return k.when.empty() || std::find(k.when.begin(), k.when.end(), variant) != k.when.end();
}

/// The section of a dotted name: everything before the last dot.
std::string section_of(const std::string& name) { return name.substr(0, name.rfind('.')); }

/// "mesh.type = grid, cantilever" for a key with variants; "" otherwise.
std::string applies_text(const SceneKey& k) {
  if (k.when.empty()) return "";
  const std::string selector = k.name.rfind("integrator.", 0) == 0 ? "integrator.method"
                               : k.name.rfind("ode.", 0) == 0      ? "ode.problem"
                               : k.name.rfind("bending.", 0) == 0  ? "bending.model"
                                                                   : "mesh.type";
  return selector + " = " + join(k.when, ", ");
}

std::string needs_text(const SceneKey& k) {
  std::vector<std::string> n;
  for (const auto& item : k.needs) {
    const auto eq = item.find('=');
    n.push_back(item.substr(0, eq) + " = " + item.substr(eq + 1));
  }
  return join(n, " and ");
}

struct AuditState {
  std::mutex mutex;
  SceneKeyAudit audit;
};
AuditState& audit_state() {
  static AuditState s;
  return s;
}

}  // namespace

std::string shortest_number(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

bool KeyRange::contains(double v) const {
  if (lo && (lo_open ? !(v > *lo) : !(v >= *lo))) return false;
  if (hi && (hi_open ? !(v < *hi) : !(v <= *hi))) return false;
  return true;
}

namespace {
/// A bound: integers exactly (4611686018427387904, not 4.611686018427388e+18).
std::string bound(double v) {
  if (v == std::floor(v) && std::fabs(v) < 9.2e18) return std::to_string(static_cast<long long>(v));
  return shortest_number(v);
}
}  // namespace

std::string KeyRange::text() const {
  if (lo && hi)
    return std::string(lo_open ? "(" : "[") + bound(*lo) + ", " + bound(*hi) +
           (hi_open ? ")" : "]");
  if (lo) return std::string(lo_open ? "> " : ">= ") + bound(*lo);
  if (hi) return std::string(hi_open ? "< " : "<= ") + bound(*hi);
  return "";
}

const std::vector<SceneKey>& scene_keys() {
  static const std::vector<SceneKey> table = make_table();
  return table;
}

std::string key_without_indices(const std::string& path) {
  std::string out;
  out.reserve(path.size());
  for (size_t i = 0; i < path.size(); ++i) {
    if (path[i] == '[') {
      const size_t close = path.find(']', i);
      if (close == std::string::npos) break;
      i = close;
      continue;
    }
    out += path[i];
  }
  return out;
}

const SceneKey* find_scene_key(const std::string& name, const std::string& variant) {
  for (const auto& k : scene_keys())
    if (k.name == name && applies(k, variant)) return &k;
  return nullptr;
}

const char* to_string(KeyType t) {
  switch (t) {
    case KeyType::Number:
      return "number";
    case KeyType::Integer:
      return "integer";
    case KeyType::Boolean:
      return "boolean";
    case KeyType::String:
      return "string";
    case KeyType::Vector3:
      return "[x, y, z]";
    case KeyType::Numbers:
      return "[numbers]";
    case KeyType::Integers:
      return "[integers]";
    case KeyType::Rows:
      return "[[numbers], ...]";
  }
  return "";
}

std::string default_text(const SceneKey& k) { return k.def.empty() ? "required" : k.def; }

std::string range_text(const SceneKey& k) {
  if (!k.choices.empty()) {
    std::vector<std::string> quoted;
    for (const auto& c : k.choices) quoted.push_back("'" + c + "'");
    return join(quoted, " | ");
  }
  return k.range.text();
}

std::string scene_keys_text(const std::string& section) {
  std::ostringstream os;
  for (const auto& k : scene_keys()) {
    if (!section.empty() && k.name.rfind(section + ".", 0) != 0) continue;
    os << k.name << "  " << to_string(k.type);
    if (!k.unit.empty()) os << " (" << k.unit << ")";
    os << ", default " << default_text(k);
    if (const std::string r = range_text(k); !r.empty()) os << ", allowed " << r;
    if (const std::string a = applies_text(k); !a.empty()) os << "; with " << a;
    if (!k.needs.empty()) os << "; takes effect with " << needs_text(k);
    if (!k.build.empty()) os << "; needs a build with " << k.build;
    os << "\n    ";
    if (!k.replaced_by.empty()) os << "DEPRECATED: use " << k.replaced_by << "; ";
    os << k.meaning << "\n";
  }
  return os.str();
}

std::string scene_keys_markdown() {
  std::ostringstream os;
  os << "# Scene keys\n\n"
        "<!-- Generated by `hooke keys --markdown` from problems/scene_keys.cpp, the table the "
        "scene readers check themselves against; the test SceneKeys.ReferenceIsFresh fails when "
        "this file differs. Do not edit by hand. -->\n\n"
        "Every key a scene file (TOML) accepts, by section. `hooke keys [SECTION]` prints the "
        "same list in the terminal; `--set section.key=value` changes any key from the command "
        "line. A key that does not apply to the scene (another mesh type or method, or a setting "
        "that makes it ineffective) is refused with the reason, never silently ignored.\n\n"
        "Paths: `mesh.file` is relative to the folder of the scene file; `output.dir` is "
        "relative to the current folder (where hooke runs). The resolved scene that a run "
        "writes (`scene.toml` in its output folder) holds absolute paths, so it runs from "
        "anywhere.\n\n"
        "Array tables: `[collision.ground]`, `[collision.sphere]`, `[pin_motion]`, "
        "`[fluid.block]` and `[fluid.obstacle]` may be given once or as arrays "
        "(`[[collision.sphere]]`), one table per collider, motion or box.\n";
  std::string current;
  for (const auto& k : scene_keys()) {
    const std::string sec = section_of(k.name);
    if (sec != current) {
      current = sec;
      os << "\n## [" << sec << "]\n\n"
         << "| key | applies to | type | unit | default | allowed | meaning |\n"
         << "|---|---|---|---|---|---|---|\n";
    }
    std::string meaning = k.meaning;
    if (!k.replaced_by.empty())
      meaning = "**Deprecated**: use `" + k.replaced_by + "` (accepted with a warning); " + meaning;
    std::string applies_to = applies_text(k);
    if (!k.needs.empty()) applies_to += (applies_to.empty() ? "" : "; ") + needs_text(k);
    if (!k.build.empty()) applies_to += (applies_to.empty() ? "" : "; ") + k.build + " build";
    std::string range = range_text(k);
    // A pipe inside a cell would split the Markdown table.
    for (std::string* cell : {&meaning, &applies_to, &range}) {
      for (size_t p = 0; (p = cell->find('|', p)) != std::string::npos; p += 2)
        cell->replace(p, 1, "\\|");
    }
    std::string type = to_string(k.type);
    os << "| `" << k.name << "` | " << applies_to << " | " << type << " | " << k.unit << " | "
       << (k.computed || k.def.empty() ? default_text(k) : "`" + k.def + "`") << " | " << range
       << " | " << meaning << " |\n";
  }
  return os.str();
}

SceneKeyAudit scene_key_audit() {
  std::lock_guard<std::mutex> lock(audit_state().mutex);
  return audit_state().audit;
}

void reset_scene_key_audit() {
  std::lock_guard<std::mutex> lock(audit_state().mutex);
  audit_state().audit = {};
}

void note_scene_key_use(const SceneKey* entry) {
  std::lock_guard<std::mutex> lock(audit_state().mutex);
  audit_state().audit.used.insert(entry);
}

void note_scene_key_problem(const std::string& problem) {
  std::lock_guard<std::mutex> lock(audit_state().mutex);
  auto& p = audit_state().audit.problems;
  if (std::find(p.begin(), p.end(), problem) == p.end()) p.push_back(problem);
}

}  // namespace hooke
