/// @file paper_robot.hpp
/// @brief The robot of the paper's case study (Table 3) and its maximum tension T_M (Eq. 55).
#pragma once

#include "tdcr/core/scene.hpp"

namespace tdcr::paper {

/// @brief Table 3: two 50 mm segments, n disks each, pitch radius 8 mm, 0.8 mm backbone,
/// E = 2.11e11 Pa times `stiffness_factor`, nu = 0.3. Tendons per segment: (0, +r_d) then
/// (0, -r_d), so T1, T2 end at segment 1 and T3, T4 at the tip.
Robot robot(int disks_per_segment, double stiffness_factor = 1.0);

/// @brief T_M of Eq. 55 for theta_M = 90 deg: (pi/2) EI / (3 r_d L) (5.5533 N for Table 3).
double max_tension(const Robot& robot);

/// @brief Tensions of case-study configuration c in 1..16: T_k = T_M if bit k-1 of c-1 is set.
std::vector<double> configuration_tensions(int c, double t_max);

/// @brief The paper's effects for `model` (a model name as in scene files, any case): its case
/// study removes the tendon force's normal component at the disks (Eq. 58,
/// `effects.disk_normal_force` "removed"), and its CCsub and PRB are inextensible (Eq. 43-51:
/// `effects.shear_extension` false for "ccsub" and "prb"; its CC shortens under the tendons'
/// compression as tdcr's does, its VC and VCref shear and extend); otherwise the library's
/// defaults.
Effects effects(const std::string& model);

/// @brief A tension-driven scene of the paper robot for configuration c (no loads), with the
/// paper's effects for `model` (effects(model)).
Scene scene(int disks_per_segment, int configuration, const std::string& model = "vcref");

}  // namespace tdcr::paper
