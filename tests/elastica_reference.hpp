// The planar elastica reference of the propped cantilever under a large load, shared by the
// contact tests of the lumped and the shooting models (tests/test_contact_lumped.cpp,
// tests/test_contact_shooting.cpp).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace tdcr::test {

// The planar elastica (inextensible Kirchhoff rod) of the propped cantilever: clamped at s = 0
// along z, tip force P along x, a frictionless point support (a sphere of radius rho about c)
// pushing on the backbone at s = a along the normal from its centre, |p(a) - c| = rho + r_o.
// Shooting on the base moment, the reaction R and its direction angle (RK4, 4000 steps);
// returns R.
inline double elastica_reaction(double EI, double L, double a, double P, double r_o, double rho) {
  const double cx = r_o + rho, cz = a;
  // State (x, z, theta, M); dM/ds = -(t x N), N the distal loads, EI theta' = -M.
  const auto shoot = [&](const Eigen::Vector3d& u, Eigen::Vector3d& res) {
    const double M0 = u[0], R = u[1], phi = u[2];
    Eigen::Vector4d y(0, 0, 0, M0);
    const auto rhs = [&](double s, const Eigen::Vector4d& q) {
      double Nx = P, Nz = 0.0;
      if (s < a) Nx += R * std::cos(phi), Nz += R * std::sin(phi);
      const double tx = std::sin(q[2]), tz = std::cos(q[2]);
      return Eigen::Vector4d(tx, tz, -q[3] / EI, -(tx * Nz - tz * Nx));
    };
    constexpr int steps = 4000;
    const double h = L / steps;
    double pax = 0, paz = 0;
    for (int k = 0; k < steps; ++k) {
      const double s = k * h, mid = s + 0.5 * h;
      const Eigen::Vector4d k1 = rhs(mid - 0.5 * h + 1e-15, y), k2 = rhs(mid, y + 0.5 * h * k1),
                            k3 = rhs(mid, y + 0.5 * h * k2), k4 = rhs(s + h - 1e-15, y + h * k3);
      y += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
      if (k + 1 == steps / 2) pax = y[0], paz = y[1];  // a = L / 2
    }
    const double dx = pax - cx, dz = paz - cz, d = std::hypot(dx, dz);
    res = Eigen::Vector3d(y[3] / (P * L), (d - rho - r_o) / L, std::cos(phi) * dz - std::sin(phi) * dx);
  };
  Eigen::Vector3d u(-L * P + a * 2.5 * P, 2.5 * P, M_PI), r;
  for (int it = 0; it < 50; ++it) {
    shoot(u, r);
    if (r.norm() < 1e-13) break;
    Eigen::Matrix3d J;
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d up = u, rp;
      const double h = 1e-7 * std::max(1.0, std::abs(u[c]));
      up[c] += h;
      shoot(up, rp);
      J.col(c) = (rp - r) / h;
    }
    u -= J.partialPivLu().solve(r);
  }
  return u[1];
}


}  // namespace tdcr::test
