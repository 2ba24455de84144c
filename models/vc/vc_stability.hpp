// Private to models/vc: the stability of a converged VC equilibrium (vc_stability.cpp).
#pragma once

#include "tdcr/core/solution.hpp"
#include "vc/vc_shooting.hpp"

namespace tdcr::vc {

/// The conjugate-point test of Till & Rucker (IEEE T-RO 2017) on the equilibrium with base
/// wrench `base` = (n(0), m(0)) at load factor `load_factor`, conjugate points counted with
/// their multiplicity (see vc_stability.cpp for the definition); leaves W at that load factor.
Stability conjugate_point_test(VcWorkspace::Impl& W, const Vec6& base, double load_factor);

}  // namespace tdcr::vc
