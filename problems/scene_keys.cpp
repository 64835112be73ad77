#include "problems/scene_keys.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <mutex>
#include <sstream>

#include "hooke/integrators/implicit_stepper.hpp"

namespace hooke {

namespace {

/// Builds one SceneKey: K("mesh.nx", KeyType::Integer).in({"grid"}).def("20")...
struct K {
  SceneKey k;
  K(std::string name, KeyType type) {
    k.name = std::move(name);
    k.type = type;
  }
  K& in(std::vector<std::string> variants) {
    k.when = std::move(variants);
    return *this;
  }
  K& unit(std::string u) {
    k.unit = std::move(u);
    return *this;
  }
  K& def(std::string d) {
    k.def = std::move(d);
    return *this;
  }
  /// A default that depends on other keys or the build, in words.
  K& computed(std::string d) {
    k.def = std::move(d);
    k.computed = true;
    return *this;
  }
  K& range(std::optional<double> lo, bool lo_open, std::optional<double> hi, bool hi_open) {
    k.range = {lo, hi, lo_open, hi_open};
    return *this;
  }
  K& positive() { return range(0.0, true, std::nullopt, false); }
  K& non_negative() { return range(0.0, false, std::nullopt, false); }
  /// An integer option held in an int: from lo to the largest int.
  K& int_from(double lo) { return between(lo, 2147483647.0); }
  K& between(double lo, double hi) { return range(lo, false, hi, false); }
  K& choices(std::vector<std::string> c) {
    k.choices = std::move(c);
    return *this;
  }
  K& needs(std::vector<std::string> n) {
    k.needs = std::move(n);
    return *this;
  }
  K& example(std::string e) {
    k.example = std::move(e);
    return *this;
  }
  K& replaced_by(std::string r) {
    k.replaced_by = std::move(r);
    return *this;
  }
  K& build(std::string b) {
    k.build = std::move(b);
    return *this;
  }
  SceneKey meaning(std::string m) {
    k.meaning = std::move(m);
    return k;
  }
};

using T = KeyType;
constexpr double kMaxCount = 1e9;                    // nx, ny, n: the builders' bound
constexpr double kMaxSteps = 4611686018427387904.0;  // 2^62: step counts

const std::vector<std::string> kLattices = {"grid", "cantilever"};
const std::vector<std::string> kLines = {"chain", "hair"};
const std::vector<std::string> kImplicit = {"implicit", "implicit-midpoint", "bdf2"};
const std::vector<std::string> kSundials = {"cvode", "ida"};
// Methods that read integrator.adaptive (all but cvode and ida, which control their error
// always), and those that can run under error control (MethodInfo::error_estimate_order > 0).
const std::vector<std::string> kFixedStepFamilies = {"forward-euler",
                                                     "symplectic-euler",
                                                     "midpoint",
                                                     "trapezoid",
                                                     "rk4",
                                                     "dopri5",
                                                     "bs32",
                                                     "implicit",
                                                     "implicit-midpoint",
                                                     "bdf2",
                                                     "ceres-implicit",
                                                     "fast-mass-spring",
                                                     "vbd",
                                                     "xpbd"};
const std::vector<std::string> kAdaptive = {
    "dopri5",           "bs32", "implicit", "implicit-midpoint", "bdf2", "ceres-implicit",
    "fast-mass-spring", "vbd",  "xpbd"};

const std::string kWholeStepTolerance =
    "stop once h^2 max_p |grad_p g| / m_p, the distance to the exact step the mass term alone "
    "gives, is at most tolerance times the longest side of the bounding box; 0: a fixed "
    "iteration count";
const std::string kNewtonStop =
    "Newton stops when max |dv| <= tolerance * max(|v1|, |v0|) (infinity norms)";
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

/// Adds the Newton keys of the implicit methods (implicit-midpoint iterates by default).
void add_newton_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("integrator.newton_iterations", T::Integer)
          .in({"implicit", "bdf2"})
          .def("1")
          .between(1, 100000)
          .meaning("most Newton iterations per step; 1 is the linearised step"));
  add(K("integrator.newton_iterations", T::Integer)
          .in({"implicit-midpoint"})
          .def(std::to_string(ImplicitOptions::kMidpointNewtonIterations))
          .between(1, 100000)
          .meaning("most Newton iterations per step; 1 is the linearised step (which gains "
                   "energy on stiff cloth); Newton stops early when it cannot converge"));
  add(K("integrator.tolerance", T::Number)
          .in({"implicit", "bdf2"})
          .def("1e-10")
          .positive()
          .needs({"integrator.newton_iterations=2"})
          .meaning(kNewtonStop));
  add(K("integrator.tolerance", T::Number)
          .in({"implicit-midpoint"})
          .def("1e-08")
          .positive()
          .meaning(kNewtonStop));
  add(K("integrator.discrete_gradient", T::Boolean)
          .in({"implicit-midpoint"})
          .def("true")
          .meaning("Newton converges to the energy-momentum step (the springs' discrete gradient, "
                   "Simo and Tarnow 1992), which conserves energy exactly; false: the classical "
                   "rule, f at the midpoint"));
}

/// Adds integrator.method and the keys of the implicit family.
void add_implicit_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  // [integrator]: the method, then the keys of the chosen method.
  add(K("integrator.method", T::String)
          .def("'symplectic-euler'")
          .choices({"forward-euler", "symplectic-euler", "midpoint", "trapezoid", "rk4", "dopri5",
                    "bs32", "implicit", "implicit-midpoint", "bdf2", "cvode", "ida",
                    "ceres-implicit", "fast-mass-spring", "vbd", "xpbd", "wcsph", "iisph", "dfsph"})
          .meaning(
              "the time stepper; explicit methods (the first seven) take no other keys "
              "but the error control's; wcsph, iisph and dfsph step [fluid] scenes, and only they "
              "do"));
  add(K("integrator.adaptive", T::Boolean)
          .in(kFixedStepFamilies)
          .def("false")
          .meaning(
              "error-controlled steps (methods with a local error estimate: dopri5, bs32, "
              "implicit, implicit-midpoint, bdf2; ceres-implicit, fast-mass-spring, vbd and xpbd "
              "by step doubling): time.dt is the first step, rtol and atol bound each "
              "step's local error"));
  add(K("integrator.rtol", T::Number)
          .in(kAdaptive)
          .def("1e-08")
          .range(0, true, 1, true)
          .needs({"integrator.adaptive=true"})
          .meaning("relative tolerance of the local error test on [x; v], as CVODE's"));
  add(K("integrator.atol", T::Number)
          .in(kAdaptive)
          .def("1e-10")
          .positive()
          .needs({"integrator.adaptive=true"})
          .meaning("absolute tolerance of the local error test (m for x, m/s for v), as CVODE's"));
  add(K("integrator.max_dt", T::Number)
          .in(kAdaptive)
          .unit("s")
          .def("0")
          .non_negative()
          .needs({"integrator.adaptive=true"})
          .meaning("largest step under error control; 0: no cap"));
  add(K("integrator.beta", T::Number)
          .in({"implicit"})
          .def("1")
          .between(0, 1)
          .meaning(
              "(M - beta h D - beta h^2 K) dv = h (f + beta h K v): 1 backward Euler, 0 symplectic "
              "Euler"));
  add(K("integrator.linear_solver", T::String)
          .in(kImplicit)
          .computed("'cholmod' ('pcg-block' without CHOLMOD)")
          .choices({"cholmod", "pcg-cholmod", "pcg-nodal", "pcg-block", "pcg", "cg", "petsc",
                    "colored-gauss-seidel", "gauss-seidel", "jacobi"})
          .example("'pcg-nodal'")
          .meaning("linear backend of each Newton iteration (pcg = Jacobi-preconditioned CG, cg = "
                   "unpreconditioned; cholmod and pcg-* with CHOLMOD; petsc with PETSc)"));
  add(K("integrator.preconditioner", T::String)
          .in(kImplicit)
          .def("''")
          .choices({"", "cholmod", "nodal", "block", "jacobi", "none"})
          .needs({"integrator.linear_solver=pcg"})
          .example("'block'")
          .meaning("preconditioner of linear_solver = 'pcg' ('' = jacobi); 'pcg' + 'nodal' is "
                   "'pcg-nodal'"));
  add(K("integrator.petsc_options", T::String)
          .in(kImplicit)
          .def("''")
          .needs({"integrator.linear_solver=petsc"})
          .build("PETSc")
          .example("'-pc_type gamg'")
          .meaning("PETSc options of the KSP and PC, over hooke's defaults (CG preconditioned by "
                   "one hypre BoomerAMG per coordinate: an additive PCFIELDSPLIT of block size "
                   "3) and under the environment's PETSC_OPTIONS"));
  add_newton_keys(t);
  add(K("integrator.linear_tolerance", T::Number)
          .in(kImplicit)
          .def("1e-08")
          .positive()
          .needs({"integrator.linear_solver=pcg"})
          .meaning("relative residual at which an iterative linear backend stops"));
  add(K("integrator.max_linear_iterations", T::Integer)
          .in(kImplicit)
          .def("10000")
          .int_from(1)
          .needs({"integrator.linear_solver=pcg"})
          .meaning("iteration cap of an iterative linear backend"));
  add(K("integrator.clamp_compressed", T::Boolean)
          .in(kImplicit)
          .def("true")
          .meaning(
              "drop the indefinite part of compressed springs' stiffness, keeping the matrix SPD"));
}

/// Adds the keys of CVODE and IDA.
void add_sundials_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("integrator.rtol", T::Number)
          .in(kSundials)
          .def("1e-08")
          .range(0, true, 1, true)
          .build("SUNDIALS")
          .meaning("relative tolerance of the local error test on [x; v]"));
  add(K("integrator.atol", T::Number)
          .in(kSundials)
          .def("1e-10")
          .positive()
          .build("SUNDIALS")
          .meaning("absolute tolerance of the local error test (m for x, m/s for v)"));
  add(K("integrator.max_steps", T::Integer)
          .in(kSundials)
          .def("100000")
          .between(1, kMaxSteps)
          .build("SUNDIALS")
          .meaning("most internal steps per output step"));
  add(K("integrator.linear_solver", T::String)
          .in(kSundials)
          .def("'klu'")
          .choices({"klu", "spgmr"})
          .build("SUNDIALS")
          .meaning("klu: sparse direct LU of the 6n Newton matrix; spgmr: matrix-free GMRES with "
                   "a hooke linear backend as preconditioner"));
  add(K("integrator.preconditioner", T::String)
          .in(kSundials)
          .computed("'' = 'cholmod' ('pcg-block' without CHOLMOD)")
          .needs({"integrator.linear_solver=spgmr"})
          .build("SUNDIALS")
          .example("'pcg-block'")
          .meaning("linear backend (integrator.linear_solver's names) or 'none' that solves "
                   "SPGMR's preconditioner system M - g D - g^2 K"));
  add(K("integrator.preconditioner_tolerance", T::Number)
          .in(kSundials)
          .def("1e-10")
          .range(0, true, 1, true)
          .needs({"integrator.linear_solver=spgmr", "integrator.preconditioner=pcg-block"})
          .build("SUNDIALS")
          .meaning("relative residual of each iterative preconditioner solve"));
  add(K("integrator.petsc_options", T::String)
          .in(kSundials)
          .def("''")
          .needs({"integrator.linear_solver=spgmr", "integrator.preconditioner=petsc"})
          .build("SUNDIALS and PETSc")
          .example("'-pc_type gamg'")
          .meaning("PETSc options of the preconditioner's KSP and PC"));
  add(K("integrator.adams", T::Boolean)
          .in({"cvode"})
          .def("false")
          .build("SUNDIALS")
          .meaning("Adams-Moulton (non-stiff problems) instead of BDF"));
  add(K("integrator.max_order", T::Integer)
          .in({"cvode"})
          .computed("5 (12 with adams)")
          .between(1, 12)
          .build("SUNDIALS")
          .example("3")
          .meaning("largest method order: at most 5 for BDF, 12 for Adams"));
  add(K("integrator.nonlinear_solver", T::String)
          .in({"cvode"})
          .def("'newton'")
          .choices({"newton", "fixed-point"})
          .build("SUNDIALS")
          .meaning("Newton, or functional iteration (Adams only, no linear solves)"));
  add(K("integrator.max_order", T::Integer)
          .in({"ida"})
          .def("5")
          .between(1, 5)
          .build("SUNDIALS")
          .meaning("largest BDF order"));
}

/// Adds the keys of ceres-implicit.
void add_ceres_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("integrator.formulation", T::String)
          .in({"ceres-implicit"})
          .def("'residual'")
          .choices({"residual", "energy"})
          .build("Ceres")
          .meaning("least squares of the backward Euler residual, or of the incremental "
                   "potential (Gauss-Newton drops geometric stiffness: slower, looser)"));
  add(K("integrator.max_iterations", T::Integer)
          .in({"ceres-implicit"})
          .def("100")
          .int_from(1)
          .build("Ceres")
          .meaning("most Levenberg-Marquardt iterations per step"));
  for (const char* which : {"function", "gradient", "parameter"})
    add(K(std::string("integrator.") + which + "_tolerance", T::Number)
            .in({"ceres-implicit"})
            .def("1e-14")
            .non_negative()
            .build("Ceres")
            .meaning(std::string("Ceres' ") + which + " tolerance (0 disables that test)"));
  add(K("integrator.residual_tolerance", T::Number)
          .in({"ceres-implicit"})
          .def("1e-06")
          .non_negative()
          .build("Ceres")
          .meaning("a step converged only if |G| <= this * (|M dv / h| + |f|) on the free DOFs"));
  add(K("integrator.linear_solver", T::String)
          .in({"ceres-implicit"})
          .def("'sparse-normal-cholesky'")
          .choices({"sparse-normal-cholesky", "dense-qr", "cgnr"})
          .build("Ceres")
          .meaning("linear solver of each Levenberg-Marquardt iteration"));
  add(K("integrator.threads", T::Integer)
          .in({"ceres-implicit"})
          .def("1")
          .int_from(1)
          .build("Ceres")
          .meaning("threads Ceres uses"));
}

/// Adds the keys of local/global (fast-mass-spring).
void add_local_global_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("integrator.iterations", T::Integer)
          .in({"fast-mass-spring"})
          .def("10")
          .int_from(1)
          .build("CHOLMOD")
          .meaning("local/global iterations per step (at most, with a tolerance)"));
  add(K("integrator.tolerance", T::Number)
          .in({"fast-mass-spring"})
          .def("0")
          .range(0, false, 1, true)
          .build("CHOLMOD")
          .meaning(kWholeStepTolerance));
  add(K("integrator.warm_start", T::String)
          .in({"fast-mass-spring"})
          .def("'inertial'")
          .choices({"inertial", "previous"})
          .build("CHOLMOD")
          .meaning("first iterate: x0 + h v0 (inertial) or x0 (previous)"));
  add(K("integrator.acceleration", T::String)
          .in({"fast-mass-spring"})
          .def("'none'")
          .choices({"none", "chebyshev", "lbfgs"})
          .build("CHOLMOD")
          .meaning("plain local/global, Chebyshev (Wang 2015) or L-BFGS (Liu et al. 2017)"));
  add(K("integrator.chebyshev_rho", T::Number)
          .in({"fast-mass-spring"})
          .def("0")
          .range(0, false, 1, true)
          .needs({"integrator.acceleration=chebyshev"})
          .build("CHOLMOD")
          .meaning("spectral radius of the plain iteration; 0: estimated in every step"));
  add(K("integrator.chebyshev_delay", T::Integer)
          .in({"fast-mass-spring"})
          .def("10")
          .int_from(0)
          .needs({"integrator.acceleration=chebyshev"})
          .build("CHOLMOD")
          .meaning("plain iterations before Chebyshev starts (at least 2 when chebyshev_rho = 0)"));
  add(K("integrator.lbfgs_history", T::Integer)
          .in({"fast-mass-spring"})
          .def("5")
          .between(1, 1000)
          .needs({"integrator.acceleration=lbfgs"})
          .build("CHOLMOD")
          .meaning("(s, t) pairs L-BFGS keeps"));
  add(K("integrator.global_solver", T::String)
          .in({"fast-mass-spring"})
          .def("'cholmod'")
          .choices({"cholmod", "jacobi"})
          .build("CHOLMOD")
          .meaning("global step: exact prefactored solve, or one Jacobi sweep (pair it with "
                   "Chebyshev; not with L-BFGS)"));
  add(K("integrator.factor_precision", T::String)
          .in({"fast-mass-spring"})
          .def("'double'")
          .choices({"double", "single"})
          .build("CHOLMOD")
          .meaning("the factor the global step's solves read: as computed, or rounded to float "
                   "(half the bytes; each global step then corrects the iterate with its residual "
                   "in double, so the converged step is the same); global_solver = 'cholmod'"));
}

/// Adds the keys of vertex block descent (vbd).
void add_vbd_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("integrator.iterations", T::Integer)
          .in({"vbd"})
          .def("10")
          .int_from(1)
          .meaning("vertex block descent iterations (passes over the colours) per step (at most, "
                   "with a tolerance)"));
  add(K("integrator.tolerance", T::Number)
          .in({"vbd"})
          .def("0")
          .range(0, false, 1, true)
          .meaning(kWholeStepTolerance));
  add(K("integrator.initialization", T::String)
          .in({"vbd"})
          .def("'adaptive'")
          .choices({"adaptive", "previous", "inertial", "external"})
          .meaning(
              "first iterate: x0 + h v0 + h^2 alpha g with alpha from the last step's "
              "acceleration (adaptive, Chen et al. 2024), x0, x0 + h v0, or x0 + h v0 + h^2 g"));
  add(K("integrator.acceleration", T::String)
          .in({"vbd"})
          .def("'none'")
          .choices({"none", "chebyshev"})
          .meaning("plain vertex block descent, or Chebyshev (restarted when it raises the "
                   "objective)"));
  add(K("integrator.chebyshev_rho", T::Number)
          .in({"vbd"})
          .def("0.95")
          .range(0, true, 1, true)
          .needs({"integrator.acceleration=chebyshev"})
          .meaning("spectral radius assumed for the plain iteration"));
  add(K("integrator.line_search", T::Boolean)
          .in({"vbd"})
          .def("true")
          .meaning("backtrack each vertex's Newton step until its local objective falls; false: "
                   "the paper's plain step"));
}

/// Adds the keys of XPBD.
void add_xpbd_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  add(K("integrator.substeps", T::Integer)
          .in({"xpbd"})
          .def("10")
          .int_from(1)
          .meaning("substeps per step (Macklin et al. 2019)"));
  add(K("integrator.iterations", T::Integer)
          .in({"xpbd"})
          .def("1")
          .int_from(1)
          .meaning("constraint sweeps per substep"));
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

/// Adds the keys of the fluid methods (wcsph, iisph, dfsph).
void add_sph_method_keys(std::vector<SceneKey>& t) {
  auto add = [&t](SceneKey k) { t.push_back(std::move(k)); };
  const std::vector<std::string> sph = {"wcsph", "iisph", "dfsph"};
  const std::vector<std::string> implicit_sph = {"iisph", "dfsph"};
  add(K("integrator.sound_speed", T::Number)
          .in({"wcsph"})
          .unit("m/s")
          .positive()
          .example("20")
          .meaning("speed of sound c0; the Tait stiffness is B = rho0 c0^2 / gamma. Monaghan's "
                   "rule c0 = 10 max|v| keeps the density within about 1% of rho0"));
  add(K("integrator.gamma", T::Number)
          .in({"wcsph"})
          .def("7")
          .range(1, false, std::nullopt, false)
          .meaning("Tait exponent: p = B ((rho / rho0)^gamma - 1), clamped at 0"));
  add(K("integrator.tolerance", T::Number)
          .in(implicit_sph)
          .def("0.001")
          .positive()
          .meaning("the pressure solve stops when the mean density residual is at most this "
                   "times rho0 (0.001: 0.1%)"));
  add(K("integrator.min_iterations", T::Integer)
          .in(implicit_sph)
          .def("2")
          .int_from(1)
          .meaning("fewest relaxed Jacobi iterations of the pressure solve per step"));
  add(K("integrator.max_iterations", T::Integer)
          .in(implicit_sph)
          .def("200")
          .int_from(1)
          .meaning("most relaxed Jacobi iterations per step (then the step has not converged; "
                   ">= min_iterations)"));
  add(K("integrator.divergence_tolerance", T::Number)
          .in({"dfsph"})
          .def("0.001")
          .positive()
          .meaning("the divergence solve stops when the mean residual of the density change the "
                   "velocities would make in one step is at most this times rho0"));
  add(K("integrator.omega", T::Number)
          .in(implicit_sph)
          .def("0.5")
          .range(0, true, 1, false)
          .meaning("Jacobi relaxation (Ihmsen et al. 2014: 0.5)"));
  add(K("integrator.max_density_error", T::Number)
          .in(sph)
          .def("0.5")
          .positive()
          .meaning("stop (exit 3) when a particle is compressed beyond this relative density "
                   "error at the start of a step: the fluid is being crushed"));
  add(K("integrator.courant", T::Number)
          .in(sph)
          .def("0.4")
          .non_negative()
          .meaning(
              "split each time.dt step into the fewest equal substeps of at most courant dx "
              "/ (c0 + max|v|) (wcsph) or courant dx / max|v| (iisph, dfsph); 0: steps of time.dt "
              "exactly, as the stability study needs to cross the CFL limit"));
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
        add_scene_part_keys, add_bending_keys, add_pin_strain_ode_keys, add_implicit_keys,
        add_sundials_keys, add_ceres_keys, add_local_global_keys, add_vbd_keys, add_xpbd_keys,
        add_sph_method_keys, add_fluid_keys, add_run_keys})
    section(t);
  return t;
}

bool applies(const SceneKey& k, const std::string& variant) {
  return k.when.empty() || std::find(k.when.begin(), k.when.end(), variant) != k.when.end();
}

/// The section of a dotted name: everything before the last dot.
std::string section_of(const std::string& name) { return name.substr(0, name.rfind('.')); }

std::string join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (const auto& e : v) s += (s.empty() ? "" : sep) + e;
  return s;
}

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
