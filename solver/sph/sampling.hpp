#pragma once
#include <vector>

#include "hooke/core.hpp"

namespace hooke {

/// Particles on the regular lattice of spacing dx (m) that fills the box [lower, upper]: the
/// centres lower + (i + 1/2) dx of round(extent / dx) cells per axis (at least one). With
/// dimension 2 the box is flat: one layer at z = lower.z. Ordered x fastest, then y, then z.
std::vector<Vec3> sample_box(const Vec3& lower, const Vec3& upper, double dx, int dimension);

/// Boundary particles of a tank whose inside is the box [lower, upper]: the lattice of
/// sample_box continued `layers` cells beyond each wall and below the floor (y is up; the top
/// is open), minus the inside. A fluid sampled by sample_box in the same box lies one spacing
/// from the first layer, as in the bulk. dimension 2: walls left, right and the floor, in the
/// plane z = lower.z.
std::vector<Vec3> sample_tank(const Vec3& lower, const Vec3& upper, double dx, int dimension,
                              int layers);

/// Boundary particles filling a solid box [lower, upper] (an obstacle) with `layers` layers
/// inside its surface (all of it when the box is thinner), on the lattice of sample_box.
std::vector<Vec3> sample_solid_box(const Vec3& lower, const Vec3& upper, double dx, int dimension,
                                   int layers);

}  // namespace hooke
