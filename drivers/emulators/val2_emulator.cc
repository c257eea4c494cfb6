#include "emulators/val2_emulator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/paths.h"
#include "robot/kinematic_tree.h"

namespace hgrasp::drivers {

// ---------------------------------------------------------------------------------------------
// The arm model.

TrapezoidArmModel::TrapezoidArmModel(const std::array<AxisLimits, 6>& limits,
                                     const device::Joint6& q0) {
  for (int k = 0; k < 6; ++k) axes_.emplace_back(limits[k], q0[k]);
}

device::Joint6 TrapezoidArmModel::q() const {
  device::Joint6 q;
  for (int k = 0; k < 6; ++k) q[k] = axes_[k].position();
  return q;
}

device::Joint6 TrapezoidArmModel::qd() const {
  device::Joint6 v;
  for (int k = 0; k < 6; ++k) v[k] = axes_[k].velocity();
  return v;
}

bool TrapezoidArmModel::moving() const {
  return std::any_of(axes_.begin(), axes_.end(), [](const TrapezoidAxis& a) { return a.moving(); });
}

void TrapezoidArmModel::MoveJoints(const device::Joint6& q_target, double speed_fraction) {
  // One normalised profile s(t) from 0 to 1 for all joints, q_k = q0_k + d_k s: its speed and
  // acceleration limits are those of the most constrained joint, so every joint stays within
  // its own limits and all arrive together. Each axis runs the profile scaled by |d_k|.
  const double f = std::clamp(speed_fraction, 1e-4, 1.0);
  double v_s = std::numeric_limits<double>::infinity();
  double a_s = std::numeric_limits<double>::infinity();
  std::array<double, 6> d;
  for (int k = 0; k < 6; ++k) {
    const AxisLimits& lim = axes_[k].limits();
    d[k] = std::abs(std::clamp(q_target[k], lim.min, lim.max) - axes_[k].position());
    if (d[k] > 1e-12) {
      v_s = std::min(v_s, f * lim.max_speed / d[k]);
      a_s = std::min(a_s, lim.max_accel / d[k]);
    }
  }
  for (int k = 0; k < 6; ++k) {
    const AxisLimits& lim = axes_[k].limits();
    if (d[k] > 1e-12) {
      // A joint already moving may need its full deceleration to turn round.
      const double accel = axes_[k].velocity() != 0.0 ? lim.max_accel : a_s * d[k];
      axes_[k].MoveTo(q_target[k], v_s * d[k], accel);
    } else {
      axes_[k].MoveTo(q_target[k], f * lim.max_speed, lim.max_accel);
    }
  }
}

void TrapezoidArmModel::Stop() {
  for (TrapezoidAxis& a : axes_) a.Stop();
}

void TrapezoidArmModel::Advance(double dt) {
  for (TrapezoidAxis& a : axes_) a.Advance(dt);
}

// ---------------------------------------------------------------------------------------------
// The controller.

Val2Emulator::Val2Emulator(std::unique_ptr<Val2ArmModel> model, robot::ArmKinematics kinematics,
                           const Pose3& X_WB, double speed_percent)
    : model_(std::move(model)),
      kinematics_(std::move(kinematics)),
      X_WB_(X_WB),
      speed_percent_(speed_percent) {}

void Val2Emulator::Advance(double t_s, std::vector<std::uint8_t>* out) {
  if (last_t_ >= 0.0 && t_s > last_t_) model_->Advance(t_s - last_t_);
  last_t_ = std::max(last_t_, t_s);
}

void Val2Emulator::Receive(std::span<const std::uint8_t> in, double t_s,
                           std::vector<std::uint8_t>* out) {
  Advance(t_s, out);  // a command acts on the arm as it is at t_s
  std::string echo, line;
  for (std::uint8_t b : in) {
    echo.clear();
    const auto event = discipline_.Feed(static_cast<char>(b), &echo, &line);
    if (event == val2::LineDiscipline::Event::kExecute) {
      echo += Execute(line, t_s);
      echo += val2::kPrompt;
    }
    out->insert(out->end(), echo.begin(), echo.end());
  }
}

val2::WhereReport Val2Emulator::Where() const {
  val2::WhereReport r;
  const device::Joint6 q = model_->q();
  for (int k = 0; k < 6; ++k) r.joints[k] = RadToDeg(q[k]);
  r.location = val2::PoseToTrans(X_WB_.inverse() * kinematics_.Forward(q));
  return r;
}

std::string Val2Emulator::Execute(const std::string& line, double t_s) {
  // An empty line (or only spaces) does nothing.
  if (line.find_first_not_of(' ') == std::string::npos) return "";
  val2::Command c;
  std::string error;
  if (val2::ParseCommand(line, &c, &error)) {
    switch (c.kind) {
      case val2::CommandKind::kWhere: {
        std::string out;
        for (const std::string& l : val2::FormatWhere(Where())) out += l + "\r\n";
        return out;
      }
      case val2::CommandKind::kSpeed:
        if (!(c.value > 0.0 && c.value <= 100.0)) {
          error = val2::kErrIllegalValue;
        } else {
          speed_percent_ = c.value;
        }
        break;
      case val2::CommandKind::kAbort:
        model_->Stop();
        break;
      case val2::CommandKind::kReady: {
        device::Joint6 q;
        for (int k = 0; k < 6; ++k) q[k] = DegToRad(kReadyDeg[k]);
        error = MoveTo(q);
        break;
      }
      case val2::CommandKind::kMove:
      case val2::CommandKind::kAppro: {
        device::Joint6 q;
        if (c.precision_point) {
          for (int k = 0; k < 6; ++k) q[k] = DegToRad(c.joints[k]);
          error = MoveTo(q);
          break;
        }
        // The compound transformation, HERE being where the tool is now; APPRO backs off
        // along the tool z axis.
        const Pose3 here = X_WB_.inverse() * kinematics_.Forward(model_->q());
        Pose3 X_BE = Pose3::Identity();
        for (const val2::LocationTerm& term : c.terms) {
          X_BE = X_BE * (term.here ? here : val2::TransToPose(term.trans));
        }
        if (c.kind == val2::CommandKind::kAppro) {
          X_BE = X_BE * Eigen::Translation3d(0.0, 0.0, -c.value / 1000.0);
        }
        error = Solve(X_BE, &q) ? MoveTo(q) : std::string(val2::kErrOutOfRange);
        break;
      }
    }
  }
  if (!error.empty()) {
    refused_.emplace_back(line, error);
    return val2::ErrorLine(error) + "\r\n";
  }
  if (c.kind != val2::CommandKind::kWhere) {
    executed_.push_back({t_s, line.substr(0, line.find_last_not_of(' ') + 1), c});
  }
  return "";
}

std::string Val2Emulator::MoveTo(const device::Joint6& q) {
  if (!kinematics_.WithinLimits(q)) return std::string(val2::kErrOutOfRange);
  model_->MoveJoints(q, speed_percent_ / 100.0);
  return "";
}

bool Val2Emulator::Solve(const Pose3& X_BE, device::Joint6* q_best) const {
  const device::Joint6 q_now = model_->q();
  double best = std::numeric_limits<double>::infinity();
  for (const robot::ArmIkSolution& s : kinematics_.Inverse(X_WB_ * X_BE)) {
    // Each joint at the turn (q + 2 pi k) nearest its present angle, within its limits.
    device::Joint6 q = s.q;
    bool ok = true;
    for (int j = 0; j < 6 && ok; ++j) {
      double pick = std::numeric_limits<double>::quiet_NaN();
      for (int k = -2; k <= 2; ++k) {
        const double v = s.q[j] + 2.0 * kPi * k;
        if (v < kinematics_.lower()[j] || v > kinematics_.upper()[j]) continue;
        if (std::isnan(pick) || std::abs(v - q_now[j]) < std::abs(pick - q_now[j])) pick = v;
      }
      if (std::isnan(pick)) ok = false;
      q[j] = pick;
    }
    if (!ok) continue;
    const double cost = (q - q_now).squaredNorm();
    if (cost < best) {
      best = cost;
      *q_best = q;
    }
  }
  return std::isfinite(best);
}

std::unique_ptr<Val2Emulator> MakeVal2Emulator(device::Side side,
                                               const std::array<double, 6>& q0_deg) {
  const std::string name(device::ToString(side));
  const robot::KinematicTree tree =
      robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  robot::ArmKinematics kinematics = robot::ArmKinematics::FromTree(tree, name);
  std::array<AxisLimits, 6> limits;
  device::Joint6 q0;
  for (int k = 0; k < 6; ++k) {
    const auto lim = tree.Limits(name + "_j" + std::to_string(k + 1));
    limits[k].min = lim.lower;
    limits[k].max = lim.upper;
    limits[k].max_speed = lim.velocity;
    // Ours (nothing published for the 260): full speed in 0.25 s.
    limits[k].max_accel = 4.0 * lim.velocity;
    q0[k] = DegToRad(q0_deg[k]);
  }
  const Pose3 X_WB = tree.LinkPose(name + "_base", {});
  return std::make_unique<Val2Emulator>(std::make_unique<TrapezoidArmModel>(limits, q0),
                                        std::move(kinematics), X_WB);
}

}  // namespace hgrasp::drivers
