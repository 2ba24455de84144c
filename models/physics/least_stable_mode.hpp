// Private to the models: the least stable mode of a non-symmetric stiffness (the real parts of
// its eigenvalues decide stability under non-conservative loads, docs/models.md "Stability").
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <string>

#include <Eigen/Core>

namespace tdcr::detail {

/// The words of least_stable_mode()'s note for a complex pair.
inline constexpr const char* kOscillatoryMode = "a complex pair";

/// Whether a Stability::method names an oscillatory least stable mode (least_stable_mode()): a
/// loss of stability the loading path does not meet as a fold or a bifurcation
/// (path_following.cpp).
inline bool oscillatory_mode(const std::string& method) {
  return method.find(std::string("least stable mode: ") + kOscillatoryMode) != std::string::npos;
}

/// The eigenvalue of smallest real part of `eigenvalues` (of a real matrix, so complex ones come
/// in conjugate pairs), and in `note` what kind of mode it is: a real eigenvalue (divergence-type:
/// the equilibrium turns into a fold or a bifurcation where it crosses 0) or a complex pair
/// (an oscillatory, flutter-type mode, which only non-conservative loads have: where its real
/// part crosses 0 the loading path has no fold and no bifurcation, and the verdict depends on
/// the overdamped motion assumed, dq/dt = -K q in the scaled coordinates).
inline double least_stable_mode(const Eigen::VectorXcd& eigenvalues, std::string& note) {
  int k = 0;
  for (int i = 1; i < eigenvalues.size(); ++i)
    if (eigenvalues[i].real() < eigenvalues[k].real()) k = i;
  if (eigenvalues.size() == 0) return NAN;
  const std::complex<double> z = eigenvalues[k];
  char buf[200];
  if (std::abs(z.imag()) > 1e-9 * std::max(1.0, std::abs(z)))
    std::snprintf(buf, sizeof buf,
                  "; least stable mode: %s %.3g +- %.3gi (oscillatory, flutter-type, as only "
                  "non-conservative loads have)",
                  kOscillatoryMode, z.real(), std::abs(z.imag()));
  else
    std::snprintf(buf, sizeof buf, "; least stable mode: a real eigenvalue %.3g (divergence-type)", z.real());
  note = buf;
  return z.real();
}

}  // namespace tdcr::detail
