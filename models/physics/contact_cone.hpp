// Private to models/: the cone test of weakly active contacts (touching, no force) in the
// stability tests with contact (docs/contact.md, "Stability with contact").
//
// At an answer whose weakly active contacts have no force, the second variation must be positive
// on the cone of admissible variations, {x : G_w x >= 0} (each such gap may open, none close),
// on the active contacts' tangent space. The tests bound this from both sides: with the weakly
// active contacts open (positive on the whole space: sufficient) and closed (positive on
// G_w x = 0: necessary). Between the two, a negative direction x of the open form proves
// instability when x or -x is admissible, since the form is even in x: so with one weakly active
// contact the open test decides alone, and with d negative directions spanning N, a nonzero ray
// of the cone {a in N : G_w N a >= 0} proves it (the form is negative on all of N).
#pragma once

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

namespace tdcr::physics {

/// Contacts with a scaled force (of F_s) above this are active: constraints of the stability
/// tests. Below it, a touching contact (gap below kTouching r_o) is weakly active.
constexpr double kActiveForce = 1e-6;
constexpr double kTouching = 1e-6;

/// The method's note on `weak` weakly active contacts taken as open (the sufficient test).
inline std::string weakly_active_note(int weak) {
  char buf[120];
  std::snprintf(buf, sizeof buf, "; %d weakly active (touching, force < %.0e F_s) taken as open: a sufficient test",
                weak, kActiveForce);
  return buf;
}

/// The method's note on an instability the cone test proves: `negative` negative directions
/// (`what` names them), one of them admissible.
inline std::string cone_unstable_note(int negative, const char* what) {
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "; %d %s, one direction of them admissible (no weakly active contact closes on it): unstable (the cone "
                "test)",
                negative, what);
  return buf;
}

/// Whether `negative` directions of negative curvature (the open form's Morse index) are sure to
/// include an admissible one against `weak` weakly active contacts, from the counts alone: with one
/// such contact (x or -x opens it), or with more negative directions than contacts (a combination
/// keeps every contact touching).
inline bool negative_direction_admissible(int weak, int negative) {
  return negative > 0 && (weak == 1 || negative > weak);
}

/// Whether the cone {a : Gn a >= 0} holds a nonzero vector (Gn: one row per weakly active contact,
/// its gap's gradient times an orthonormal basis of the negative directions; rows of unit size).
/// A kernel vector of Gn does (both signs); otherwise a pointed cone's extreme rays lie on d - 1
/// independent active rows, enumerated (few contacts). `tol`: the rows' round-off.
inline bool cone_has_ray(const Eigen::MatrixXd& Gn, double tol = 1e-9) {
  const int c = static_cast<int>(Gn.rows()), d = static_cast<int>(Gn.cols());
  if (d == 0) return false;
  if (negative_direction_admissible(c, d) || c == 0) return true;
  Eigen::FullPivLU<Eigen::MatrixXd> whole(Gn);
  whole.setThreshold(tol);
  if (whole.dimensionOfKernel() > 0) return true;
  if (d == 1) return (Gn.array() >= -tol).all() || (Gn.array() <= tol).all();
  // Subsets of d - 1 rows (c >= d here): their kernel's direction a, admissible if every other
  // row has one sign on it.
  std::vector<int> pick(static_cast<std::size_t>(d - 1));
  for (int i = 0; i < d - 1; ++i) pick[static_cast<std::size_t>(i)] = i;
  Eigen::MatrixXd A(d - 1, d);
  while (true) {
    for (int i = 0; i < d - 1; ++i) A.row(i) = Gn.row(pick[static_cast<std::size_t>(i)]);
    Eigen::FullPivLU<Eigen::MatrixXd> lu(A);
    lu.setThreshold(tol);
    if (lu.dimensionOfKernel() == 1) {
      const Eigen::VectorXd a = lu.kernel().col(0).normalized();
      const Eigen::VectorXd g = Gn * a;
      if ((g.array() >= -tol).all() || (g.array() <= tol).all()) return true;
    }
    // The next subset in lexicographic order.
    int i = d - 2;
    while (i >= 0 && pick[static_cast<std::size_t>(i)] == c - (d - 1) + i) --i;
    if (i < 0) break;
    ++pick[static_cast<std::size_t>(i)];
    for (int j = i + 1; j < d - 1; ++j) pick[static_cast<std::size_t>(j)] = pick[static_cast<std::size_t>(j - 1)] + 1;
  }
  return false;
}

}  // namespace tdcr::physics
