#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "twinwatch/core/error.hpp"
#include "twinwatch/model/description_io.hpp"
#include "twinwatch/model/dynamics.hpp"
#include "error_text.hpp"

namespace twinwatch::model {
namespace {

using ::testing::HasSubstr;

// a minimal valid one-joint description; tests break one field at a time
std::string one_joint(const std::string& joint_fields) {
  return R"({"name": "t", "convention": "dh", "joints": [{"a": 0.1, "d": 0.2, "alpha": 0.0, )" + joint_fields + "}]}";
}
const std::string kGood = R"("mass": 1.0, "com": [0, 0, 0], "inertia": [0.01, 0, 0, 0.01, 0, 0.01])";

std::string error_of(const std::string& text) {
  return twinwatch::test::error_text<ParseError>([&] { parse_description_json(text, "robot.json"); });
}

TEST(DescriptionJson, ValidMinimalFileLoads) {
  const RobotDescription d = parse_description_json(one_joint(kGood), "robot.json");
  ASSERT_EQ(d.joints.size(), 1u);
  EXPECT_TRUE(std::isnan(d.joints[0].drive.gear_ratio)) << "unknown gear ratio must stay NaN";
}

TEST(DescriptionJson, SyntaxErrorNamesTheLine) {
  EXPECT_THAT(error_of("{\n\"name\": \"t\",\n\"joints\": [,]\n}"), HasSubstr("robot.json:3"));
}

TEST(DescriptionJson, MissingFieldIsNamed) {
  EXPECT_THAT(error_of(one_joint(R"("com": [0,0,0], "inertia": [0.01,0,0,0.01,0,0.01])")),
              HasSubstr("field 'joints[0].mass': missing required field"));
}

TEST(DescriptionJson, WrongTypeSaysExpectedAndActual) {
  EXPECT_THAT(error_of(one_joint(R"("mass": "heavy", "com": [0,0,0], "inertia": [0.01,0,0,0.01,0,0.01])")),
              HasSubstr("joints[0].mass': expected a number, got string"));
}

TEST(DescriptionJson, UnknownKeyIsRejected) {
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "masss": 2.0)")), HasSubstr("unknown key 'masss'"));
}

TEST(DescriptionJson, NegativeMassIsRejected) {
  EXPECT_THAT(error_of(one_joint(R"("mass": -1.0, "com": [0,0,0], "inertia": [0.01,0,0,0.01,0,0.01])")),
              HasSubstr("mass of link is -1, must be >= 0"));
}

// the rated payload (session 21): what --payload-mass, --known-payload and scenarios are checked
// against; without it, the arm's own moving mass
TEST(DescriptionJson, TheRatedPayloadIsTheLimitOfADeclaredPayload) {
  const std::string with = R"({"name": "t", "convention": "dh", "rated_payload": 2.5, "joints": [{"a": 0.1, "d": 0.2, "alpha": 0.0, )" +
                           kGood + "}]}";
  const RobotModel rated(parse_description_json(with, "robot.json"));
  EXPECT_EQ(rated.payload_limit(), 2.5);
  EXPECT_EQ(rated.payload_limit_text(), "the rated payload of t");
  const RobotModel unrated(parse_description_json(one_joint(kGood), "robot.json"));
  EXPECT_EQ(unrated.payload_limit(), 1.0);  // its one link's mass
  EXPECT_THAT(unrated.payload_limit_text(), HasSubstr("the moving mass of t: its description gives no rated payload"));
  EXPECT_EQ(load_robot("ur3e").payload_limit(), 3.0);
  EXPECT_EQ(load_robot("ur5e").payload_limit(), 5.0);
  EXPECT_EQ(load_robot("ur10e").payload_limit(), 12.5);
  EXPECT_EQ(load_robot("panda").payload_limit(), 3.0);
  std::string bad = with;
  bad.replace(bad.find("2.5"), 3, "-1");
  EXPECT_THAT(error_of(bad), HasSubstr("robot.json: field 'rated_payload': expected a mass > 0 kg, got -1"));
  bad = with;
  bad.replace(bad.find("2.5"), 3, "\"3 kg\"");
  EXPECT_THAT(error_of(bad), HasSubstr("field 'rated_payload': expected a number, got string"));
}

// where the elbow's housing lies along the elbow's axis (session 46): the elbow speed's two ends;
// none given, the kinematic chain's point; a length in mm is refused
TEST(DescriptionJson, TheElbowHousingIsReadInMetresAlongTheElbowsAxis) {
  const std::string with = R"({"name": "t", "convention": "dh", "elbow_housing": [0.02, 0.1], "joints": [{"a": 0.1, "d": 0.2, "alpha": 0.0, )" +
                           kGood + "}]}";
  EXPECT_EQ(RobotModel(parse_description_json(with, "robot.json")).description().elbow_housing, Eigen::Vector2d(0.02, 0.1));
  EXPECT_EQ(RobotModel(parse_description_json(one_joint(kGood), "robot.json")).description().elbow_housing, Eigen::Vector2d::Zero());
  EXPECT_EQ(load_robot("ur5e").description().elbow_housing, Eigen::Vector2d(0.007, 0.138));
  EXPECT_EQ(load_robot("ur10e").description().elbow_housing, Eigen::Vector2d(0.0393, 0.1762));
  std::string bad = with;
  bad.replace(bad.find("[0.02, 0.1]"), 11, "[27, 120]");
  EXPECT_THAT(error_of(bad), HasSubstr("robot.json: field 'elbow_housing': expected two distances along the elbow's axis within ±1 m, "
                                       "got [27, 120] (in mm? give metres)"));
  bad = with;
  bad.replace(bad.find("[0.02, 0.1]"), 11, "[0.1]");
  EXPECT_THAT(error_of(bad), HasSubstr("field 'elbow_housing': expected 2 numbers, got 1"));
}

TEST(DescriptionJson, NonPositiveDefiniteInertiaIsRejected) {
  EXPECT_THAT(error_of(one_joint(R"("mass": 1.0, "com": [0,0,0], "inertia": [0.01,0,0,-0.01,0,0.01])")),
              HasSubstr("not positive semi-definite"));
}

TEST(DescriptionJson, TriangleInequalityIsChecked) {
  EXPECT_THAT(error_of(one_joint(R"("mass": 1.0, "com": [0,0,0], "inertia": [0.01,0,0,0.01,0,0.05])")),
              HasSubstr("triangle inequality"));
}

TEST(DescriptionJson, AccelerationLimitMustBePositive) {
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "limits": {"qdd_max": 0})")),
              HasSubstr("joints[0].limits.qdd_max': must be > 0, got 0"));
}

// the drive's fields are named with their path (the model's check named "joint 2 ('elbow')" counted
// from 0, for the third joint; audit, session 37)
TEST(DescriptionJson, DriveFieldsAreCheckedWithTheirPath) {
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "drive": {"current_limit": 0})")),
              HasSubstr("field 'joints[0].drive.current_limit': must be > 0 A (or null if none), got 0"));
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "drive": {"efficiency": 1.5})")),
              HasSubstr("field 'joints[0].drive.efficiency': expected a factor in (0, 1], got 1.5"));
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "drive": {"efficiency": 0.9, "efficiency_reverse": 0})")),
              HasSubstr("field 'joints[0].drive.efficiency_reverse': expected a factor in (0, 1], got 0"));
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "drive": {"gear_ratio": -101})")),
              HasSubstr("field 'joints[0].drive.gear_ratio': must be > 0 (or null if unknown), got -101"));
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "drive": {"torque_constant": 0})")),
              HasSubstr("field 'joints[0].drive.torque_constant': must be > 0 (or null if unknown), got 0"));
  // and a description built in code is checked with its joints numbered from 1
  RobotDescription d = parse_description_json(one_joint(kGood), "robot.json");
  d.joints[0].drive.current_limit = 0.0;
  EXPECT_THAT(twinwatch::test::error_text<twinwatch::InvalidArgument>([&] { RobotModel m(d); }),
              HasSubstr("current limit of joint 1 ('joint1') is 0"));
}

// unit slips the kinematics and the simulator took silently (d 151.85 "m" put the flange 152 m up)
TEST(DescriptionJson, UnitSlipsAreRefusedWithTheUnitToGive) {
  EXPECT_THAT(error_of(R"({"name": "t", "convention": "dh", "joints": [{"a": 0.1, "d": 151.85, "alpha": 0.0, )" + kGood + "}]}"),
              HasSubstr("joints[0].d': expected a length within ±5 m, got 151.85 (in mm? give metres)"));
  EXPECT_THAT(error_of(R"({"name": "t", "convention": "dh", "joints": [{"a": 0.1, "d": 0.1, "alpha": 90, )" + kGood + "}]}"),
              HasSubstr("joints[0].alpha': expected an angle within ±6.283 rad (2π), got 90 (in degrees? give radians)"));
  EXPECT_THAT(error_of(one_joint(R"("mass": 1.0, "com": [0, -20, 0], "inertia": [0.01, 0, 0, 0.01, 0, 0.01])")),
              HasSubstr("joints[0].com': expected a centre of mass within 5 m of the joint, got one 20 m away (in mm? give metres)"));
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "limits": {"qd_max": 180})")),
              HasSubstr("joints[0].limits.qd_max': expected at most 50 rad/s, got 180 (in degrees/s? give rad/s)"));
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "limits": {"q_min": -360, "q_max": 360})")),
              HasSubstr("joints[0].limits.q_min': expected a position within ±31.42 rad (five turns), got -360 (in degrees?"));
  EXPECT_THAT(error_of(R"({"name": "t", "convention": "dh", "gravity": [0, 0, -981], "joints": [{"a": 0.1, "d": 0.2, "alpha": 0.0, )" + kGood + "}]}"),
              HasSubstr("field 'gravity': expected a vector of 9.7 to 9.9 m/s² (or 0), got one of 981 m/s² (in cm/s²? give m/s²)"));
  EXPECT_THAT(error_of(R"({"name": "t", "convention": "dh", "rated_payload": 1000, "joints": [{"a": 0.1, "d": 0.2, "alpha": 0.0, )" + kGood + "}]}"),
              HasSubstr("field 'rated_payload': expected at most 10 times the arm's moving mass (1 kg), got 1000 kg (in grams? give kg)"));
  // a robot on a ceiling: gravity along +z is a direction, not a slip
  EXPECT_NO_THROW(parse_description_json(
      R"({"name": "t", "convention": "dh", "gravity": [0, 0, 9.81], "joints": [{"a": 0.1, "d": 0.2, "alpha": 0.0, )" + kGood + "}]}", "robot.json"));
}

// a key given twice: the JSON reader kept one of the values without a word
TEST(DescriptionJson, AKeyGivenTwiceIsRefused) {
  EXPECT_THAT(error_of(R"({"name": "t", "convention": "dh", "joints": [{"a": 0.1, "d": 0.2, "alpha": 0.0, "alpha": 1.5, )" + kGood + "}]}"),
              HasSubstr("joints[0].alpha': the key appears twice in its object"));
}

TEST(DescriptionJson, AccelerationLimitIsOptionalAndLoads) {
  const RobotModel panda = load_robot("panda");
  EXPECT_DOUBLE_EQ(panda.joint(1).limits.qdd_max, 7.5);  // Franka specifications
  EXPECT_FALSE(std::isfinite(load_robot("ur3e").joint(0).limits.qdd_max));  // UR publishes none
}

TEST(DescriptionJson, WrongVectorLengthIsNamed) {
  EXPECT_THAT(error_of(one_joint(R"("mass": 1.0, "com": [0,0], "inertia": [0.01,0,0,0.01,0,0.01])")),
              HasSubstr("joints[0].com': expected 3 numbers, got 2"));
}

TEST(DescriptionJson, PositionLimitsMustBeOrdered) {
  EXPECT_THAT(error_of(one_joint(kGood + R"(, "limits": {"q_min": 1.0, "q_max": -1.0})")),
              HasSubstr("q_min (1) must be < q_max (-1)"));
}

TEST(DescriptionJson, UnknownConventionIsRejected) {
  EXPECT_THAT(error_of(R"({"name": "t", "convention": "dh2", "joints": []})"), HasSubstr("expected \"dh\""));
}

TEST(LoadRobot, UnknownNameListsTheBuiltins) {
  try {
    load_robot("ur99");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("robot 'ur99' is unknown"));
    EXPECT_THAT(e.what(), HasSubstr("ur3e"));
  }
}

TEST(LoadRobot, MissingFileIsNamed) {
  try {
    load_robot("/nonexistent/robot.json");
    FAIL();
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent/robot.json: cannot open"));
  }
}

TEST(Ur3e, MovingMassesSumToTheDatasheet) {
  const RobotModel m = load_robot("ur3e");
  double total = 0.0;
  for (int i = 0; i < m.n_dof(); ++i) total += m.joint(i).body.mass;
  EXPECT_NEAR(total, 8.7985, 1e-12);
}

// the flange at the zero pose from the DH product computed independently here
TEST(Ur3e, ZeroPoseFlangeMatchesDhProduct) {
  const RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  const double a[] = {0, -0.24355, -0.2132, 0, 0, 0}, dd[] = {0.15185, 0, 0, 0.13105, 0.08535, 0.0921},
               al[] = {M_PI / 2, 0, 0, M_PI / 2, -M_PI / 2, 0};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int trial = 0; trial < 50; ++trial) {
    VectorJ q(6);
    for (int i = 0; i < 6; ++i) q[i] = trial == 0 ? 0.0 : u(rng);
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    for (int i = 0; i < 6; ++i) {
      const double ct = std::cos(q[i]), st = std::sin(q[i]), ca = std::cos(al[i]), sa = std::sin(al[i]);
      Eigen::Matrix4d A;
      A << ct, -st * ca, st * sa, a[i] * ct, st, ct * ca, -ct * sa, a[i] * st, 0, sa, ca, dd[i], 0, 0, 0, 1;
      T = T * A;
    }
    EXPECT_LT((forward_kinematics(m, d, q).matrix() - T).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
  }
}

// arm stretched horizontally (shoulder at -pi/2... here q = 0 has upper arm and forearm along -x):
// shoulder gravity torque = -g * sum over links 2..6 of m_i * x_i, computed by hand from the DH data
TEST(Ur3e, HorizontalArmGravityTorqueMatchesHandComputation) {
  const RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  const VectorJ g = gravity_torque(m, d, VectorJ::Zero(6));
  // x of each COM at q = 0 (links 4-6 COMs lie on the wrist axis line x = a2 + a3 in the horizontal plane)
  const double x2 = -0.24355 + 0.13, x3 = -0.24355 - 0.2132 + 0.05, xw = -0.24355 - 0.2132;
  const double expected = 9.81 * (3.4445 * x2 + 1.437 * x3 + (0.871 + 0.805 + 0.261) * xw);
  EXPECT_NEAR(g[1], expected, 1e-9);
  EXPECT_NEAR(g[0], 0.0, 1e-12);
}

// The URDF fixture is written from the same numbers in URDF link frames (UR ROS 2 description
// layout); both loaders must give the same kinematics and dynamics.
TEST(DescriptionUrdf, Ur3eMatchesJsonDescription) {
  const RobotModel js = load_robot("ur3e");
  const RobotModel ur = load_robot(std::string(TWINWATCH_SOURCE_DIR) + "/tests/data/model/ur3e.urdf");
  ASSERT_EQ(ur.n_dof(), 6);
  DynamicsData dj(js), du(ur);
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int trial = 0; trial < 200; ++trial) {
    VectorJ q(6), qd(6), qdd(6);
    for (int i = 0; i < 6; ++i) q[i] = u(rng), qd[i] = u(rng), qdd[i] = u(rng);
    const Eigen::Vector3d pj = forward_kinematics(js, dj, q).translation();
    const Eigen::Vector3d pu = forward_kinematics(ur, du, q).translation();
    EXPECT_LT((pj - pu).norm(), 1e-9) << "seed 42 trial " << trial;
    const VectorJ tj = rnea(js, dj, q, qd, qdd);
    const VectorJ tu = rnea(ur, du, q, qd, qdd);
    EXPECT_LT((tj - tu).cwiseAbs().maxCoeff(), 1e-9) << "seed 42 trial " << trial;
  }
}

TEST(DescriptionUrdf, MalformedXmlNamesTheFile) {
  const std::string path = ::testing::TempDir() + "description_test_bad.urdf";
  std::ofstream(path) << "<robot name='x'><link name='a'></robot";
  try {
    load_description_urdf(path);
    FAIL();
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad.urdf"));
    EXPECT_THAT(e.what(), HasSubstr("not a valid URDF"));
  }
  // a file that is no XML at all is said as such, not as urdfdom's "Error document empty"
  std::ofstream(path) << "name,value\nmass,3\n";
  EXPECT_THAT(twinwatch::test::error_text<ParseError>([&] { load_description_urdf(path); }),
              HasSubstr("description_test_bad.urdf: not a URDF: no <robot> element"));
}

TEST(DescriptionUrdf, BranchingTreeNeedsATip) {
  const std::string path = ::testing::TempDir() + "description_test_branch.urdf";
  std::ofstream(path) << R"(<robot name="b"><link name="base"/><link name="l1"/><link name="l2"/>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="j2" type="revolute"><parent link="base"/><child link="l2"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)";
  try {
    load_description_urdf(path);
    FAIL();
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("the tree has 2 leaves below 1 revolute joints (l1, l2), expected one: name the tip link "
                                    "after the file, e.g. --robot "));
    EXPECT_THAT(e.what(), HasSubstr("branch.urdf#l1"));
  }
  // named: the chain to that leaf
  EXPECT_EQ(load_robot(path + "#l2").description().joints.front().name, "j2");
}

// A joint whose child is its own parent: urdfdom takes it, and the loader's walk up the tree from
// a leaf went round for ever (a fuzzing finding, session 57). It is refused, naming that joint and
// its line; the same file with the joint's child fixed loads.
TEST(DescriptionUrdf, AJointWhoseChildIsItsParentIsRefusedNotWalkedForEver) {
  const std::string path = ::testing::TempDir() + "description_test_loop.urdf";
  const auto write = [&](const char* parent) {
    std::ofstream(path) << fmt::format(R"(<robot name="loop"><link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="j2" type="revolute"><parent link="{}"/><child link="l2"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    </robot>)", parent);
  };
  write("l2");
  try {
    load_description_urdf(path);
    FAIL() << "a joint from l2 to l2 loaded";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("description_test_loop.urdf:3: field 'joint': joint 'j2' (parent 'l2', child 'l2') closes a "
                                    "loop: its child is its own parent"));
  }
  write("l1");
  EXPECT_EQ(load_description_urdf(path).joints.size(), 3u);
  // two links that are each other's parent, beside the arm (l4 <-> l5)
  std::ofstream(path) << R"(<robot name="loop2"><link name="base"/><link name="l1"/><link name="l4"/><link name="l5"/>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="j4" type="fixed"><parent link="l5"/><child link="l4"/></joint>
    <joint name="j5" type="fixed"><parent link="l4"/><child link="l5"/></joint></robot>)";
  try {
    load_description_urdf(path);
    FAIL() << "a loop l4 <-> l5 loaded";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("closes a loop: the links above its child lead back to it"));
  }
}

// A link that two joints name as their child: urdfdom keeps one joint and drops the other without a
// word (base->l1 and l2->l1 loaded as three joints of four; review of session 57). Refused, naming
// both joints.
TEST(DescriptionUrdf, ALinkWithTwoParentJointsIsRefused) {
  const std::string path = ::testing::TempDir() + "description_test_two_parents.urdf";
  std::ofstream(path) << R"(<robot name="two"><link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/>
    <joint name="j0" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l2"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="j2" type="revolute"><parent link="l2"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="j3" type="revolute"><parent link="l1"/><child link="l3"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)";
  try {
    load_description_urdf(path);
    FAIL() << "a link with two parent joints loaded";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("description_test_two_parents.urdf:4: field 'joint': link 'l1' is the child of two joints, 'j0' and "
                                    "'j2', expected a tree"));
  }
}

// A description with frames beside the arm (ur_description's massless 'base' and 'tool0', a
// sensor frame) has several leaves but one chain with the most revolute joints: that one is taken.
TEST(DescriptionUrdf, FramesBesideTheChainDoNotHideTheArm) {
  const std::string path = ::testing::TempDir() + "description_test_frames.urdf";
  std::ofstream(path) << R"(<robot name="f"><link name="base_link"/><link name="base"/><link name="l1"/><link name="l2"/><link name="tool0"/><link name="cam"/>
    <joint name="base_fixed" type="fixed"><parent link="base_link"/><child link="base"/></joint>
    <joint name="j1" type="revolute"><parent link="base_link"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="cam_fixed" type="fixed"><parent link="l1"/><child link="cam"/></joint>
    <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    <joint name="tool_fixed" type="fixed"><parent link="l2"/><child link="tool0"/></joint></robot>)";
  const RobotDescription d = load_description_urdf(path);
  ASSERT_EQ(d.joints.size(), 2u);
  EXPECT_EQ(d.joints[0].name, "j1");
  EXPECT_EQ(d.joints[1].name, "j2");
}

// urdfdom logs a mass that is not a number and drops the link's whole <inertial> block: the arm
// loaded with a massless link. The loader refuses the file, naming the line and the value.
TEST(DescriptionUrdf, AMassThatIsNotANumberIsRefusedNotZero) {
  const std::string path = ::testing::TempDir() + "description_test_mass.urdf";
  std::ofstream(path) << R"(<robot name="m"><link name="base"/>
    <link name="l1"><inertial><origin xyz="0 0 0.1"/>
      <mass value="abc"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)";
  try {
    load_description_urdf(path);
    FAIL() << "a link with mass 'abc' loaded";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("description_test_mass.urdf:3: not a valid URDF"));
    EXPECT_THAT(e.what(), HasSubstr("mass [abc] is not a float"));
  }
  // the same file with a number loads that mass
  std::ofstream(path) << R"(<robot name="m"><link name="base"/>
    <link name="l1"><inertial><origin xyz="0 0 0.1"/>
      <mass value="1.25"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)";
  EXPECT_DOUBLE_EQ(load_description_urdf(path).joints.at(0).body.mass, 1.25);
}

// unit slips the JSON reader refuses are refused in a URDF too, with the joint's line: an origin in
// mm, a negative limit (velocity="-1" left the joint without a speed limit; audit of session 56)
TEST(DescriptionUrdf, AnOriginInMillimetresOrANegativeLimitIsRefused) {
  const std::string path = ::testing::TempDir() + "description_test_units.urdf";
  const auto urdf = [&](const std::string& origin, const std::string& limit) {
    std::ofstream(path) << R"(<robot name="u"><link name="base"/>
    <link name="l1"><inertial><origin xyz="0 0 0.1"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
    <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz=")" + origin +
                               R"("/><axis xyz="0 0 1"/><limit lower="-1" upper="1" )" + limit + R"(/></joint></robot>)";
    return twinwatch::test::error_text<ParseError>([&] { load_description_urdf(path); });
  };
  EXPECT_EQ(urdf("0 0 0.15", R"(effort="10" velocity="2")"), "no error");
  EXPECT_THAT(urdf("0 0 152", R"(effort="10" velocity="2")"),
              HasSubstr("description_test_units.urdf:3: field 'joint 'j1'.origin': expected an offset within 5 m, got one of 152 m (in mm? give metres)"));
  EXPECT_THAT(urdf("0 0 0.15", R"(effort="10" velocity="-1")"),
              HasSubstr("description_test_units.urdf:3: field 'joint 'j1'.limit.velocity': expected a limit >= 0 (0: not published), got -1"));
  EXPECT_THAT(urdf("0 0 0.15", R"(effort="-10" velocity="2")"), HasSubstr("field 'joint 'j1'.limit.effort'"));
}

// Masses in grams pass every per-number bound but make an arm that cannot lift itself; the UR3e
// with its link masses in grams was simulated with J2 at its limit, collapsed, exit 0 (audit of
// session 56). The shipped arms hold themselves
TEST(Description, AnArmThatCannotHoldItsOwnWeightIsRefused) {
  for (const char* name : {"ur3e", "ur5e", "ur10e", "panda"}) EXPECT_NO_THROW(load_robot(name)) << name;
  EXPECT_NO_THROW(load_robot(std::string(TWINWATCH_SOURCE_DIR) + "/data/robots/kinova_gen3.urdf"));
  RobotDescription grams = load_robot("ur3e").description();
  for (Joint& j : grams.joints) j.body.mass *= 1000.0;
  const std::string error = twinwatch::test::error_text<ParseError>([&] { check_holds_itself(grams, "grams.json"); });
  EXPECT_THAT(error, ::testing::MatchesRegex("grams\\.json: field 'joints\\[[12]\\]': the arm cannot hold its own weight: J[23] \\([a-z_]+\\) "
                                             "needs [0-9.e+]+ N·m against gravity at q = \\[[-0-9., ]+\\], more than 5 times its torque limit "
                                             "(54|28) N·m; its links weigh [0-9.]+ kg in all \\(masses in grams\\? give kg\\)"));
  // twice the masses: a heavier arm, still one that holds itself
  RobotDescription heavy = load_robot("ur3e").description();
  for (Joint& j : heavy.joints) j.body.mass *= 2.0;
  EXPECT_NO_THROW(check_holds_itself(heavy, "heavy.json"));
}

// a directory named like a description was read as an empty document ("not valid JSON: unexpected
// end of input"): the wrong cause
TEST(LoadRobot, ADirectoryNamedLikeADescriptionIsSaidToBeOne) {
  for (const std::string name : {"description_test_dir.json", "description_test_dir.urdf"}) {
    const std::string path = ::testing::TempDir() + name;
    std::filesystem::create_directories(path);
    try {
      load_robot(path);
      FAIL() << name;
    } catch (const ParseError& e) {
      EXPECT_THAT(e.what(), HasSubstr(name + ": cannot read: it is a directory, not a file"));
    }
  }
}

TEST(Payload, ChangesGravityTorqueByJTransposeMg) {
  RobotModel m = load_robot("ur3e");
  DynamicsData d(m);
  VectorJ q(6);
  q << 0.3, -1.0, 1.2, -1.7, -1.5, 0.4;
  const VectorJ g0 = gravity_torque(m, d, q);
  RigidBodyInertia payload;
  payload.mass = 0.5;
  payload.com = Eigen::Vector3d(0.0, 0.0, 0.05);
  m.set_payload(payload);
  const VectorJ g1 = gravity_torque(m, d, q);
  // J^T of the payload COM times its weight
  forward_kinematics(m, d, q);
  Matrix6J J;
  const Eigen::Vector3d p_link = m.description().flange * payload.com;
  point_jacobian(m, d, 5, p_link, J);
  const VectorJ expected = -J.topRows<3>().transpose() * (0.5 * m.gravity());
  EXPECT_LT((g1 - g0 - expected).cwiseAbs().maxCoeff(), 1e-12);
  m.clear_payload();
  EXPECT_LT((gravity_torque(m, d, q) - g0).cwiseAbs().maxCoeff(), 1e-14);
}

// found by fuzzing (fuzz/regressions/description_json): json's out_of_range escaped
TEST(DescriptionJson, NumberBeyondADoubleIsAParseError) {
  EXPECT_THAT(error_of(one_joint(R"("mass": 1e400, "com": [0, 0, 0], "inertia": [0.01, 0, 0, 0.01, 0, 0.01])")),
              HasSubstr("robot.json: expected numbers within the range of a double"));
}

// found by fuzzing a scenario's robot name: std::filesystem threw "File name too long"
TEST(LoadRobot, OverlongNameIsAnUnknownRobot) {
  EXPECT_THROW(load_robot(std::string(300, 'a')), InvalidArgument);
}

// found by fuzzing (fuzz/regressions/description_urdf): a file ending in a truncated UTF-8
// sequence made TinyXML (under urdfdom) read past its buffer
TEST(DescriptionUrdf, InvalidUtf8NamesTheLine) {
  const std::string path = ::testing::TempDir() + "description_test_utf8.urdf";
  std::ofstream(path, std::ios::binary) << "<robot name=\"r\">\n  <link name=\"a\"/>\n</robot>\xf4";
  try {
    load_description_urdf(path);
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("description_test_utf8.urdf:3: not valid UTF-8 text"));
  }
}

}  // namespace
}  // namespace twinwatch::model
