// The grasp planner on hand-made box models whose faces are known exactly: contacts at the
// middles of opposite faces below the top, the hand aligned with them, reachable within the
// joint limits, clear of the table and other boxes, the most comfortable chosen.

#include "grasp/grasp_planner.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "common/paths.h"

namespace hgrasp::grasp {
namespace {

using Eigen::Vector3d;

const robot::KinematicTree& Tree() {
  static const robot::KinematicTree tree =
      robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  return tree;
}

struct Arms {
  robot::ArmKinematics left = robot::ArmKinematics::FromTree(Tree(), "left");
  robot::ArmKinematics right = robot::ArmKinematics::FromTree(Tree(), "right");
  std::array<const robot::ArmKinematics*, 2> both() const { return {&left, &right}; }
};

/// A box resting on the table: centre (x, y), yaw, full edges.
model::BoxModel Box(double x, double y, double yaw_deg, const Vector3d& size) {
  model::BoxModel b;
  b.X_WO.linear() = RotZ(DegToRad(yaw_deg));
  b.X_WO.translation() = Vector3d(x, y, size.z() / 2);
  b.size_O = size;
  for (int k = 0; k < 8; ++k) {
    b.vertices_W[k] =
        b.X_WO * Vector3d((k & 1 ? 0.5 : -0.5) * size.x(), (k & 2 ? 0.5 : -0.5) * size.y(),
                          (k & 4 ? 0.5 : -0.5) * size.z());
  }
  return b;
}

TEST(PlanGrasp, PaperGraspOfTheYellowBox) {
  const Arms arms;
  const std::vector<model::BoxModel> boxes = {Box(0.30, 0.06, 25, {0.06, 0.09, 0.12})};
  std::vector<GraspPlan> feasible;
  const std::optional<GraspPlan> plan = PlanGrasp(boxes, 0, arms.both(), {}, &feasible);
  ASSERT_TRUE(plan.has_value());
  // Only the 6 cm pair fits the hand (9 cm + 2 cm clearance > 10 cm): contacts on the faces
  // along O's x, at their middles, 1 cm below the top.
  const Vector3d ex = boxes[0].X_WO.linear().col(0);
  const Vector3d mid(0.30, 0.06, 0.11);
  const Vector3d a = mid - 0.03 * ex, b = mid + 0.03 * ex;
  const Vector3d nearer = a.head<2>().norm() < b.head<2>().norm() ? a : b;
  const Vector3d farther = nearer == a ? b : a;
  EXPECT_LT((plan->contacts_W[0] - nearer).norm(), 1e-12);  // the thumb nearer the robot
  EXPECT_LT((plan->contacts_W[1] - farther).norm(), 1e-12);
  EXPECT_NEAR(plan->opening_m, 0.08, 1e-12);
  // The contacts lie where the hand's fingers touch: (-+w/2, 0, 0.12) in E.
  const Pose3 X_EW = plan->X_WE.inverse();
  EXPECT_LT((X_EW * plan->contacts_W[0] - Vector3d(-0.03, 0, 0.12)).norm(), 1e-12);
  EXPECT_LT((X_EW * plan->contacts_W[1] - Vector3d(0.03, 0, 0.12)).norm(), 1e-12);
  // The palm above the top; the pre-grasp 8 cm back along the approach.
  EXPECT_GT((plan->X_WE * Vector3d(0, 0, 0.04)).z(), 0.12);
  EXPECT_NEAR((plan->X_WE_pre.translation() - plan->X_WE.translation()).norm(), 0.08, 1e-12);
  // Reachable: the joints give the poses and lie within the limits.
  const robot::ArmKinematics& arm = plan->side == device::Side::kLeft ? arms.left : arms.right;
  EXPECT_TRUE(arm.WithinLimits(plan->q));
  EXPECT_TRUE(arm.WithinLimits(plan->q_pre));
  EXPECT_LT((arm.Forward(plan->q).translation() - plan->X_WE.translation()).norm(), 1e-9);
  EXPECT_LT((arm.Forward(plan->q_pre).translation() - plan->X_WE_pre.translation()).norm(), 1e-9);
  // The via pose 10 cm above the pre-grasp, reachable too.
  EXPECT_NEAR(plan->X_WE_via.translation().z() - plan->X_WE_pre.translation().z(), 0.10, 1e-12);
  EXPECT_TRUE(arm.WithinLimits(plan->q_via));
  EXPECT_LT((arm.Forward(plan->q_via).translation() - plan->X_WE_via.translation()).norm(), 1e-9);
  // The most comfortable of all feasible candidates; both arms were considered.
  bool left = false, right = false;
  for (const GraspPlan& p : feasible) {
    EXPECT_GE(p.comfort_rad, plan->comfort_rad);
    left |= p.side == device::Side::kLeft;
    right |= p.side == device::Side::kRight;
  }
  EXPECT_TRUE(left && right) << feasible.size() << " feasible";
}

TEST(PlanGrasp, TooWideForTheHandIsNoPlan) {
  const Arms arms;
  const std::vector<model::BoxModel> boxes = {Box(0.30, 0.0, 10, {0.12, 0.13, 0.08})};
  EXPECT_FALSE(PlanGrasp(boxes, 0, arms.both()).has_value());
}

TEST(PlanGrasp, NeighbourInTheWayForcesTheOtherPair) {
  const Arms arms;
  // A 6 x 6 cm box: both pairs fit. Tall walls 1 cm from its +-x faces leave no room for the
  // fingers there: only the pair along y remains.
  std::vector<model::BoxModel> boxes = {Box(0.30, 0.0, 0, {0.06, 0.06, 0.08})};
  const std::optional<GraspPlan> free = PlanGrasp(boxes, 0, arms.both());
  ASSERT_TRUE(free.has_value());
  boxes.push_back(Box(0.30 - 0.03 - 0.01 - 0.01, 0.0, 0, {0.02, 0.2, 0.15}));
  boxes.push_back(Box(0.30 + 0.03 + 0.01 + 0.01, 0.0, 0, {0.02, 0.2, 0.15}));
  const std::optional<GraspPlan> plan = PlanGrasp(boxes, 0, arms.both());
  ASSERT_TRUE(plan.has_value());
  const Vector3d axis = (plan->contacts_W[1] - plan->contacts_W[0]).normalized();
  EXPECT_NEAR(std::abs(axis.y()), 1.0, 1e-9);
  for (const OrientedBox& part : HandBoxes(plan->X_WE, plan->opening_m, {})) {
    for (size_t i = 1; i < boxes.size(); ++i) {
      EXPECT_FALSE(
          Overlap(part, {boxes[i].X_WO.translation(), boxes[i].X_WO.linear(), boxes[i].size_O}));
    }
  }
}

// random_3002, reduced: the plan's forearm rested on a tall neighbour that the hand cleared (the
// planner checked the hand only), so the arm stopped 1.2 deg short at joint 2 and the servo
// could not converge. A tall box put under the forearm of the free plan must move the plan off it.
TEST(PlanGrasp, ArmLinksClearTheOtherBoxes) {
  const Arms arms;
  std::vector<model::BoxModel> boxes = {Box(0.30, 0.10, 20, {0.05, 0.04, 0.08})};
  const std::optional<GraspPlan> free = PlanGrasp(boxes, 0, arms.both());
  ASSERT_TRUE(free.has_value());
  const robot::ArmKinematics& arm = free->side == device::Side::kLeft ? arms.left : arms.right;
  const GraspConfig config;
  ASSERT_TRUE(ArmClear(arm, free->q_pre, boxes, config));
  // The forearm tube at the pre-grasp (the longest capsule beyond the elbow): a box standing under
  // its middle, its top 1 cm below the tube, clear of the hand at every pose of the plan.
  const std::vector<robot::Capsule> links = arm.LinkCapsules(free->q_pre);
  const robot::Capsule* forearm = nullptr;
  for (const robot::Capsule& c : links) {
    if (forearm == nullptr || (c.b - c.a).norm() > (forearm->b - forearm->a).norm()) forearm = &c;
  }
  ASSERT_NE(forearm, nullptr);
  const Vector3d under = 0.5 * (forearm->a + forearm->b);
  const double top = under.z() - forearm->radius - 0.005;
  ASSERT_GT(top, 0.05);
  boxes.push_back(Box(under.x(), under.y(), 0, {0.04, 0.04, top}));
  for (const Pose3* X : {&free->X_WE, &free->X_WE_pre, &free->X_WE_via}) {
    for (const OrientedBox& part : HandBoxes(*X, free->opening_m, {})) {
      ASSERT_FALSE(
          Overlap(part, {boxes[1].X_WO.translation(), boxes[1].X_WO.linear(), boxes[1].size_O}));
    }
  }
  EXPECT_FALSE(ArmClear(arm, free->q_pre, boxes, config));
  const std::optional<GraspPlan> plan = PlanGrasp(boxes, 0, arms.both());
  ASSERT_TRUE(plan.has_value());
  EXPECT_GT((plan->q_pre - free->q_pre).norm(), 1e-3);
  const robot::ArmKinematics& used = plan->side == device::Side::kLeft ? arms.left : arms.right;
  for (double s = 0; s <= 1.0; s += 0.1) {
    EXPECT_TRUE(ArmClear(used, plan->q_via + s * (plan->q_pre - plan->q_via), boxes, config));
    EXPECT_TRUE(ArmClear(used, plan->q_pre + s * (plan->q - plan->q_pre), boxes, config));
  }
}

TEST(PlanGrasp, OutOfReachIsNoPlan) {
  const Arms arms;
  const std::vector<model::BoxModel> boxes = {Box(0.95, 0.0, 0, {0.06, 0.06, 0.08})};
  EXPECT_FALSE(PlanGrasp(boxes, 0, arms.both()).has_value());
}

TEST(Overlap, SeparatingAxes) {
  const OrientedBox a{Vector3d::Zero(), Eigen::Matrix3d::Identity(), Vector3d(1, 1, 1)};
  OrientedBox b = a;
  b.centre = Vector3d(0.99, 0, 0);
  EXPECT_TRUE(Overlap(a, b));
  b.centre = Vector3d(1.01, 0, 0);
  EXPECT_FALSE(Overlap(a, b));
  // Rotated 45 deg about z: its corner reaches 0.707 out.
  b.R = RotZ(DegToRad(45));
  b.centre = Vector3d(1.2, 0, 0);
  EXPECT_TRUE(Overlap(a, b));
  b.centre = Vector3d(1.22, 0, 0);
  EXPECT_FALSE(Overlap(a, b));
}

TEST(SegmentBoxDistance, HandWorkedCases) {
  const OrientedBox unit{Vector3d::Zero(), Eigen::Matrix3d::Identity(), Vector3d(1, 1, 1)};
  // Beside a face, parallel to it: 2 - 0.5.
  EXPECT_NEAR(SegmentBoxDistance({2, -1, 0}, {2, 1, 0}, unit), 1.5, 1e-9);
  // Through the box: 0.
  EXPECT_EQ(SegmentBoxDistance({-2, 0.1, 0.2}, {2, 0.1, 0.2}, unit), 0.0);
  // Parallel to an edge at (1.5, 1.5): sqrt(2) from the edge (0.5, 0.5).
  EXPECT_NEAR(SegmentBoxDistance({1.5, 1.5, -1}, {1.5, 1.5, 1}, unit), std::sqrt(2.0), 1e-9);
  // Ending short of the box, pointing at it: from its end.
  EXPECT_NEAR(SegmentBoxDistance({3, 0, 0}, {0.8, 0, 0}, unit), 0.3, 1e-9);
  // Crossing past a corner: the segment x = y = t, z = 1 passes the corner (.5,.5,.5) at 0.5.
  EXPECT_NEAR(SegmentBoxDistance({-1, -1, 1}, {2, 2, 1}, unit), 0.5, 1e-9);
}

TEST(SegmentBoxDistance, AgreesWithDenseSampling) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    OrientedBox box{Vector3d(u(rng), u(rng), u(rng)) * 0.2,
                    Eigen::AngleAxisd(3.0 * u(rng), Vector3d(u(rng), u(rng), u(rng)).normalized())
                        .toRotationMatrix(),
                    Vector3d(0.3 + 0.2 * u(rng), 0.3 + 0.2 * u(rng), 0.3 + 0.2 * u(rng))};
    const Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    double brute = 1e9;
    for (int k = 0; k <= 20000; ++k) {
      const Vector3d p = a + (b - a) * (k / 20000.0);
      const Vector3d l = box.R.transpose() * (p - box.centre);
      brute = std::min(brute, (l.cwiseAbs() - 0.5 * box.size).cwiseMax(0.0).norm());
    }
    // Sampled every 1/20000 of at most 3.5: the brute force is high by at most 1e-4.
    const double d = SegmentBoxDistance(a, b, box);
    EXPECT_LE(d, brute + 1e-12) << trial;
    EXPECT_GE(d, brute - 1.0e-4) << trial;
  }
}

}  // namespace
}  // namespace hgrasp::grasp
