#pragma once
#include "hooke/core.hpp"

namespace hooke::contact {

/// Continuous collision detection by conservative advancement, the idea of additive CCD (Li,
/// Kaufman and Jiang 2021, "Codimensional incremental potential contact", section 5): a stencil
/// whose points move linearly from x to x + t dx, t in [0, 1], cannot come closer than its
/// distance d minus L t, where L bounds how fast any two of its primitives' points approach
/// (the largest displacement of one side plus that of the other, after the stencil's common
/// motion is taken out). So advancing by (d - xi - keep) / L keeps the distance above xi + keep,
/// and repeating from the new distance approaches the first time of contact from below.
///
/// Each returns the largest fraction t in [0, 1] it proves safe: over [0, t] the distance stays
/// above thickness + (1 - scale) (d0 - thickness), d0 the distance at t = 0 (> thickness). 1 means
/// no contact over the whole step; a smaller t is a lower bound of the time the distance would
/// reach the thickness (conservative: it may stop short of a contact that does not come). scale
/// in (0, 1): how much of the initial gap a step may use (0.9 leaves a tenth of it).
double point_triangle_ccd(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                          const Vec3& dp, const Vec3& dt0, const Vec3& dt1, const Vec3& dt2,
                          double thickness = 0.0, double scale = 0.9);
double edge_edge_ccd(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1,
                     const Vec3& da0, const Vec3& da1, const Vec3& db0, const Vec3& db1,
                     double thickness = 0.0, double scale = 0.9);

/// The same fraction, exactly, for a point moving from p to p + t dp against a plane (through
/// `origin`, unit normal `normal`, the side it points to being outside) that moves by d_origin:
/// the signed distance is linear in t, so the bound is its own root.
double point_plane_ccd(const Vec3& p, const Vec3& dp, const Vec3& origin, const Vec3& normal,
                       const Vec3& d_origin, double thickness = 0.0, double scale = 0.9);
/// The same fraction, exactly, for a point moving from p to p + t dp against a sphere (centre c,
/// radius r) whose centre moves by dc: the first root of |p - c + t (dp - dc)| = r + thickness +
/// (1 - scale) (d0 - r - thickness), a quadratic.
double point_sphere_ccd(const Vec3& p, const Vec3& dp, const Vec3& c, double r, const Vec3& dc,
                        double thickness = 0.0, double scale = 0.9);

}  // namespace hooke::contact
