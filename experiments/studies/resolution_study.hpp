#pragma once
#include <string>
#include <vector>

namespace hooke {

/// One way of choosing per-spring and per-particle parameters as the grid is refined.
struct ResolutionVariant {
  std::string name;  ///< "unscaled", "membrane", "1d-rule"
  /// Exponent of the spring stiffness factor (a_ref / a)^p with a the grid spacing: 0 keeps k,
  /// 1 is k proportional to 1 / rest length (the 1D rule k = EA / L).
  double stiffness_power = 0.0;
  bool scale_drag = false;  ///< drag per particle proportional to 1 / particles (total drag fixed)
  std::string description;  ///< one line for tables and the paper
};

/// The variants: unscaled (only nx, ny change), membrane (k fixed, which is the scaling that keeps
/// a 2D lattice's membrane stiffness, and drag per particle scaled so the cloth's total drag is
/// fixed) and the 1D rule (k proportional to 1 / a, drag scaled).
std::vector<ResolutionVariant> resolution_variants();

/// Options of `hooke resolution`.
struct ResolutionOptions {
  std::vector<int> n;     ///< grid sizes n x n (empty: 8, 16, 32; full: 8..256 by doubling)
  double h = 5e-3;        ///< step of the dynamic run (s)
  double duration = 4.0;  ///< simulated time of the dynamic run (s)
  /// Multiplies the scene's stiffnesses (1000, 200, 20 N/m at 16 x 16): 0.1 makes the cloth soft
  /// enough (strains near 0.3) that its sag measures its stiffness, not only its geometry.
  double stiffness_scale = 0.1;
  /// Particles along the strand and sheet cantilevers (empty: 21, 41, 81; full: up to 321).
  std::vector<int> cantilever_n;
  bool full = false;
  bool plot = true;
  std::string out_dir = "out/resolution";
};

/// The Euler-Bernoulli cantilever built in at x = clamp with rigidity EI under point loads P_i at
/// x_i: its deflection at x_tip, sum_i P_i a_i^2 (3 L - a_i) / (6 EI), a_i = x_i - clamp,
/// L = x_tip - clamp.
double cantilever_deflection(const std::vector<double>& xs, const std::vector<double>& loads,
                             double clamp, double x_tip, double EI);

/// `hooke resolution`: the hanging cloth of hanging_cloth_16.toml (1 m x 1 m, 1 kg, two corners
/// pinned) at each grid size and variant: the first swing period from a dynamic run and the static
/// sag from settling; then the bending cantilevers of strand_cantilever.toml (rod) and
/// sheet_cantilever.toml (shell on both diagonal patterns, dihedral, quadratic) at each number of
/// particles along, their settled tip sag against the Euler-Bernoulli beam's; writes
/// OUT/resolution.csv, OUT/cantilever.csv and (experiments/plot/resolution.py) OUT/resolution.png
/// and OUT/resolution.md.
int run_resolution(const ResolutionOptions& options, const std::string& scenes_dir);

/// Period (s) of a sampled signal y (at spacing dt): the time between its first two local minima,
/// a minimum being a sample no larger than every sample within `window` seconds of it, and more
/// than `depth` below the largest sample between the two. NaN if there are fewer than two.
double first_period(const std::vector<double>& y, double dt, double window, double depth);

}  // namespace hooke
