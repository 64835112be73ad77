#include "problems/scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "hooke/constraints/collider.hpp"
#include "hooke/constraints/strain_limit.hpp"
#include "hooke/contact/contact_model.hpp"
#include "hooke/contact/contact_potential.hpp"
#include "hooke/forces/air_drag.hpp"
#include "hooke/forces/gravity.hpp"
#include "hooke/forces/hooke_spring.hpp"
#include "hooke/forces/spring_damper.hpp"
#include "hooke/registry.hpp"
#include "problems/builders/mesh_build.hpp"
#include "problems/method_readers.hpp"
#include "problems/ode_problems.hpp"

namespace hooke {

long long TimeSettings::steps() const {
  StepPlan plan;
  plan.end = duration;
  plan.dt = dt;
  return plan.steps();
}

StepPlan Scene::step_plan() const {
  StepPlan plan;
  plan.end = time.duration;
  plan.dt = time.dt;
  plan.adaptive = integrator.adaptive;
  plan.frame_interval = output.interval;
  return plan;
}

namespace {

/// A mesh type: its name in [mesh] type and its builder (base_dir: the scene file's folder).
struct MeshType {
  const char* name;
  void (*build)(TableReader& mesh, TableReader& springs, const std::string& base_dir,
                MeshBuild& out);
};

// The one table of mesh types (builders in problems/builders/).
const std::vector<MeshType>& mesh_table() {
  using R = TableReader;
  static const std::vector<MeshType> table = {
      {"grid", [](R& m, R& s, const std::string&, MeshBuild& b) { build_grid(m, s, b); }},
      {"cantilever",
       [](R& m, R& s, const std::string&, MeshBuild& b) { build_cantilever(m, s, b); }},
      {"chain", [](R& m, R& s, const std::string&, MeshBuild& b) { build_chain(m, s, b); }},
      {"hair", [](R& m, R& s, const std::string&, MeshBuild& b) { build_hair(m, s, b); }},
      {"damped-springs",
       [](R& m, R& s, const std::string&, MeshBuild& b) { build_damped_springs(m, s, b); }},
      {"two-particle",
       [](R& m, R& s, const std::string&, MeshBuild& b) { build_two_particle(m, s, b); }},
      {"particles", [](R& m, R& s, const std::string&, MeshBuild& b) { build_particles(m, s, b); }},
      {"obj", build_obj},
  };
  return table;
}

}  // namespace

const std::vector<std::string>& mesh_types() {
  static const std::vector<std::string> types = [] {
    std::vector<std::string> v;
    for (const auto& t : mesh_table()) v.push_back(t.name);
    return v;
  }();
  return types;
}

namespace {

/// Applies one "section.key=value" override to the parsed table. The value is parsed as a TOML
/// value; if that fails it is taken as a string (so --set integrator.method=rk4 works unquoted).
/// Returns the dotted key it set.
std::string apply_override(toml::table& root, const std::string& item) {
  const std::string where = "--set " + item;
  const auto eq = item.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("<command line>", item, "expected section.key=value");
  const std::string path = item.substr(0, eq), text = item.substr(eq + 1);
  // One key per --set: a value spanning lines would parse as several keys and lose all but one.
  if (text.find_first_of("\r\n") != std::string::npos)
    throw InputError("<command line>", path,
                     "the value spans several lines; give each key its own --set");
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    parsed = toml::table{{"v", text}};
  }
  toml::table* t = &root;
  std::string rest = path;
  for (size_t dot; (dot = rest.find('.')) != std::string::npos;) {
    const std::string part = rest.substr(0, dot);
    rest = rest.substr(dot + 1);
    if (part.empty()) throw InputError("<command line>", path, "empty section name");
    auto* node = t->get(part);
    if (!node) {
      t->insert(part, toml::table{});
      node = t->get(part);
    }
    t = node->as_table();
    if (!t) throw InputError("<command line>", path, "'" + part + "' is not a table in the scene");
  }
  if (rest.empty()) throw InputError("<command line>", path, "empty key name");
  t->insert_or_assign(rest, std::move(*parsed.get("v")));
  return path;
}

MeshBuild build_mesh(TableReader& mesh, TableReader& springs, const std::string& base_dir) {
  MeshBuild b;
  const std::string type = mesh.choice("type", std::nullopt, mesh_types());
  b.type = type;
  mesh.set_variant(type);
  springs.set_variant(type);
  for (const auto& t : mesh_table())
    if (type == t.name) t.build(mesh, springs, base_dir, b);
  return b;
}

void read_ode(TableReader& ode, Scene& scene) {
  const std::string problem = ode.choice("problem", std::nullopt, {"decay", "circle"});
  ode.set_variant(problem);
  if (problem == "decay") {
    const double rate = ode.number("rate", 1.0);
    const double x0 = ode.number("x0", 1.0);
    scene.ode = std::make_unique<DecayOde>(rate);
    scene.ode_initial = Vec::Constant(1, x0);
    scene.ode_exact = [rate, x0](double t, VecRef X) { X[0] = x0 * std::exp(-rate * t); };
  } else {
    const auto x0 = ode.numbers("x0", std::vector<double>{1.0, 0.0});
    if (x0.size() != 2) ode.fail("x0", "must be [x, y]");
    scene.ode = std::make_unique<CircleOde>();
    scene.ode_initial = Vec::Map(x0.data(), 2);
    scene.ode_exact = [x0](double t, VecRef X) {
      X[0] = std::cos(t) * x0[0] - std::sin(t) * x0[1];
      X[1] = std::sin(t) * x0[0] + std::cos(t) * x0[1];
    };
  }
}

/// A collider the scene declares: its scene key ("collision.sphere"), what it is with its numbers
/// (for messages), the keys that place it, and the constraint the system owns.
struct SceneCollider {
  std::string key, what, placed_by;
  /// The system's projection; nullptr under [contact], whose obstacles check_contact_start
  /// checks.
  const Constraint* constraint;
};

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string fmt(const Vec3& v) {
  return "(" + fmt(v[0]) + ", " + fmt(v[1]) + ", " + fmt(v[2]) + ")";
}

/// Refuses a free particle that starts inside a collider: the collider would push it to its
/// surface in the first step, a jump the springs turn into a blow-up that reads as a time step too
/// large. The depth is what the collider's own project() moves the particle (its inward distance
/// from the surface: radial for the sphere, along the normal for the plane), so every collider is
/// judged by the rule it applies in the run. Depths up to 1e-5 of the scene size, max(extent of
/// the initial positions, largest coordinate), count as on the surface: a cloth resting on a
/// surface, given with positions rounded to 6 significant digits (as OBJ exporters write them),
/// is fine. Pinned particles are never moved by colliders, so they may start anywhere.
void check_particles_outside(const std::vector<SceneCollider>& colliders, const Scene& scene) {
  const Vec& x = scene.initial.x;
  const Index n = x.size() / 3;
  if (colliders.empty() || n == 0) return;
  const Eigen::Map<const Eigen::Matrix<double, 3, Eigen::Dynamic>> p(x.data(), 3, n);
  const double size =
      std::max((p.rowwise().maxCoeff() - p.rowwise().minCoeff()).norm(), p.cwiseAbs().maxCoeff());
  const double tolerance = 1e-5 * size;
  const std::vector<char>& pinned = scene.system->pinned();
  Vec moved(x.size()), v(x.size());
  for (const auto& c : colliders) {
    if (c.constraint == nullptr) continue;  // a barrier obstacle: check_contact_start's
    moved = x;
    v.setZero();
    // Colliders move positions only: x0 = x1 (no motion within the step), h only scales v.
    c.constraint->project(x, 1.0, pinned, moved, v);
    Index deepest = -1, inside = 0;
    double depth = 0.0;
    for (Index i = 0; i < n; ++i) {
      const double d = (moved.segment<3>(3 * i) - x.segment<3>(3 * i)).norm();
      if (!(d > tolerance)) continue;
      ++inside;
      if (d > depth) {
        depth = d;
        deepest = i;
      }
    }
    if (inside == 0) continue;
    std::ostringstream os;
    os << "free particle " << deepest << " at " << fmt(Vec3(x.segment<3>(3 * deepest)))
       << " starts " << fmt(depth) << " m inside " << c.what << " (tolerance " << fmt(tolerance)
       << " m, 1e-5 of the scene size)";
    if (inside > 1) os << "; " << inside << " free particles start inside, this one deepest";
    os << ". The first step would snap it to the surface, a jump that can make the run diverge "
       << "(not a time step problem: a smaller time.dt does not help). Move the collider ("
       << c.placed_by << ") or the object ([mesh] placement) so that no "
       << "free particle starts inside; a particle exactly on the surface is fine";
    throw InputError(scene.file, c.key, os.str());
  }
}

/// Under [contact]: refuses a contact gap that starts at or below 0 (a free particle on or inside
/// an obstacle grown by contact.thickness, a triangle that touches or cuts a sphere, a surface that
/// meets a mesh obstacle), which the barrier cannot start from. `colliders` lists the planes,
/// then the spheres, then the meshes, as the model does.
void check_contact_start(const std::vector<SceneCollider>& colliders, const Scene& scene) {
  const MassSpringSystem& sys = *scene.system;
  const ContactModel* model = sys.contact();
  if (model == nullptr) return;
  ContactPotential potential(*model, sys.masses(), sys.pinned(), sys.pattern(), 0.0);
  const ContactFigures fig = potential.figures(scene.initial.x);
  if (fig.min_gap > 0.0) return;
  if (fig.min_self)
    throw InputError(scene.file, "contact.self",
                     "two parts of the cloth start at a gap of " + fmt(fig.min_gap) +
                         " m (gaps between its parts are measured from 2 contact.thickness = " +
                         fmt(2.0 * model->options().thickness) +
                         "): self-contact needs every gap > 0 at the start; the mesh must not "
                         "cross itself");
  const size_t planes = model->planes().size(), spheres = model->spheres().size();
  const size_t k = fig.min_plane >= 0    ? size_t(fig.min_plane)
                   : fig.min_sphere >= 0 ? planes + size_t(fig.min_sphere)
                                         : planes + spheres + size_t(fig.min_mesh);
  const SceneCollider& c = colliders[k];
  throw InputError(
      scene.file, c.key,
      "the cloth starts at a contact gap of " + fmt(fig.min_gap) + " m from " + c.what +
          (model->options().thickness > 0.0 ? " (gaps are measured from contact.thickness = " +
                                                  fmt(model->options().thickness) + ")"
                                            : "") +
          ": barrier contact needs every gap > 0 at the start. Move the obstacle (" + c.placed_by +
          ") or the object ([mesh] placement)");
}

/// [[pin_motion]]: scripted pins. Each table moves the pinned particles whose initial position lies
/// in its box (every pinned particle without one) along a rigid motion; a particle may follow one
/// motion only. The initial state takes their prescribed velocity.
void read_pin_motion(TableReader& root, Scene& scene) {
  if (!root.has("pin_motion")) return;
  const MassSpringSystem& sys = *scene.system;
  const std::vector<char>& pinned = sys.pinned();
  const Vec& x = scene.initial.x;
  PinMotion motion;
  std::vector<std::string> owner(pinned.size());
  for (TableReader& m : root.tables("pin_motion")) {
    RigidMotion r;
    std::optional<std::vector<std::vector<double>>> box;
    if (m.has("box")) {
      box = m.rows("box", 3, 3);
      if (box->size() != 2)
        m.fail("box", "must be two corners [[xmin, ymin, zmin], [xmax, ymax, zmax]]");
    }
    r.velocity = m.vec3("velocity", Vec3::Zero());
    r.angular_velocity = m.vec3("angular_velocity", Vec3::Zero());
    r.start = m.non_negative("start", 0.0);
    if (m.has("stop")) {
      r.stop = m.positive("stop");
      if (!(r.stop > r.start)) m.fail("stop", "must be after start = " + fmt(r.start) + " s");
    }
    // Selection errors name the box, or the table when it has none.
    auto refuse = [&](const std::string& reason) {
      throw InputError(m.file(), box ? m.path("box") : m.name(), reason);
    };
    std::vector<Index> chosen;
    Vec3 lo = Vec3::Constant(HUGE_VAL), hi = -lo, sum = Vec3::Zero();
    for (Index i = 0; i < sys.num_particles(); ++i) {
      if (!pinned[size_t(i)]) continue;
      const Vec3 p = x.segment<3>(3 * i);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      if (box && ((p - Vec3((*box)[0].data())).minCoeff() < 0.0 ||
                  (Vec3((*box)[1].data()) - p).minCoeff() < 0.0))
        continue;
      if (!owner[size_t(i)].empty())
        refuse("pinned particle " + std::to_string(i) + " at " + fmt(p) + " already follows " +
               owner[size_t(i)] + "; each pin follows one motion");
      chosen.push_back(i);
      sum += p;
    }
    if (chosen.empty()) {
      const std::string span =
          sys.num_pinned() ? "; the pinned particles lie in " + fmt(lo) + " .. " + fmt(hi) : "";
      refuse("selects no pinned particle" + span +
             " (pin_motion moves pinned particles: pin them in [mesh])");
    }
    r.center = m.vec3("center", sum / double(chosen.size()));
    m.finish();
    const int id = motion.add_motion(r);
    for (const Index i : chosen) {
      motion.add_particle(i, id, x.segment<3>(3 * i));
      owner[size_t(i)] = m.name();
    }
  }
  motion.place(0.0, scene.initial.x, scene.initial.v);
  scene.system->set_pin_motion(std::move(motion));
}

/// [contact]: barrier contact's settings (ContactOptions).
ContactOptions read_contact_options(TableReader& root) {
  ContactOptions o;
  auto ct = root.table("contact");
  o.distance = ct->positive("distance", o.distance);
  o.stiffness = ct->non_negative("stiffness", o.stiffness);
  o.friction_velocity = ct->positive("friction_velocity", o.friction_velocity);
  o.thickness = ct->non_negative("thickness", o.thickness);
  o.self = ct->boolean("self", o.self);
  o.friction = ct->non_negative("friction", o.friction);
  if (!o.self && o.friction > 0.0)
    ct->fail("friction",
             "is the friction between parts of the cloth and needs self = true (an obstacle's "
             "friction is its own key)");
  ct->finish();
  return o;
}

/// The sphere's motion keys, which only the barrier takes.
void read_sphere_motion(TableReader& sp, bool contact, ContactSphere& s) {
  for (const char* key : {"velocity", "angular_velocity"})
    if (!contact)
      sp.reject_if_present(key,
                           "a moving sphere acts through barrier contact: add a [contact] "
                           "section (and method = \"implicit\")");
  if (!contact) return;
  s.velocity = sp.vec3("velocity", Vec3::Zero());
  s.angular_velocity = sp.vec3("angular_velocity", Vec3::Zero());
}

/// [[collision.mesh]]: triangle-mesh obstacles from OBJ files (placed by scale and translate,
/// moved rigidly as [[pin_motion]] moves pins), listed in `colliders` after the planes and spheres.
std::vector<ContactMesh> read_mesh_obstacles(TableReader& c, bool contact,
                                             std::vector<SceneCollider>& colliders) {
  std::vector<ContactMesh> meshes;
  if (!c.has("mesh")) return meshes;
  if (!contact)
    c.fail("mesh",
           "a mesh obstacle acts through barrier contact: add a [contact] section (and method = "
           "\"implicit\")");
  const std::string base_dir = std::filesystem::path(c.file()).parent_path().string();
  for (TableReader& t : c.tables("mesh")) {
    ObjSurface obj = read_obj_surface(t, base_dir);
    if (obj.triangles.empty()) t.fail("file", "the OBJ file has no faces");
    const double scale = t.positive("scale", 1.0);
    const Vec3 shift = t.vec3("translate", Vec3::Zero());
    ContactMesh m;
    for (Vec3& v : obj.vertices) v = scale * v + shift;
    Vec3 lo = Vec3::Constant(HUGE_VAL), hi = -lo;
    for (const Vec3& v : obj.vertices) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    m.vertices = std::move(obj.vertices);
    m.triangles = std::move(obj.triangles);
    m.friction = t.non_negative("friction", 0.0);
    m.velocity = t.vec3("velocity", Vec3::Zero());
    m.angular_velocity = t.vec3("angular_velocity", Vec3::Zero());
    m.center = t.vec3("center", 0.5 * (lo + hi));
    m.start = t.non_negative("start", 0.0);
    if (t.has("stop")) {
      m.stop = t.positive("stop");
      if (!(m.stop > m.start)) t.fail("stop", "must be after start = " + fmt(m.start) + " s");
    }
    t.finish();
    colliders.push_back({t.name(),
                         "the mesh obstacle (" + std::to_string(m.triangles.size()) +
                             " triangles in " + fmt(lo) + " .. " + fmt(hi) + ")",
                         t.path("file") + ", " + t.path("translate"), nullptr});
    meshes.push_back(std::move(m));
  }
  return meshes;
}

/// [collision.*]: each kind as one table ([collision.ground]) or several ([[collision.ground]]:
/// walls, floors, any normal; [[collision.sphere]]). Without [contact] they are post-step
/// projections, applied in the order given, planes first; with it, obstacles of the system's
/// barrier contact (ContactModel over the mesh's triangles).
void read_colliders(TableReader& root, const MeshBuild& b, MassSpringSystem& sys,
                    std::vector<SceneCollider>& colliders) {
  const bool contact = root.has("contact");
  std::vector<ContactSphere> spheres;
  std::vector<ContactPlane> planes;
  std::vector<ContactMesh> meshes;
  // A projection joins the system; a barrier obstacle joins the ContactModel below.
  auto add = [&](std::unique_ptr<Constraint> c, SceneCollider entry) {
    entry.constraint = contact ? nullptr : c.get();
    if (!contact) sys.add_constraint(std::move(c));
    colliders.push_back(std::move(entry));
  };
  if (auto c = root.table("collision")) {
    for (TableReader& g : c->tables("ground")) {
      const Vec3 normal = g.vec3("normal", Vec3(0, 1, 0));
      if (normal.norm() == 0.0) g.fail("normal", "must be a nonzero vector");
      const double height = g.number("height", 0.0);
      const double mu = g.non_negative("friction", 0.0);
      g.finish();
      planes.push_back({normal.normalized(), height, mu});
      add(std::make_unique<GroundPlane>(normal, height, mu),
          {g.name(),
           "the ground plane (normal " + fmt(Vec3(normal.normalized())) + ", height " +
               fmt(height) + ")",
           g.path("height") + ", " + g.path("normal"), nullptr});
    }
    for (TableReader& sp : c->tables("sphere")) {
      ContactSphere s;
      s.center = sp.vec3("center", Vec3::Zero());
      s.radius = sp.positive("radius", 0.5);
      s.friction = sp.non_negative("friction", 0.0);
      read_sphere_motion(sp, contact, s);
      sp.finish();
      spheres.push_back(s);
      add(std::make_unique<SphereCollider>(s.center, s.radius, s.friction),
          {sp.name(), "the sphere (center " + fmt(s.center) + ", radius " + fmt(s.radius) + ")",
           sp.path("center") + ", " + sp.path("radius"), nullptr});
    }
    meshes = read_mesh_obstacles(*c, contact, colliders);
    c->finish();
  }
  if (contact)
    sys.set_contact(std::make_shared<ContactModel>(read_contact_options(root), b.triangles,
                                                   std::move(spheres), std::move(planes),
                                                   std::move(meshes), b.x));
}

/// Forces, colliders and strain limiting: each added only when the scene declares it. The
/// colliders are listed in `colliders` for check_particles_outside().
void add_forces_and_constraints(TableReader& root, const MeshBuild& b, Scene& scene,
                                std::vector<SceneCollider>& colliders) {
  MassSpringSystem& sys = *scene.system;
  const Index n = b.num_particles();
  auto springs = std::make_unique<HookeSpring>();
  auto dampers = std::make_unique<SpringDamper>();
  scene.edges.reserve(b.springs.size());
  scene.edge_rest.reserve(b.springs.size());
  for (const auto& s : b.springs) {
    springs->add(s.i, s.j, s.k, s.L);
    if (s.c > 0.0) dampers->add(s.i, s.j, s.c);
    scene.edges.push_back({s.i, s.j});
    scene.edge_rest.push_back(s.L);
  }
  if (springs->size()) sys.add_force(std::move(springs));
  if (dampers->size()) sys.add_force(std::move(dampers));

  if (auto bending = root.table("bending")) {
    add_bending(*bending, b, sys);
    bending->finish();
  }

  if (auto f = root.table("forces")) {
    if (f->has("gravity")) sys.add_force(std::make_unique<Gravity>(b.masses, f->vec3("gravity")));
    const double drag = f->non_negative("drag", 0.0);
    const Vec3 wind = f->vec3("wind", Vec3::Zero());
    if (wind.norm() > 0.0 && drag == 0.0)
      f->fail("wind", "wind acts through air drag: set forces.drag > 0 (kg/s per particle)");
    if (drag > 0.0) sys.add_force(std::make_unique<AirDrag>(n, drag, wind));
    f->finish();
  }

  read_colliders(root, b, sys, colliders);
  if (auto sl = root.table("strain_limit")) {
    const double max_strain = sl->positive("max_strain", 0.1);
    const int passes = static_cast<int>(sl->integer("passes", 10, 1, 1000000));
    sl->finish();
    auto limit = std::make_unique<StrainLimit>(max_strain, passes);
    for (const auto& s : b.springs)
      if (s.limited && s.L > 0.0) limit->add(s.i, s.j, s.L);
    sys.add_constraint(std::move(limit));
  }
}

void read_run_settings(TableReader& root, Scene& scene) {
  {
    auto it = root.table("integrator");
    TableReader& r = *it;
    const std::string method = r.string("method", "symplectic-euler");
    try {
      method_info(method);
    } catch (const UnknownName& e) {
      r.fail("method", e.what());
    }
    scene.integrator.method = method;
    // A fluid is stepped by the fluid methods only, and they step nothing else.
    const bool fluid_method = method_info(method).kind == MethodKind::Fluid;
    if (scene.is_fluid() && !fluid_method)
      r.fail("method", "'" + method +
                           "' steps mass-spring systems; a [fluid] scene is stepped by a fluid "
                           "method: " +
                           fluid_method_names());
    if (fluid_method && !scene.is_fluid())
      r.fail("method", "'" + method + "' steps fluids: it needs a [fluid] scene (this one has " +
                           (scene.ode ? "an [ode]" : "a [mesh]") + ")");
    r.set_variant(method);
    scene.integrator.adaptive = read_error_control(r, method, scene.integrator.error_control);
    if (scene.integrator.adaptive && r.contact_scene())
      r.fail("adaptive",
             "barrier contact ([contact]) takes fixed steps (time.dt) for now; remove adaptive");
    if (scene.integrator.adaptive && scene.ode)
      r.fail("adaptive",
             "[ode] scenes take fixed steps (time.dt); error control runs on particle "
             "scenes");
    scene.integrator.options = read_method_options(r, method);
  }
  {
    auto it = root.table("time");
    TableReader& r = *it;
    scene.time.dt = r.positive("dt", 1e-3);
    scene.time.duration = r.non_negative("duration", 1.0);
    if (scene.time.duration / scene.time.dt > 1e12)
      r.fail("dt", "duration / dt = " + std::to_string(scene.time.duration / scene.time.dt) +
                       " steps is more than 1e12");
    r.finish();
  }
  const long long steps = scene.time.steps();
  {
    auto it = root.table("output");
    TableReader& r = *it;
    scene.output.dir = r.string("dir", "out/" + scene.name);
    if (scene.output.dir.empty()) r.fail("dir", "must not be empty");
    // Frames by steps (every) or by simulated time (interval), not both. A --set switch for one
    // drops the other from the file with a warning (the command line cannot remove a key).
    bool by_time = r.has("interval");
    if (by_time && r.has("every")) {
      const bool set_interval = r.overridden("interval"), set_every = r.overridden("every");
      if (set_interval == set_every)
        r.fail("every", "give every (steps) or interval (seconds) for the frames, not both");
      const std::string dropped = set_interval ? "every" : "interval";
      r.warn(dropped, std::string("has no effect with output.") +
                          (set_interval ? "interval" : "every") + " (from --set); ignored");
      r.skip(dropped);
      by_time = set_interval;
    }
    if (by_time) {
      scene.output.interval = r.positive("interval");
      if (scene.time.duration / scene.output.interval > 1e9)
        r.fail("interval", "interval = " + std::to_string(scene.output.interval) +
                               " s gives more than 1e9 frames");
      scene.output.every = 0;
    } else if (scene.integrator.adaptive) {
      // Error-controlled steps vary in size: frames follow simulated time, 50 by default.
      if (r.has("every"))
        r.fail("every",
               "counts steps, whose size error control varies (integrator.adaptive = "
               "true); give output.interval (s) for the frames instead");
      scene.output.every = 0;
      scene.output.interval = scene.time.duration / 50.0;
    } else {
      scene.output.every = r.integer("every", std::max(1LL, steps / 50), 0, 1LL << 62);
    }
    scene.output.log_every = r.integer("log_every", std::max(1LL, steps / 10000), 1, 1LL << 62);
    scene.output.vtk = r.boolean("vtk", true);
    scene.output.png = r.boolean("png", true);
    r.finish();
  }
  {
    auto it = root.table("run");
    TableReader& r = *it;
    RunSettings& run = scene.run;
    run.energy_growth_limit = r.positive("energy_growth_limit", 10.0);
    run.allow_not_converged = r.boolean("allow_not_converged", false);
    if (!scene.integrator.adaptive)
      run.max_step_halvings = int(r.integer("max_step_halvings", 0, 0, 30));
    else if (r.has("max_step_halvings"))
      r.fail("max_step_halvings",
             "has no effect with integrator.adaptive = true: error control retries a failed step "
             "with a smaller one itself; remove it");
    run.checkpoint_every = r.integer("checkpoint_every", 0, 0, 1LL << 62);
    run.checkpoint_seconds = r.positive("checkpoint_seconds", 300.0);
    r.finish();
  }
}

/// The --set switches that take every spring damper out of a scene: each [springs] key of the
/// scene (its file and --set switches: per-kind dampings default to `damping`) that names a damping
/// (ends in "damping") and is > 0, set to 0, and the mesh's own spring rows ([mesh] springs of a
/// particles mesh: [i, j, k, L, c]) with every c set to 0; empty if the dampers come from
/// elsewhere.
std::string damper_overrides(const toml::table& given) {
  std::string out;
  if (const toml::array* rows = given["mesh"]["springs"].as_array()) {
    bool damped = false;
    std::string text;
    for (const toml::node& row : *rows) {
      const toml::array* r = row.as_array();
      if (r == nullptr) return out;
      text += text.empty() ? "[[" : ", [";
      for (size_t k = 0; k < r->size(); ++k) {
        const auto v = (*r)[k].value<double>();
        if (!v) return out;
        damped = damped || (k == 4 && *v > 0.0);
        text += (k ? ", " : "") + shortest_number(k == 4 ? 0.0 : *v);
      }
      text += "]";
    }
    if (damped) out = "--set 'mesh.springs=" + text + "]'";
  }
  if (const toml::table* springs = given["springs"].as_table())
    for (const auto& [name, value] : *springs) {
      const std::string key(name.str());
      const std::string suffix = "damping";
      const auto c = value.value<double>();
      if (key.size() >= suffix.size() &&
          key.compare(key.size() - suffix.size(), suffix.size(), suffix) == 0 && c && *c > 0.0)
        out += (out.empty() ? "" : " ") + std::string("--set springs.") + key + "=0";
    }
  return out;
}

Scene load_parsed(toml::table tbl, const std::string& file,
                  const std::vector<std::string>& overrides) {
  auto context = std::make_shared<ReadContext>();
  for (const auto& o : overrides) context->overridden.insert(apply_override(tbl, o));
  context->contact = tbl.contains("contact");
  Scene scene;
  scene.file = file;
  scene.name = std::filesystem::path(file).stem().string();
  const bool is_ode = tbl.contains("ode");
  const bool is_fluid = !is_ode && tbl.contains("fluid");
  // Sections every scene has are created empty so their defaults land in the resolved scene.
  for (const char* sec : {"integrator", "time", "output", "run"})
    if (!tbl.contains(sec)) tbl.insert(sec, toml::table{});
  if (!is_ode && !is_fluid && !tbl.contains("springs")) tbl.insert("springs", toml::table{});
  TableReader root(tbl, scene.resolved, file, "", context);

  if (is_ode) {
    for (const char* sec : {"mesh", "springs", "bending", "forces", "collision", "strain_limit",
                            "pin_motion", "fluid"})
      root.reject_if_present(sec, "an [ode] scene has no particles; remove this section");
    auto ode = root.table("ode");
    read_ode(*ode, scene);
    ode->finish();
  } else if (is_fluid) {
    for (const char* sec : {"mesh", "springs", "bending", "strain_limit", "pin_motion"})
      root.reject_if_present(sec,
                             "a [fluid] scene has fluid particles only (no mesh or springs); "
                             "remove this section");
    root.reject_if_present("collision",
                           "a fluid meets solids as boundary particles: give the walls as "
                           "[fluid.tank] and solids as [[fluid.obstacle]] boxes");
    Vec3 gravity = Vec3::Zero();
    if (auto f = root.table("forces")) {
      if (f->has("gravity")) gravity = f->vec3("gravity");
      for (const char* key : {"drag", "wind"})
        f->reject_if_present(key,
                             "air drag is not modelled on fluid particles (a fluid scene takes "
                             "forces.gravity only)");
      f->finish();
    }
    auto fluid = root.table("fluid");
    build_fluid(*fluid, gravity, scene);
    fluid->finish();
  } else {
    if (!root.has("mesh")) root.fail("mesh", "is required (or an [ode] or [fluid] section)");
    auto mesh = root.table("mesh");
    auto springs = root.table("springs");
    const std::string base_dir = std::filesystem::path(file).parent_path().string();
    MeshBuild b = build_mesh(*mesh, *springs, base_dir.empty() ? "." : base_dir);
    mesh->finish();
    springs->finish();
    scene.system = std::make_unique<MassSpringSystem>(b.masses, b.pinned);
    scene.initial.x = b.x;
    scene.initial.v = b.v;
    for (Index i = 0; i < b.num_particles(); ++i)
      if (b.pinned[size_t(i)]) scene.initial.v.segment<3>(3 * i).setZero();
    scene.initial.t = 0.0;
    scene.exact = b.exact;
    std::vector<SceneCollider> colliders;
    add_forces_and_constraints(root, b, scene, colliders);
    scene.triangles = std::move(b.triangles);
    read_pin_motion(root, scene);
    scene.system->finalize();
    check_particles_outside(colliders, scene);
    check_contact_start(colliders, scene);
  }
  read_run_settings(root, scene);
  if (scene.system) {
    std::string why = method_unsupported(scene.integrator.method, *scene.system);
    if (!why.empty()) {
      const auto& forces = scene.system->forces();
      // Only when the dampers are what the method refuses (the refusal names the others first).
      const bool dampers = why.find("spring-damper") != std::string::npos &&
                           std::any_of(forces.begin(), forces.end(), [](const auto& f) {
                             return std::string(f->name()) == "spring-damper";
                           });
      // Say how to run the scene anyway: the one switch (per damping key) that drops the dampers.
      if (dampers) {
        const std::string sets = damper_overrides(tbl);
        why += sets.empty() ? "; or remove the scene's spring dampers (its damping keys)"
                            : "; or run it without spring dampers: " + sets;
      }
      throw InputError(file, "integrator.method", why);
    }
  } else if (method_info(scene.integrator.method).kind != MethodKind::Explicit) {
    std::string explicit_methods;
    for (const auto& m : methods())
      if (m.kind == MethodKind::Explicit)
        explicit_methods += (explicit_methods.empty() ? "" : ", ") + std::string(m.name);
    throw InputError(file, "integrator.method",
                     "'" + scene.integrator.method +
                         "' steps a mass-spring system; an [ode] scene "
                         "runs the explicit methods: " +
                         explicit_methods);
  }
  root.finish();
  scene.warnings = context->warnings;
  return scene;
}

toml::table parse_toml(const std::string& text, const std::string& file) {
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    const auto& src = e.source();
    throw InputError(
        file,
        "line " + std::to_string(src.begin.line) + ", column " + std::to_string(src.begin.column),
        std::string(e.description()));
  }
}

}  // namespace

Scene load_scene_from_string(const std::string& text, const std::string& file,
                             const std::vector<std::string>& overrides) {
  return load_parsed(parse_toml(text, file), file, overrides);
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "file", "does not exist");
  if (fs::is_directory(path, ec))
    throw InputError(path, "file", "is a directory, not a scene file");
  // A device, FIFO or socket (/dev/zero, /dev/stdin) could be read forever: only regular files.
  if (!fs::is_regular_file(path, ec))
    throw InputError(path, "file", "is not a regular file (a device, FIFO or socket?)");
  const auto size = fs::file_size(path, ec);
  if (ec) throw InputError(path, "file", "cannot read its size: " + ec.message());
  if (size > (64u << 20))
    throw InputError(path, "file",
                     "is " + std::to_string(size >> 20) +
                         " MiB; scene files are limited to 64 MiB (use an obj mesh)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "file", "cannot be read");
  std::stringstream ss;
  ss << in.rdbuf();
  return load_scene_from_string(ss.str(), path, overrides);
}

}  // namespace hooke
