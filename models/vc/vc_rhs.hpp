// Private to models/vc: the tendon-loaded rod of one robot segment, the ODE VC integrates (the
// rod of cosserat::rod_rhs with the segment's tensioned tendons, optionally with the tendon
// lengths as extra states).
#pragma once

#include <vector>

#include "tdcr/bvp/integrator.hpp"
#include "tdcr/core/robot.hpp"
#include "tdcr/models/cosserat_rod.hpp"

namespace tdcr::vc {

/// A tendon whose length is integrated (every tendon through the segment, tensioned or not).
struct LengthTerm {
  Vec3 r = Vec3::Zero();               ///< Body-frame offset (straight routing).
  int index = 0;                       ///< Global tendon index.
  const RoutedTendon* tendon = nullptr;  ///< Its routing (read when the segment is not all straight).
};

/// The tendon loads of one segment at the current load factor.
struct SegmentLoads {
  std::vector<cosserat::TendonLoad> tendons;      ///< Tensioned, running through the segment.
  std::vector<int> tendon_index;                  ///< Global index of each of `tendons`.
  std::vector<cosserat::TendonLoad> terminating;  ///< Tensioned, ending at the segment's end.
  std::vector<int> terminating_index;             ///< Global index of each of `terminating`.
  std::vector<LengthTerm> lengths;                ///< Every tendon running through the segment.
  // General routing (docs/models.md, "Tendon routing").
  bool all_straight = true;  ///< Every tendon through the segment straight: offsets constant (fast path).
  std::vector<const RoutedTendon*> routed;              ///< The routing of each of `tendons`.
  std::vector<const RoutedTendon*> terminating_routed;  ///< The routing of each of `terminating`.
  mutable std::vector<cosserat::TendonLoad> at_s;              ///< Scratch: `tendons` at one s.
  mutable std::vector<cosserat::TendonLoad> terminating_at_s;  ///< Scratch: `terminating` at one s.

  /// `tendons` with r_k, r_k', r_k'' at arc length s (themselves if all straight; no allocation).
  const std::vector<cosserat::TendonLoad>& tendons_at(double s) const;
  /// `terminating` likewise.
  const std::vector<cosserat::TendonLoad>& terminating_at(double s) const;
};

/// The most degenerate tensioned tendon path seen by a watching rod (TendonRod::watch).
///
/// The measure is curvature x offset, c_k = -(u x r_k) . v / |v|^2 = 1 - (q_k . v) / |v|^2 with
/// q_k = v + u x r_k the tangent of the fully constrained tendon path: the fraction of the
/// backbone's advance that the tendon loses by running on the inside of the bend (kappa |r_k| for
/// a tendon straight towards the centre of curvature). At c_k = 1 the tendon sits on the centre of
/// curvature and its path degenerates (q_k . v = 0); beyond, it would have to run backwards, i.e.
/// cross the backbone. No actuation of a real robot passes c_k = 1.
struct Degeneracy {
  double value = -1e300;  ///< Largest c_k seen.
  double s = 0.0;         ///< Arc length where it was seen (m).
  int tendon = -1;        ///< Its global tendon index (-1: none seen).
  void reset() { *this = Degeneracy{}; }
};

/// The rod of one segment: 18 states, plus one length per tendon (|q_k|, Eq. 56) if requested.
/// Reads the section (its weight at the current load factor) and the segment's loads through
/// pointers, so that rescaling the loads needs no rebuild.
class TendonRod final : public bvp::OdeSystem {
 public:
  /// `section` and `segment` must outlive the rod; `tendon_count` length states if `lengths`.
  TendonRod(const cosserat::Section& section, const SegmentLoads& segment, int tendon_count, bool lengths)
      : section_(&section), seg_(&segment), tendon_count_(tendon_count), lengths_(lengths) {}
  int dimension() const override { return cosserat::kStateSize + (lengths_ ? tendon_count_ : 0); }
  void rhs(double s, const double* y, double* dyds) const override;
  /// Integrate segment `segment` from now on.
  void set(const SegmentLoads& segment) { seg_ = &segment; }
  /// Record the largest curvature x offset of the tensioned tendons in `d` (null: stop).
  void watch(Degeneracy* d) { watch_ = d; }

 private:
  template <bool Shear, bool Gravity>
  void eval(double s, const double* y, double* dyds) const;

  const cosserat::Section* section_;
  const SegmentLoads* seg_;
  int tendon_count_;
  bool lengths_;
  Degeneracy* watch_ = nullptr;
};

}  // namespace tdcr::vc
