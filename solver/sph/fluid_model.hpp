#pragma once
#include <utility>

#include "hooke/core.hpp"
#include "hooke/options.hpp"
#include "hooke/sph/kernels.hpp"
#include "hooke/sph/neighbours.hpp"

namespace hooke {

/// What a fluid is made of: fixed for a run, validated once.
struct FluidOptions {
  /// 2 (particles in a plane of constant z, the 2D validation cases) or 3.
  int dimension = 3;
  /// Particle spacing dx (m), > 0: a fluid particle stands for a cube (2D: square) of side dx.
  double spacing = 0.0;
  /// Rest density rho0 (kg/m^3), > 0.
  double rest_density = 1000.0;
  /// Kernel support radius H as a multiple of the spacing, in [1.5, 4]: 2 gives about 13
  /// neighbours in 2D and 33 in 3D with the cubic spline.
  double support_factor = 2.0;
  KernelType kernel = KernelType::CubicSpline;
  /// Kinematic viscosity nu (m^2/s), >= 0, in the discretisation of Morris et al. 1997 /
  /// Monaghan 2005 (Koschier et al. 2019, "SPH techniques for the physics based simulation of
  /// fluids and solids", eq. 30): a_i += 2 (d + 2) nu sum_j (m_j / rho_ij) (v_ij . x_ij) /
  /// (|x_ij|^2 + 0.01 H^2) gradW_ij, rho_ij = (rho_i + rho_j) / 2 so that it conserves
  /// momentum exactly. Monaghan's artificial viscosity alpha with sound speed c
  /// is nu = alpha c (H / 2) / (2 (d + 2)). Between fluid particles only: the walls slip.
  double viscosity = 0.0;
  /// Divide the pressure forces by the kernel gradient's mean first moment
  /// (FluidModel::compute_density, mean_gradient_moment), so that they see a linear pressure
  /// field with its true slope. The moment is 1 for the exact integral but the sum over a
  /// particle arrangement makes it something else (cubic spline, support 2 dx: 0.981 on a
  /// hexagonal lattice at rest density, 1.012 on a square one, about 0.985 on the arrangement
  /// still water settles into), and uncorrected still water stands on a pressure 1.5-2% steeper
  /// than rho0 g. One factor for the whole fluid, as a scalar, keeps the pair forces equal,
  /// opposite and central (momentum and angular momentum conserved) and leaves an implicit
  /// method's motion as it was (its pressures are Lagrange multipliers, scaled by the factor's
  /// inverse). (The per-particle matrix of Bonet and Lok 1999, (L_i + L_j) / 2 gradW_ij, gives
  /// the same pressures to 1% but its non-central forces spin still water up to 0.1-0.5 m/s.)
  bool gradient_correction = true;
  OptionError validate() const;
};

/// A fluid of particles with static boundary particles, as smoothed particle hydrodynamics
/// models it (Monaghan 2005, "Smoothed particle hydrodynamics", Rep. Prog. Phys. 68). The
/// particles of a system are ordered: [0, num_fluid) fluid, [num_fluid, n) boundary. The
/// boundary particles are the dummy particles of Adami, Hu and Adams 2012 ("A generalized wall
/// boundary condition for smoothed particle hydrodynamics", J. Comput. Phys. 231): solid walls
/// sampled at the fluid's spacing, at least as thick as the kernel's support, each of mass
/// psi_b = rho0 dx^d, so that a fluid particle next to a wall sees a full kernel of mass at rest
/// density. They take part in the density and continuity sums like fluid at rest, and push with
/// the pressure of Adami et al. (eq. 27) extrapolated from the fluid around the particle they push
/// on: p_b = p~_i + max(0, h_i + rho_i a_i . (x_b - x_i)), where p~_i = sum_j W_ij p_j / sum_j W_ij
/// is the Shepard average of the fluid's pressures around i (i included), h_i = sum_j W_ij rho_j
/// a_i . (x_i - x_j) / sum_j W_ij carries that average hydrostatically to x_i, and a_i is i's body
/// acceleration (gravity): the fluid's pressure mirrored into the wall (add_pressure_acceleration)
/// plus its hydrostatic rise into a wall beneath (add_wall_support). Still water then rests on a
/// floor with the hydrostatic pressure down to the first row. (The one-term wall force of Akinci
/// et al. 2012, psi_b p_i / rho_i^2, is the variational one but holds the water up only with the
/// first row's pressure some 70% above rho0 g H, and slows a dam break's front by 5%; mirroring
/// p_i itself rather than its Shepard average pumps energy into the first row until still water
/// at Monaghan's alpha = 0.02 boils.)
///
/// The SPH sums (density, pressure and viscous accelerations, the density change of a velocity
/// field) are here, shared by the pressure methods (wcsph.hpp, iisph.hpp). Each reads a
/// NeighbourSearch updated on all n positions with num_fluid queries; each writes only the
/// entries of fluid particles, each particle's sum in its neighbour order, so results do not
/// depend on the thread count.
class FluidModel {
 public:
  /// num_fluid: fluid particles (>= 1); num_boundary: boundary particles (>= 0). Throws
  /// InternalError if the options are not valid.
  FluidModel(FluidOptions options, Index num_fluid, Index num_boundary);

  const FluidOptions& options() const { return m_options; }
  int dimension() const { return m_options.dimension; }
  Index num_fluid() const { return m_num_fluid; }
  Index num_boundary() const { return m_psi.size(); }
  Index num_particles() const { return m_num_fluid + m_psi.size(); }
  /// The support radius H (m).
  double support() const { return m_options.support_factor * m_options.spacing; }
  double rest_density() const { return m_options.rest_density; }
  /// rho0 dx^d (kg): the mass of a fluid particle of the regular sampling.
  double particle_mass() const;
  /// psi_b = rho0 dx^d (kg) of each boundary particle, nb vector.
  const Vec& boundary_psi() const { return m_psi; }

  /// rho_i = sum_j m_j W_ij (fluid, itself included) + sum_b psi_b W_ib, for i < num_fluid.
  /// x: 3n positions; masses: n; rho: at least num_fluid entries (kg/m^3).
  void compute_density(const NeighbourSearch& nb, ConstRef x, ConstRef masses, VecRef rho) const;
  /// The same densities, and in the same pass each particle's first moment of the kernel
  /// gradient (FluidOptions::gradient_correction): with
  ///   M_i = sum_j V_j gradW_ij (x_j - x_i)^T,
  /// what the SPH gradient sum_j V_j (f_j - f_i) gradW_ij makes of the gradient of a linear f
  /// (the identity for the exact integral), moment_i = tr(M_i) / d (d = 2: the in-plane part)
  /// if no diagonal entry of M_i is below 0.9, else -1: particles at the free surface and in
  /// spray, whose kernels are partly empty, have one near 1/2 (a surface at 45 degrees: two near
  /// 3/4) and are left out. V_b = psi_b / rho0 for the walls and V_j = m_j / rho_i, the fluid
  /// neighbours at i's density, so that the sum rides along with the density's: exact at
  /// uniform density, and in the mean over a fluid the neighbours' own volumes would change it
  /// only by the square of the density's variation over a kernel. moment: num_fluid entries.
  void compute_density(const NeighbourSearch& nb, ConstRef x, ConstRef masses, VecRef rho,
                       VecRef moment) const;
  /// The mean of compute_density's moments over the particles it did not leave out (1 if it left
  /// out all), summed in index order, so that it does not depend on the thread count.
  static double mean_gradient_moment(ConstRef moment);
  /// a_i += -s [sum_j m_j (p_i / rho_i^2 + p_j / rho_j^2) gradW_ij + sum_b psi_b (p_i / rho_i^2 +
  /// p~_i / rho0^2) gradW_ib]: the symmetric, momentum-conserving gradient, with the walls at the
  /// fluid's Shepard-averaged pressure p~_i around i (rho_b = rho0), for fluid i, times the
  /// gradient scale s (1 / mean_gradient_moment with FluidOptions::gradient_correction, else 1).
  /// a: 3n; rho, p: num_fluid entries (Pa).
  void add_pressure_acceleration(const NeighbourSearch& nb, ConstRef x, ConstRef masses,
                                 ConstRef rho, ConstRef p, VecRef a, double scale = 1.0) const;
  /// a_i += -s sum_b psi_b max(0, h_i + rho_i a_i . (x_b - x_i)) / rho0^2 gradW_ib: the rest of
  /// the walls' push, the hydrostatic rise of their pressure over p~_i (class comment) under the
  /// body accelerations `body` (3n), with the pressure forces' gradient scale s. Independent of
  /// the fluid's pressures, so implicit methods count it with the other non-pressure
  /// accelerations.
  void add_wall_support(const NeighbourSearch& nb, ConstRef x, ConstRef rho, ConstRef body,
                        VecRef a, double scale = 1.0) const;
  /// a_i += the viscous acceleration of FluidOptions::viscosity (nothing if it is 0).
  void add_viscous_acceleration(const NeighbourSearch& nb, ConstRef x, ConstRef v, ConstRef masses,
                                ConstRef rho, VecRef a) const;
  /// div_i = sum_j m_j (u_i - u_j) . gradW_ij + sum_b psi_b u_i . gradW_ib: the rate of change
  /// of rho_i (kg/m^3/s) that the velocity field u (3n; boundary particles at rest) gives, the
  /// SPH continuity equation (Monaghan 2005, eq. 4.4) with the walls at rest.
  void density_change(const NeighbourSearch& nb, ConstRef x, ConstRef masses, ConstRef u,
                      VecRef div) const;
  /// Calls f(kernel) with this fluid's SphKernel<Shape>, so pair loops are compiled per shape.
  template <class F>
  decltype(auto) with_kernel(F&& f) const {
    if (m_options.kernel == KernelType::WendlandC2)
      return f(SphKernel<WendlandC2Shape>(dimension(), support()));
    return f(SphKernel<CubicSplineShape>(dimension(), support()));
  }

 private:
  template <bool kMoment>
  void density_pass(const NeighbourSearch& nb, ConstRef x, ConstRef masses, VecRef rho,
                    VecRef moment) const;

  FluidOptions m_options;
  Index m_num_fluid;
  Vec m_psi;
};

/// Per-step figures of a fluid step (relative density errors over the fluid particles, at the
/// start of each substep). A step of several CFL substeps reports the largest errors and
/// residual of its substeps and the sum of their pressure iterations.
struct FluidStepStats {
  double max_density_error = 0.0;   ///< max_i (rho_i - rho0) / rho0 (compression only)
  double mean_density_error = 0.0;  ///< mean_i max(rho_i - rho0, 0) / rho0
  double max_speed = 0.0;           ///< max |v_i| at the step's end (m/s)
  int pressure_iterations = 0;      ///< iterations of the pressure solve (0: none)
  double pressure_residual = 0.0;   ///< its final mean density error (implicit methods)
  int substeps = 0;                 ///< substeps the step took (1 without CFL substeps)
  long long lost = 0;  ///< fluid particles that have left the walls' domain (SphStepper)
};

/// The fluid's density errors (FluidStepStats's first two fields) for densities rho
/// (num_fluid entries).
std::pair<double, double> density_errors(ConstRef rho, double rest_density);

}  // namespace hooke
