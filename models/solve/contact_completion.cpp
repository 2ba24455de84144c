// The contact completion of the shooting models (contact_completion.hpp, docs/contact.md).
#include "solve/contact_completion.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "solve/newton_summary.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr::detail {

namespace {

constexpr int kMaxContactRounds = 8;
constexpr double kContactStepFactor = 100.0;
/// Below this scaled force (of F_s) every candidate of a contact answer is taken as left.
constexpr double kLeftForce = 1e-9;

// The candidates' margin: pairs this close join the penetrated ones.
double margin(const ContactHost& host) { return 0.1 * host.contact_length() / host.contact_disks(); }

// The disk poses between two shapes (`from`, `to`: frames 0..N), each disk along the screw from
// its pose in one to its pose in the other (position linear, rotation by the geodesic), at 15
// samples: an obstacle thinner than the step between the shapes can lie between them, penetrated
// by neither. The first sample that penetrates a pair that is not a candidate adds its pairs (as
// contact::scan with `add`); returns that scan, passed_through set.
contact::Scan swept_scan(ContactHost& host, const std::vector<Frame>& from, const std::vector<Frame>& to,
                         std::vector<Frame>& between) {
  constexpr int kSamples = 16;
  const int N = host.contact_disks();
  for (int k = 1; k < kSamples; ++k) {
    contact::frames_between(from, to, double(k) / kSamples, between);
    contact::Scan found = contact::scan(host.contact_obstacles(), host.contact_surfaces(), between.data(), N,
                                        margin(host), true, host.contact_candidates());
    if (found.penetrates) {
      found.passed_through = true;
      return found;
    }
  }
  return contact::Scan{};
}

// Whether the disks' way from `from` to `to` (swept as in swept_scan) passes deeper than a
// quarter of its radius into a sphere, cylinder or capsule (contact::Scan::passed_through; every
// pair, candidates or not): an answer that penetrates such an obstacle only shallowly may still
// have come through it.
bool passes_through(const ContactHost& host, const std::vector<Frame>& from, const std::vector<Frame>& to,
                    std::vector<Frame>& between) {
  constexpr int kSamples = 16;
  const int N = host.contact_disks();
  std::vector<contact::Candidate> none;  // every pair is scanned (and none is added)
  for (int k = 1; k < kSamples; ++k) {
    contact::frames_between(from, to, double(k) / kSamples, between);
    if (contact::scan(host.contact_obstacles(), host.contact_surfaces(), between.data(), N, margin(host), false, none)
            .passed_through)
      return true;
  }
  return false;
}

// The straight robot at rest: disk j at s_j e_z.
void rest_frames(const ContactHost& host, std::vector<Frame>& frames) {
  const std::vector<double>& s = host.contact_disk_s();
  frames.assign(s.size(), Frame{});
  for (std::size_t j = 0; j < s.size(); ++j) frames[j].p = s[j] * Vec3::UnitZ();
}

// Natural-parameter steps of the load factor from rest, each a Newton solve from the last answer;
// a step whose answer penetrates a pair left out adds it and is solved again; a failed step is
// halved (the lumped models' loading with contacts, lumped_contact.cpp).
bool load_with_contacts(ContactHost& host, Eigen::VectorXd& y, const bvp::NewtonOptions& nopt,
                        std::vector<Frame>& frames, SolverSummary& work) {
  std::vector<Frame> last_frames, between;
  rest_frames(host, last_frames);
  constexpr double kFirstStep = 0.125, kMinStep = 1.0 / 1024.0;
  bvp::ParameterizedSystem& sys = host.contact_system();
  std::vector<contact::Candidate>& cands = host.contact_candidates();
  sys.set_parameter(0.0);
  host.contact_rest(y);
  double t = 0.0, h = kFirstStep;
  Eigen::VectorXd last = y;
  while (t < 1.0) {
    const double next = std::min(1.0, t + h);
    sys.set_parameter(next);
    SolverSummary step;
    copy_newton_result(host.contact_newton().solve(sys, y, nopt), step);
    add_work(step, work);
    ++work.continuation_steps;
    work.message = step.message;
    if (!step.converged()) {
      y = last;
      h *= 0.5;
      if (h < kMinStep) {
        sys.set_parameter(1.0);
        work.termination = step.termination;
        return false;
      }
      continue;
    }
    const std::size_t before = cands.size();
    if (!host.contact_frames(y, frames)) return false;
    if (!contact::scan(host.contact_obstacles(), host.contact_surfaces(), frames.data(), host.contact_disks(),
                       margin(host), true, cands)
             .penetrates)
      swept_scan(host, last_frames, frames, between);
    if (cands.size() != before) {  // a new contact closed within this step: again with it
      host.contact_candidates_changed();
      const Eigen::Index n = last.size(), added = static_cast<Eigen::Index>(cands.size() - before);
      y.resize(n + added);
      y.head(n) = last;
      y.tail(added).setZero();
      last = y;
      continue;
    }
    t = next;
    last = y;
    last_frames = frames;
    h = std::min(2.0 * h, 0.25);
  }
  sys.set_parameter(1.0);
  work.termination = TerminationType::Converged;
  return true;
}

}  // namespace

void warm_contacts(const Solution& previous, int disks, int obstacles, double force_scale,
                   std::vector<contact::Candidate>& candidates) {
  candidates.clear();
  for (const Contact& p : previous.contacts) {
    if (p.obstacle < 0 || p.obstacle >= obstacles || p.disk_index < 1 || p.disk_index > disks) continue;
    contact::Candidate c;
    c.disk = p.disk_index, c.obstacle = p.obstacle;
    c.body = p.disk ? ContactBody::Disk : ContactBody::Backbone;
    c.lambda = p.force / force_scale;
    candidates.push_back(c);
  }
}

ModelProblem::Completion complete_contacts(ContactHost& host, Eigen::VectorXd& y, const bvp::NewtonOptions& options,
                                           SolverSummary& summary) {
  if (host.contact_obstacles().empty()) return ModelProblem::Completion::Done;
  bvp::NewtonOptions nopt = options;
  nopt.reuse_jacobian = false;  // the contact set changes between solves
  nopt.freeze_jacobian_below = 0.0;
  // A model's bound on the Newton step (VC's single shooting: 1 in the scales of the loads) is
  // too short for the step to the contact forces, which the loads' scales do not know (an
  // unactuated robot bent by a lumen: n(0) of 50 force scales).
  if (nopt.max_newton_step > 0.0) nopt.max_newton_step *= kContactStepFactor;
  bvp::ParameterizedSystem& sys = host.contact_system();
  std::vector<contact::Candidate>& cands = host.contact_candidates();
  contact::Law& law = host.contact_law();
  std::vector<Frame> frames;
  for (int round = 0;; ++round) {
    if (!host.contact_frames(y, frames)) {
      summary.termination = TerminationType::IntegrationFailed;
      summary.message += "; the shots of the answer failed in the contact test";
      return ModelProblem::Completion::Done;
    }
    const std::size_t before = cands.size();
    contact::Scan found = contact::scan(host.contact_obstacles(), host.contact_surfaces(), frames.data(),
                                        host.contact_disks(), margin(host), true, cands);
    if (!found.penetrates && round == 0 && before == 0) {
      // The free answer may have passed a thin obstacle on its way from rest: then loaded from
      // rest with the contacts.
      std::vector<Frame> rest, between;
      rest_frames(host, rest);
      found = swept_scan(host, rest, frames, between);
    }
    if (!found.penetrates) return ModelProblem::Completion::Done;
    if (round == 0 && before == 0 && !found.passed_through) {
      // Shallow at the answer, but through an obstacle's middle on the way from rest (a tip that
      // slid past a ball on the far side of it): the loading from rest meets it on the near side.
      std::vector<Frame> rest, between;
      rest_frames(host, rest);
      found.passed_through = passes_through(host, rest, frames, between);
    }
    if (round == kMaxContactRounds || cands.size() == before) {
      summary.termination = TerminationType::NoConvergence;
      summary.message += "; the answer still penetrates an obstacle after " + std::to_string(round) +
                         " rounds of contact candidates";
      return ModelProblem::Completion::Done;
    }
    host.contact_candidates_changed();
    const Eigen::Index n = y.size(), added = static_cast<Eigen::Index>(cands.size() - before);
    y.conservativeResize(n + added);
    y.tail(added).setZero();
    summary.unknowns = sys.size();
    SolverSummary step;
    if (round == 0 && found.passed_through) {
      // The free answer is deep inside a sphere, cylinder or capsule: loaded from rest with the
      // contacts, so that the robot meets the obstacle on the side it comes from.
      if (load_with_contacts(host, y, nopt, frames, step)) {
        add_work(step, summary);
        summary.message += "; contact with " + std::to_string(cands.size()) +
                           " candidates, loaded from rest (the free answer had passed an obstacle's middle): " +
                           step.message;
        continue;
      }
      add_work(step, summary);
      summary.termination = step.termination;
      summary.message += "; loading from rest with contact failed: " + step.message;
      return ModelProblem::Completion::FollowAgain;
    }
    const Eigen::VectorXd start = y;
    if (law.stiffness == 0.0 && found.deepest < margin(host)) {
      // A few semismooth Newton steps on min(a, b) first (the active set's linearisation closes a
      // penetrated gap in one step), then Fischer-Burmeister from there.
      bvp::NewtonOptions mopt = nopt;
      mopt.max_iterations = 3;
      law.use_min = true;
      SolverSummary pre;
      copy_newton_result(host.contact_newton().solve(sys, y, mopt), pre);
      add_work(pre, summary);
      summary.message += "; min(gap, force) steps: " + pre.message;
      law.use_min = false;
      if (!pre.converged()) y = start;
    }
    copy_newton_result(host.contact_newton().solve(sys, y, nopt), step);
    if (!step.converged() && law.stiffness == 0.0) {
      // Rigid contact from a deeply penetrating answer can diverge: compliant contact first, its
      // stiffness raised a decade per solve from F_s / L to 1e6 times that, then rigid.
      add_work(step, summary);
      y = start;
      const double soft = law.force_scale / host.contact_length();
      int decade = 0;
      for (; decade <= 7; ++decade) {
        law.stiffness = decade < 7 ? soft * std::pow(10.0, decade) : 0.0;
        step = SolverSummary{};
        copy_newton_result(host.contact_newton().solve(sys, y, nopt), step);
        if (!step.converged() || decade == 7) break;
        add_work(step, summary);
      }
      law.stiffness = 0.0;
      step.message += step.converged() ? " (rigid contact reached through compliant contact of rising stiffness)"
                                       : " (compliant contact of rising stiffness failed at stage " +
                                             std::to_string(decade) + " of 7)";
    }
    // Newton from a penetrating answer may leave every contact: an equilibrium of the free robot
    // that touches nothing is not the free answer (that one penetrates), so it lies on another
    // branch, reached through the obstacles (a column beyond buckling pushed into a corner comes
    // back bent the other way, an unstable answer). Loaded from rest with the contacts instead.
    const bool left = step.converged() && !cands.empty() &&
                      y.tail(static_cast<Eigen::Index>(cands.size())).maxCoeff() <= kLeftForce;
    if (left) step.message += " (every contact left: another branch of the free robot)";
    if (!step.converged() || left) {
      add_work(step, summary);
      SolverSummary path;
      if (load_with_contacts(host, y, nopt, frames, path)) {
        add_work(path, summary);
        summary.message += "; the contact solve failed (" + step.message + "), loaded from rest with " +
                           std::to_string(cands.size()) + " candidates: " + path.message;
        continue;
      }
      step = path;
    }
    add_work(step, summary);
    summary.termination = step.termination;
    summary.residual_norm = step.residual_norm;
    summary.physical_residual = step.physical_residual;
    summary.linear_solver = step.linear_solver;
    summary.message += "; contact with " + std::to_string(cands.size()) + " candidates: " + step.message;
    if (!step.converged()) return ModelProblem::Completion::FollowAgain;
  }
}

}  // namespace tdcr::detail
