#include "tdcr/models/ccsub.hpp"

#include <cmath>

#include "common/lumped_problem.hpp"
#include "common/model_factories.hpp"

namespace tdcr {

namespace {

// Arc functions of the bending angle t, with series where the closed forms cancel:
// s1 = sin t / t, c2 = (1 - cos t) / t^2, g3 = (t - sin t) / t^3.
struct ArcCoefficients {
  double s1, c2, g3;
  explicit ArcCoefficients(double t2) {
    if (t2 < 1e-8) {
      s1 = 1.0 - t2 / 6.0 + t2 * t2 / 120.0;
      c2 = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
      g3 = 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0;
    } else {
      const double t = std::sqrt(t2);
      const double s = std::sin(t), c = std::cos(t);
      s1 = s / t;
      c2 = (1.0 - c) / t2;
      g3 = (t - s) / (t2 * t);
    }
  }
};

class CcsubBody final : public detail::LumpedBody {
 public:
  CcsubBody(const Robot& robot, const TendonRouting& routing, const Effects& effects)
      : LumpedBody(robot, routing, effects, 3) {}

  void compute_frames(const double* x, int J, Frame* frames) const override { arcs(x, J, frames, nullptr); }
  std::unique_ptr<detail::LumpedProblem> make_problem() const override;

  // Frames of all disks from the unknowns of subsegments 1..J; subsegments beyond J are
  // straight. If centroids is not null, also the arc centroids (base frame).
  void arcs(const double* x, int J, Frame* frames, Vec3* centroids) const {
    frames[0] = Frame{};
    for (int j = 1; j <= N; ++j) {
      const double l = statics.length(j);
      const Frame& prev = frames[j - 1];
      Frame& f = frames[j];
      if (j > J) {
        f.R = prev.R;
        f.p = prev.p + l * prev.R.col(2);
        if (centroids) centroids[j] = prev.p + 0.5 * l * prev.R.col(2);
        continue;
      }
      const double bx = x[3 * (j - 1)], by = x[3 * (j - 1) + 1], eps = x[3 * (j - 1) + 2];
      const double t2 = bx * bx + by * by;
      const ArcCoefficients a(t2);
      // Arc end in the frame of disk j-1 (Eq. 5; the arc bends towards u x e_z = (u_y, -u_x)).
      const Vec3 p_loc(by * l * a.c2, -bx * l * a.c2, l * a.s1);
      // Rotation exp([u l]) R_z(eps) (Eq. 8 with the twist of Section 3.1).
      Mat3 Rb;
      const double c2 = a.c2;
      Rb << 1.0 - c2 * by * by, c2 * bx * by, a.s1 * by,
            c2 * bx * by, 1.0 - c2 * bx * bx, -a.s1 * bx,
            -a.s1 * by, a.s1 * bx, 1.0 - c2 * t2;
      const double ce = std::cos(eps), se = std::sin(eps);
      Mat3 Rl;
      Rl.col(0) = ce * Rb.col(0) + se * Rb.col(1);
      Rl.col(1) = -se * Rb.col(0) + ce * Rb.col(1);
      Rl.col(2) = Rb.col(2);
      f.R = prev.R * Rl;
      f.p = prev.p + prev.R * p_loc;
      if (centroids) {
        const Vec3 c_loc(by * l * a.g3, -bx * l * a.g3, l * a.c2);
        centroids[j] = prev.p + prev.R * c_loc;
      }
    }
  }
};

// The 3J residuals of Eq. 43 with the recursive balance Eq. 44-47 (see ccsub.hpp).
class CcsubProblem final : public detail::LumpedProblem {
 public:
  explicit CcsubProblem(const CcsubBody& body) : LumpedProblem(body), body_(body) {}

  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    evaluate(x.data());
    const double gj_ei = body_.GJ / body_.EI;
    for (int j = 1; j <= active(); ++j) {
      const Mat3& Ra = frames_[j - 1].R;
      // Moment about O_{j-1} of everything distal of disk j-1 (Eq. 45, 47), frame of disk j-1.
      const Vec3 m_loc = Ra.transpose() * base_moment(j);
      const Vec3 z_loc = Ra.transpose() * frames_[j].R.col(2);
      const double s = body_.statics.length(j) / body_.EI;
      const int i = 3 * (j - 1);
      // Eq. 43 scaled by l/EI: l u + (GJ/EI) eps z_j - (l/EI) M_j = 0, frame of disk j-1.
      f[i] = x[i] + gj_ei * x[i + 2] * z_loc.x() - s * m_loc.x();
      f[i + 1] = x[i + 1] + gj_ei * x[i + 2] * z_loc.y() - s * m_loc.y();
      f[i + 2] = gj_ei * x[i + 2] * z_loc.z() - s * m_loc.z();
    }
    return f.allFinite();
  }

 private:
  void geometry(const double* x) override {
    body_.arcs(x, active(), frames_.data(), backbone_weight_on() ? centroids_.data() : nullptr);
  }
  const CcsubBody& body_;
};

std::unique_ptr<detail::LumpedProblem> CcsubBody::make_problem() const { return std::make_unique<CcsubProblem>(*this); }

std::unique_ptr<detail::LumpedBody> make_body(const Robot& robot, const TendonRouting& routing, const Effects& effects) {
  return std::make_unique<CcsubBody>(robot, routing, effects);
}

}  // namespace

CcsubModel::CcsubModel(const Robot& robot, const Effects& effects) : LumpedModel(robot, effects, make_body) {}

namespace detail {
std::unique_ptr<StaticModel> make_ccsub_model(const Robot& robot, const Effects& effects) {
  return std::make_unique<CcsubModel>(robot, effects);
}
}  // namespace detail

}  // namespace tdcr
