// Contact of CCsub and PRB with the obstacles of the bound input (docs/contact.md): candidate
// contacts at the disks (the backbone's surface at a disk's centre, a disk's rim), each with its
// force magnitude as an unknown and a complementarity residual; their forces act on the disks in
// the recursive balance like the tendon forces and the tip wrench.
//
// Rigid contact: gap g >= 0, force f >= 0, g f = 0, as the Fischer-Burmeister function
// phi(a, b) = a + b - sqrt(a^2 + b^2) = 0 of the scaled gap a = g / r_o and force b = f / F_s,
// F_s = EI / L^2: semismooth, and Newton converges on it where strict complementarity holds.
// Compliant contact: f = k max(0, -g).
#include <algorithm>
#include <cmath>

#include "lumped/lumped_problem.hpp"
#include "solve/newton_summary.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::detail {

namespace {
// Rounds of candidates added after a penetrating answer before the solve gives up.
constexpr int kMaxContactRounds = 8;
// Scaled forces below this are reported as no contact (a candidate the answer does not touch
// has force 0 to Newton's tolerance).
constexpr double kReportedForce = 1e-9;
}  // namespace

void LumpedProblem::bind_contact(const ModelInput& input) {
  contacts_.clear();
  contact_step_ = false;
  contact_ = !input.environment.obstacles.empty();
  if (!contact_) return;
  obstacles_ = input.environment.obstacles;  // allocates only when the obstacles grow
  contact_stiffness_ = input.environment.contact.stiffness;
  contact_force_scale_ = body_.EI / (body_.length * body_.length);
  contact_length_scale_ = body_.backbone_radius > 0.0 ? body_.backbone_radius : 1e-3 * body_.length;
  contact_surfaces_.backbone_radius = body_.backbone_radius;
  contact_surfaces_.disk_radius = body_.disk_radius;
  // The contact solve is the recursive form; the free-space solve before it is that too, so
  // that an untouched obstacle leaves the free-space answer of the default formulation.
  banded_ = false;
  // An unloaded robot has no unknowns (it is straight), but an obstacle may be in its way: its
  // answer is then the straight robot solved for, which complete() can test.
  if (loads_.active == 0) {
    loads_.active = body_.N;
    reduced_ = body_.reduced(body_.N);
  }
}

void LumpedProblem::enter_contact_mode() {
  residual_changed();
  loads_.active = body_.N;  // a contact can load any disk
  banded_ = false;
  reduced_ = false;
  // Structured Newton steps (lumped_contact_jacobian.cpp, KLU on (m + 12) N + candidates
  // unknowns) from LumpedBody::contact_structured_from subsegments on (PRB 16, CCsub 30: where
  // the free-space solve took the KLU system before its steps became the block LU of
  // lumped_structured.cpp), else dense LU on the m N + candidates unknowns. bench_contact
  // (n = 10, N = 20) cold: PRB 1090 / 450 us structured, 1400 / 690 us dense (wall / point);
  // CCsub 520 / 310 us either way.
  contact_step_ = body_.reduced(body_.N) && body_.N >= body_.contact_structured_from;
  damping_ = 0.0;
}

void LumpedProblem::append_contact_unknowns(Eigen::VectorXd& y) const {
  if (contacts_.empty()) return;
  const Eigen::Index n = y.size();
  y.conservativeResize(n + static_cast<Eigen::Index>(contacts_.size()));
  for (std::size_t i = 0; i < contacts_.size(); ++i) y[n + static_cast<Eigen::Index>(i)] = contacts_[i].lambda;
}

void LumpedProblem::read_contact_unknowns(const double* y) {
  const double* lambda = y + stride() * active();
  for (std::size_t i = 0; i < contacts_.size(); ++i) contacts_[i].lambda = lambda[i];
}

void LumpedProblem::evaluate_contacts() {
  body_.statics.disk_loads(loads_, frames_.data(), disk_f_.data(), disk_m_.data());
  for (ContactCandidate& c : contacts_) {
    const Frame& frame = frames_[c.disk];
    const double radius = c.body == ContactBody::Disk ? body_.disk_radius[c.disk] : body_.backbone_radius;
    c.at = contact_point(obstacles_[c.obstacle], frame, c.body, radius);
    // Reaction forces: not scaled by the load factor (they are whatever keeps the robot out).
    const Vec3 f = (c.lambda * contact_force_scale_) * c.at.normal;
    disk_f_[c.disk] += f;
    disk_m_[c.disk] += (c.at.point - frame.p).cross(f);
  }
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), disk_f_.data(), disk_m_.data(), F_.data(),
                                M_.data());
}

void LumpedProblem::contact_residuals(double* f) const {
  const contact::Law law = contact_law();
  for (std::size_t i = 0; i < contacts_.size(); ++i) f[i] = law.residual(contacts_[i].at.gap, contacts_[i].lambda);
}

void LumpedProblem::report_contacts(Solution& solution) const {
  contact::report(contacts_, body_.statics.routing().disk_s, contact_force_scale_, kReportedForce, solution.contacts);
}

bool LumpedProblem::penetrating_pairs(const Eigen::VectorXd& x, bool add) {
  contact_frames_.resize(body_.N + 1);
  body_.compute_frames(x.data(), body_.N, loads_.stretch_data(), contact_frames_.data());
  return penetrating_frames(contact_frames_.data(), add);
}

bool LumpedProblem::penetrating_frames(const Frame* frames, bool add) {
  // Pairs this close join the candidates with the penetrating ones: the contact solve then moves
  // the robot without stepping into the neighbours of the first contacts unseen.
  const double margin = 0.1 * body_.length / body_.N;
  const contact::Scan found = contact::scan(obstacles_, contact_surfaces_, frames, body_.N, margin, add, contacts_);
  passed_through_ = found.passed_through;
  deepest_ = found.deepest;
  return found.penetrates;
}

void LumpedProblem::sweep_frames(const Eigen::VectorXd& from, const Eigen::VectorXd& to) {
  sweep_from_.resize(body_.N + 1);
  sweep_to_.resize(body_.N + 1);
  body_.compute_frames(from.data(), body_.N, loads_.stretch_data(), sweep_from_.data());
  body_.compute_frames(to.data(), body_.N, loads_.stretch_data(), sweep_to_.data());
}

void LumpedProblem::frames_between(double t) {
  // Each disk along the screw between its two poses, as the shooting models sweep
  // (solve/contact_completion.cpp): the unknowns interpolated would turn PRB's bending plane on the
  // way, a path the robot never takes.
  contact::frames_between(sweep_from_, sweep_to_, t, contact_frames_);
}

bool LumpedProblem::swept_pairs(const Eigen::VectorXd& from, const Eigen::VectorXd& to) {
  // Shapes between two answers: an obstacle thinner than one step of the robot can lie between
  // them, penetrated by neither.
  constexpr int kSamples = 16;
  sweep_frames(from, to);
  for (int k = 1; k < kSamples; ++k) {
    frames_between(double(k) / kSamples);
    if (penetrating_frames(contact_frames_.data(), true)) return true;
  }
  return false;
}

bool LumpedProblem::passes_through(const Eigen::VectorXd& from, const Eigen::VectorXd& to) {
  // The shapes between (as swept_pairs), every pair scanned and none added: deeper than a quarter
  // of its radius into a sphere, cylinder or capsule on the way (contact::Scan::passed_through).
  constexpr int kSamples = 16;
  std::vector<contact::Candidate> none;
  const double margin = 0.1 * body_.length / body_.N;
  sweep_frames(from, to);
  for (int k = 1; k < kSamples; ++k) {
    frames_between(double(k) / kSamples);
    if (contact::scan(obstacles_, contact_surfaces_, contact_frames_.data(), body_.N, margin, false, none)
            .passed_through)
      return true;
  }
  return false;
}

bool LumpedProblem::warm_contacts(const Solution& previous) {
  if (!contact_ || previous.contacts.empty()) return false;
  enter_contact_mode();
  contacts_.clear();
  for (const Contact& p : previous.contacts) {
    if (p.obstacle < 0 || p.obstacle >= static_cast<int>(obstacles_.size()) || p.disk_index < 1 ||
        p.disk_index > body_.N)
      continue;
    ContactCandidate c;
    c.disk = p.disk_index, c.obstacle = p.obstacle;
    c.body = p.disk ? ContactBody::Disk : ContactBody::Backbone;
    c.lambda = p.force / contact_force_scale_;
    contacts_.push_back(c);
  }
  // A warm solve mostly reuses the last factorisation (modified Newton, adjust_warm): its
  // solves, cheaper dense at these sizes (bench_contact's trajectory, n = 10: PRB 24 kHz dense,
  // 18 kHz structured; CCsub 68 kHz, 48 kHz).
  constexpr int kDenseWarmUnknowns = 120;
  contact_step_ = contact_step_ && size() > kDenseWarmUnknowns;
  return !contacts_.empty();
}

bool LumpedProblem::load_with_contacts(Eigen::VectorXd& y, const bvp::NewtonOptions& nopt, SolverSummary& work) {
  // Natural-parameter steps of the load factor from rest, each a Newton solve from the last
  // answer; a step whose answer penetrates a pair left out adds it and is solved again; a failed
  // step is halved.
  constexpr double kFirstStep = 0.125, kMinStep = 1.0 / 1024.0;
  rest_state(y);  // the straight robot, every candidate's force 0 (active: every subsegment)
  double t = 0.0, h = kFirstStep;
  Eigen::VectorXd last = y;
  while (t < 1.0) {
    const double next = std::min(1.0, t + h);
    set_parameter(next);
    residual_changed();
    SolverSummary step;
    copy_newton_result(newton().solve(*this, y, nopt), step);
    add_work(step, work);
    ++work.continuation_steps;
    work.message = step.message;
    if (!step.converged()) {
      y = last;
      h *= 0.5;
      if (h < kMinStep) {
        set_parameter(1.0);
        work.termination = step.termination;
        return false;
      }
      continue;
    }
    gather_x(y, x_);
    contact_x_ = x_;
    const std::size_t before = contacts_.size();
    if (!penetrating_pairs(contact_x_, true)) swept_pairs(last.head(contact_x_.size()), contact_x_);
    if (contacts_.size() != before) {  // a new contact closed within this step: again with it
      residual_changed();
      const Eigen::Index n = last.size(), added = static_cast<Eigen::Index>(contacts_.size() - before);
      y.resize(n + added);  // the last answer, its forces, and 0 for the new candidates
      y.head(n) = last;
      y.tail(added).setZero();
      last = y;
      continue;
    }
    t = next;
    last = y;
    h = std::min(2.0 * h, 0.25);
  }
  set_parameter(1.0);
  work.termination = TerminationType::Converged;
  return true;
}

ModelProblem::Completion LumpedProblem::complete(Eigen::VectorXd& y, const bvp::NewtonOptions& options,
                                                 SolverSummary& summary) {
  if (!contact_) return Completion::Done;
  bvp::NewtonOptions nopt = options;
  nopt.linear_solver = bvp::LinearSolverKind::Dense;
  // The set of active contacts changes between solves: a Jacobian of another set misleads.
  nopt.reuse_jacobian = false;
  nopt.freeze_jacobian_below = 0.0;
  // Modified Newton: a Jacobian serves up to 10 iterations. With the structured contact Jacobian
  // (lumped_contact_jacobian.cpp) its factorisation, not its differences, is the cost of a
  // Jacobian; bench_contact (n = 10) cold: 1 (exact Newton, 5-9 iterations) CCsub 520 / 310 us,
  // PRB 1100 / 450 us (wall / point); 3: 350 / 220, 650 / 330; 10: 285 / 210, 640 / 295.
  nopt.max_setup_calls = 10;
  // A model's bound on the Newton step (PRB: 1, for its bending-plane chart in cold solves) is
  // too short for the step from a penetrating free-space answer: examples/robot_against_wall.json
  // (PRB, a rim 7.5 mm into the wall) diverged with 5 steps of maximum length at 1 and converged
  // in 8 iterations (exact Newton) at 3 and at 10.
  if (nopt.max_newton_step > 0.0) nopt.max_newton_step *= 10.0;
  for (int round = 0;; ++round) {
    gather_x(y, x_);
    read_contact_unknowns(y.data());
    contact_x_.setZero(body_.per_subsegment * body_.N);
    contact_x_.head(x_.size()) = x_;
    const std::size_t before = contacts_.size();
    bool penetrates = penetrating_pairs(contact_x_, true);
    if (!penetrates && round == 0 && before == 0) {
      // The free answer may have passed a thin obstacle on its way from rest: then loaded from
      // rest with the contacts (load_with_contacts).
      penetrates = swept_pairs(Eigen::VectorXd::Zero(contact_x_.size()), contact_x_);
      passed_through_ = penetrates;
    }
    if (!penetrates) return Completion::Done;
    if (round == 0 && before == 0 && !passed_through_) {
      // Shallow at the answer, but through an obstacle's middle on the way from rest (a tip that
      // slid past a ball on the far side of it): the loading from rest meets it on the near side.
      passed_through_ = passes_through(Eigen::VectorXd::Zero(contact_x_.size()), contact_x_);
    }
    if (round == kMaxContactRounds || contacts_.size() == before) {
      summary.termination = TerminationType::NoConvergence;
      summary.message += "; the answer still penetrates an obstacle after " + std::to_string(round) +
                         " rounds of contact candidates";
      return Completion::Done;
    }
    if (before == 0) enter_contact_mode();
    residual_changed();
    y = contact_x_;
    for (std::size_t i = before; i < contacts_.size(); ++i) contacts_[i].lambda = 0.0;
    append_contact_unknowns(y);
    summary.unknowns = size();
    SolverSummary step;
    if (round == 0 && passed_through_) {
      // The free answer is deep inside a sphere, cylinder or capsule: load the robot from rest
      // with the contacts instead, so that it meets the obstacle on the side it comes from.
      if (load_with_contacts(y, nopt, step)) {
        add_work(step, summary);
        summary.message += "; contact with " + std::to_string(contacts_.size()) +
                           " candidates, loaded from rest (the free answer had passed an obstacle's middle): " +
                           step.message;
        continue;  // then the usual test for pairs left out
      }
      add_work(step, summary);
      summary.termination = step.termination;
      summary.message += "; loading from rest with contact failed: " + step.message;
      return Completion::FollowAgain;
    }
    const Eigen::VectorXd start = y;
    if (contact_stiffness_ == 0.0 && deepest_ < 0.1 * body_.length / body_.N) {
      // A few semismooth Newton steps on min(a, b) first: from b = 0 at a penetrating pair
      // Fischer-Burmeister's linearisation mixes gap and force (gradient (2, 1)), min's is the
      // active set's (the gap closes in one step), and a propped cantilever converges in 2
      // iterations instead of 12. Only where the free answer penetrates less than the candidates'
      // margin (0.1 L / N): from a rim 7.5 mm deep in a wall (bench_contact's wall, the active set
      // changing on the way) min took 8 iterations and 22 residuals against Fischer-Burmeister's
      // 7 and 12; where min does not converge in kMinIterations, Fischer-Burmeister from the free
      // answer as before.
      constexpr int kMinIterations = 3;
      bvp::NewtonOptions mopt = nopt;
      mopt.max_iterations = kMinIterations;
      contact_min_ = true;
      residual_changed();
      SolverSummary pre;
      copy_newton_result(newton().solve(*this, y, mopt), pre);
      add_work(pre, summary);
      summary.message += "; min(gap, force) steps: " + pre.message;
      contact_min_ = false;
      residual_changed();
      if (!pre.converged()) y = start;
    }
    copy_newton_result(newton().solve(*this, y, nopt), step);
    if (!step.converged() && contact_stiffness_ == 0.0) {
      // Rigid contact from a deeply penetrating answer can diverge (PRB, a 1.5 N tip force into a
      // wall): compliant contact first, its stiffness raised a decade per solve from F_s / L
      // (a penetration of L for the force scale) to 1e6 times that, then rigid from there.
      add_work(step, summary);
      y = start;
      step = SolverSummary{};
      const double soft = contact_force_scale_ / body_.length;
      int decade = 0;
      for (; decade <= 7; ++decade) {
        contact_stiffness_ = decade < 7 ? soft * std::pow(10.0, decade) : 0.0;
        residual_changed();
        step = SolverSummary{};
        copy_newton_result(newton().solve(*this, y, nopt), step);
        if (!step.converged() || decade == 7) break;
        add_work(step, summary);  // the last stage's work is added below
      }
      contact_stiffness_ = 0.0;
      residual_changed();
      step.message += step.converged() ? " (rigid contact reached through compliant contact of rising stiffness)"
                                       : " (compliant contact of rising stiffness failed at stage " +
                                             std::to_string(decade) + " of 7)";
    }
    add_work(step, summary);
    summary.termination = step.termination;
    summary.residual_norm = step.residual_norm;
    summary.physical_residual = step.physical_residual;
    summary.linear_solver = step.linear_solver;
    summary.message += "; contact with " + std::to_string(contacts_.size()) + " candidates: " + step.message;
    if (!step.converged()) return Completion::FollowAgain;  // cold, with these candidates
  }
}

}  // namespace tdcr::detail
