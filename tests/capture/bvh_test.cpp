// BVH reading and forward kinematics: inline files with hand-computed answers, every
// error naming file:line, mutated files never crashing, and the CMU clips shipped by
// Debian's assimp-testmodels when installed.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>

#include "capture/motion/bvh.h"
#include "capture/motion/motion_retarget.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;

namespace {

constexpr double kPi = std::numbers::pi;
const std::string kCmuDir = "/usr/share/assimp/models/BVH/";

// Root with 6 channels, one child joint with the CMU rotation order, an end site.
// Line numbers matter for the error tests below.
std::string small_bvh() {
  return "HIERARCHY\n"                                        // 1
         "ROOT Hips\n"                                        // 2
         "{\n"                                                // 3
         "\tOFFSET 0 0 0\n"                                   // 4
         "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"  // 5
         "\tJOINT Chest\n"                                    // 6
         "\t{\n"                                              // 7
         "\t\tOFFSET 0 2 0\n"                                 // 8
         "\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n"     // 9
         "\t\tEnd Site\n"                                     // 10
         "\t\t{\n"                                            // 11
         "\t\t\tOFFSET 1 0 0\n"                               // 12
         "\t\t}\n"                                            // 13
         "\t}\n"                                              // 14
         "}\n"                                                // 15
         "MOTION\n"                                           // 16
         "Frames: 2\n"                                        // 17
         "Frame Time: .0083333\n"                             // 18
         "1 2 3 0 0 0 0 0 0\n"                                // 19
         "1 2 3 90 0 0 0 0 90\n";                             // 20
}

Eigen::Vector3d position(const BvhTransforms& G, const BvhMotion& m, const std::string& name) {
  return G[m.joint_index(name)].translation();
}

TEST(Bvh, ParsesHierarchyChannelsAndFrames) {
  const BvhMotion m = parse_bvh(small_bvh(), "small.bvh");
  ASSERT_EQ(m.joints.size(), 3u);
  EXPECT_EQ(m.num_joints_without_end_sites(), 2);
  EXPECT_EQ(m.joints[0].name, "Hips");
  EXPECT_EQ(m.joints[1].name, "Chest");
  EXPECT_EQ(m.joints[2].name, "Chest_end");
  EXPECT_TRUE(m.joints[2].end_site);
  EXPECT_EQ(m.joints[1].parent, 0);
  EXPECT_EQ(m.joints[2].parent, 1);
  EXPECT_EQ(m.joints[1].offset, Eigen::Vector3d(0, 2, 0));
  EXPECT_EQ(m.joints[0].channels.size(), 6u);
  EXPECT_EQ(m.joints[1].first_channel, 6);
  EXPECT_EQ(m.joints[1].channels[0], BvhChannel::z_rotation);
  EXPECT_EQ(m.num_channels(), 9);
  EXPECT_EQ(m.num_frames(), 2);
  EXPECT_DOUBLE_EQ(m.frame_time_s, 0.0083333);
  EXPECT_DOUBLE_EQ(m.frames(1, 3), 90.0);
}

TEST(Bvh, ForwardKinematicsByHand) {
  const BvhMotion m = parse_bvh(small_bvh(), "small.bvh");
  // Frame 0: no rotation; root at its position channels.
  BvhTransforms G = bvh_global_transforms(m, 0);
  EXPECT_LT((position(G, m, "Hips") - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
  EXPECT_LT((position(G, m, "Chest") - Eigen::Vector3d(1, 4, 3)).norm(), 1e-12);
  EXPECT_LT((position(G, m, "Chest_end") - Eigen::Vector3d(2, 4, 3)).norm(), 1e-12);
  // Frame 1: root Zrotation 90 turns the chest offset (0,2,0) into (−2,0,0); the chest's
  // Yrotation 90 then turns the end site's (1,0,0) into (0,0,−1) in the chest frame,
  // which the root's Rz(90) leaves at (0,0,−1).
  G = bvh_global_transforms(m, 1);
  EXPECT_LT((position(G, m, "Chest") - Eigen::Vector3d(-1, 2, 3)).norm(), 1e-12);
  EXPECT_LT((position(G, m, "Chest_end") - Eigen::Vector3d(-1, 2, 2)).norm(), 1e-12);
}

TEST(Bvh, RotationsComposeInChannelOrder) {
  const double v[3] = {30, -50, 70};
  const auto Rx = [](double d) { return Eigen::AngleAxisd(d * kPi / 180, Eigen::Vector3d::UnitX()).toRotationMatrix(); };
  const auto Ry = [](double d) { return Eigen::AngleAxisd(d * kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix(); };
  const auto Rz = [](double d) { return Eigen::AngleAxisd(d * kPi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix(); };
  using C = BvhChannel;
  EXPECT_TRUE(bvh_rotation({C::z_rotation, C::x_rotation, C::y_rotation}, v).isApprox(Rz(30) * Rx(-50) * Ry(70), 1e-12));
  EXPECT_TRUE(bvh_rotation({C::z_rotation, C::y_rotation, C::x_rotation}, v).isApprox(Rz(30) * Ry(-50) * Rx(70), 1e-12));
  EXPECT_TRUE(bvh_rotation({C::y_rotation, C::x_rotation, C::z_rotation}, v).isApprox(Ry(30) * Rx(-50) * Rz(70), 1e-12));
  // Position channels do not rotate.
  const double w[4] = {5, 30, 6, 7};
  EXPECT_TRUE(bvh_rotation({C::x_position, C::x_rotation, C::y_position, C::z_position}, w).isApprox(Rx(30), 1e-12));
  // The orders differ: a test that mixed them up would notice.
  EXPECT_FALSE(Rz(30) * Rx(-50) * Ry(70) == Ry(70) * Rx(-50) * Rz(30));
}

TEST(Bvh, RoundTripsThroughWriter) {
  const BvhMotion m = parse_bvh(small_bvh(), "small.bvh");
  const BvhMotion r = parse_bvh(format_bvh(m), "written.bvh");
  ASSERT_EQ(r.joints.size(), m.joints.size());
  for (size_t j = 0; j < m.joints.size(); ++j) {
    EXPECT_EQ(r.joints[j].name, m.joints[j].name);
    EXPECT_EQ(r.joints[j].parent, m.joints[j].parent);
    EXPECT_EQ(r.joints[j].channels, m.joints[j].channels);
    EXPECT_EQ(r.joints[j].offset, m.joints[j].offset);
  }
  EXPECT_EQ(r.frames, m.frames);
  EXPECT_DOUBLE_EQ(r.frame_time_s, m.frame_time_s);
}

// Joints listed breadth first (A, B, C, D with D under B): the file is written depth
// first (A, B, D, C), and the frame columns must follow, or poses get scrambled.
TEST(Bvh, WriterOrdersFrameColumnsDepthFirst) {
  BvhMotion m;
  m.frame_time_s = 0.04;
  const std::vector<BvhChannel> rot = {BvhChannel::z_rotation, BvhChannel::x_rotation, BvhChannel::y_rotation};
  const char* names[] = {"A", "B", "C", "D"};
  const int parents[] = {-1, 0, 0, 1};
  for (int j = 0; j < 4; ++j) {
    BvhJoint b;
    b.name = names[j];
    b.parent = parents[j];
    b.offset = Eigen::Vector3d(j, 1, 0.5 * j);
    b.channels = rot;
    b.first_channel = 3 * j;
    m.joints.push_back(b);
  }
  m.frames = Eigen::MatrixXd::Random(3, 12) * 90;
  const BvhMotion r = parse_bvh(format_bvh(m), "order.bvh");
  EXPECT_EQ(r.joints[2].name, "D");
  for (int f = 0; f < 3; ++f) {
    const BvhTransforms G = bvh_global_transforms(m, f), H = bvh_global_transforms(r, f);
    for (const char* n : names) EXPECT_TRUE(G[m.joint_index(n)].isApprox(H[r.joint_index(n)], 1e-8)) << n;
  }
}

TEST(Bvh, InterpolatesWithSlerpBetweenFrames) {
  const BvhMotion m = parse_bvh(small_bvh(), "small.bvh");
  // At frame times: the frames themselves.
  for (int f = 0; f < 2; ++f) {
    const BvhTransforms a = bvh_global_transforms(m, f), b = bvh_global_transforms_at(m, f * m.frame_time_s);
    for (size_t j = 0; j < a.size(); ++j) EXPECT_TRUE(a[j].isApprox(b[j], 1e-9)) << j;
  }
  // Halfway: the root is turned 45° about z, so the chest sits at 45° from vertical.
  const BvhTransforms h = bvh_global_transforms_at(m, 0.5 * m.frame_time_s);
  const Eigen::Vector3d chest = position(h, m, "Chest") - position(h, m, "Hips");
  EXPECT_LT((chest - 2 * Eigen::Vector3d(-std::sqrt(0.5), std::sqrt(0.5), 0)).norm(), 1e-9);
  // Clamped outside the clip.
  EXPECT_TRUE(bvh_global_transforms_at(m, 10.0)[1].isApprox(bvh_global_transforms(m, 1)[1], 1e-12));
  EXPECT_TRUE(bvh_global_transforms_at(m, -1.0)[1].isApprox(bvh_global_transforms(m, 0)[1], 1e-12));
}

TEST(Bvh, ResampleTimesCoverTheClip) {
  EXPECT_EQ(resample_times(1.0, 30).size(), 31u);
  EXPECT_EQ(resample_times(0.99, 30).size(), 30u);
  EXPECT_EQ(resample_times(2751 * 0.0083333, 30).size(), 688u);  // 22.925 s of 01_01
  EXPECT_EQ(resample_times(0, 25).size(), 1u);
  expect_error([] { resample_times(1, 0); }, {"frame rate"});
}

TEST(Bvh, ErrorsNameFileAndLine) {
  const std::string ok = small_bvh();
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = ok;
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    s.replace(at, from.size(), to);
    return s;
  };
  // Truncated: the second frame line missing.
  expect_error([&] { parse_bvh(ok.substr(0, ok.rfind("1 2 3 90")), "/some/dir/cut.bvh"); },
               {"cut.bvh:19:", "unexpected end of file", "frame 2 of 2"});
  // Truncated inside the hierarchy.
  expect_error([&] { parse_bvh(ok.substr(0, ok.find("\t}\n}")), "cut.bvh"); }, {"cut.bvh:13:", "end of file"});
  // A frame line with a value missing.
  expect_error([&] { parse_bvh(replace("1 2 3 90 0 0 0 0 90", "1 2 3 90 0 0 0 0"), "x.bvh"); },
               {"x.bvh:20:", "frame 2", "expected 9 channel values, found 8"});
  // More frame lines than declared: counted and ignored (real exporters write them).
  const BvhMotion extra = parse_bvh(ok + "1 2 3 0 0 0 0 0 0\n", "x.bvh");
  EXPECT_EQ(extra.num_frames(), 2);
  EXPECT_EQ(extra.extra_frame_lines, 1);
  // Unknown keyword, unknown channel.
  expect_error([&] { parse_bvh(replace("\t\tOFFSET 0 2 0", "\t\tOFSET 0 2 0"), "x.bvh"); },
               {"x.bvh:8:", "unknown keyword 'OFSET'"});
  expect_error([&] { parse_bvh(replace("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrotation Wrotation"), "x.bvh"); },
               {"x.bvh:9:", "unknown channel 'Wrotation'"});
  // Non-finite numbers.
  expect_error([&] { parse_bvh(replace("1 2 3 90 0 0", "1 2 nan 90 0 0"), "x.bvh"); },
               {"x.bvh:20:", "finite number", "'nan'"});
  expect_error([&] { parse_bvh(replace("OFFSET 1 0 0", "OFFSET 1 inf 0"), "x.bvh"); }, {"x.bvh:12:", "finite"});
  // Missing braces.
  expect_error([&] { parse_bvh(replace("\t{\n\t\tOFFSET 0 2 0", "\t\tOFFSET 0 2 0"), "x.bvh"); },
               {"x.bvh:7:", "expected '{'", "'Chest'"});
  expect_error([&] { parse_bvh(replace("\t}\n}\nMOTION", "\t}\nMOTION"), "x.bvh"); },
               {"x.bvh:15:", "unknown keyword 'MOTION'", "'Hips'"});
  // Header errors.
  expect_error([&] { parse_bvh(replace("Frame Time: .0083333", "Frame Time: 0"), "x.bvh"); },
               {"x.bvh:18:", "frame time must be > 0"});
  expect_error([&] { parse_bvh(replace("Frames: 2", "Frames: two"), "x.bvh"); }, {"x.bvh:17:", "frame count"});
  expect_error([&] { parse_bvh(replace("HIERARCHY", "HIERARCH"), "x.bvh"); }, {"x.bvh:1:", "expected 'HIERARCHY'"});
  expect_error([&] { parse_bvh(replace("JOINT Chest", "JOINT Hips"), "x.bvh"); }, {"x.bvh:6:", "duplicate joint"});
  expect_error([&] { read_bvh("/nonexistent/none.bvh"); }, {"none.bvh", "cannot open"});
}

TEST(Bvh, MutatedFilesThrowWeftErrorsOnly) {
  const std::string valid = small_bvh();
  std::mt19937 rng(7);
  int errors = 0;
  for (int i = 0; i < 3000; ++i) {
    std::string s = valid;
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits && !s.empty(); ++e) {
      const size_t at = rng() % s.size();
      const char pool[] = "0123456789-.{} \n\tXYZrotationpsJOINTEndSite";
      switch (rng() % 4) {
        case 0: s[at] = pool[rng() % (sizeof(pool) - 1)]; break;
        case 1: s.erase(at, 1 + rng() % 10); break;
        case 2: s.resize(at); break;
        case 3: s.insert(at, s.substr(at, std::min<size_t>(1 + rng() % 30, s.size() - at))); break;
      }
    }
    try {
      const BvhMotion m = parse_bvh(s, "mutant.bvh");
      if (m.num_frames() > 0) bvh_global_transforms(m, m.num_frames() - 1);
    } catch (const weft::Error&) {
      ++errors;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "mutant " << i << " threw a non-weft exception: " << e.what();
    }
  }
  EXPECT_GT(errors, 1000);  // most mutants are broken files
}

// The weft Skeleton made from a BVH skeleton poses exactly like the BVH itself.
TEST(Bvh, SkeletonFromBvhMatchesBvhKinematics) {
  const BvhMotion m = parse_bvh(small_bvh(), "small.bvh");
  const Skeleton s = skeleton_from_bvh(m);
  EXPECT_EQ(s.num_dofs(), m.num_channels());
  for (int f = 0; f < m.num_frames(); ++f) {
    const BvhTransforms G = bvh_global_transforms(m, f);
    const Transforms H = forward_kinematics(s, bvh_frame_dofs(m, f));
    for (size_t j = 0; j < m.joints.size(); ++j) {
      const int k = s.joint_index(m.joints[j].name);
      ASSERT_GE(k, 0) << m.joints[j].name;
      EXPECT_TRUE(G[j].isApprox(H[k], 1e-12)) << m.joints[j].name << " frame " << f;
    }
  }
}

TEST(Bvh, CmuClips) {
  REQUIRE_DEBIAN_FILE(kCmuDir + "01_01.bvh", "assimp-testmodels");
  for (const auto& [file, frames] : {std::pair<std::string, int>{"01_01.bvh", 2752}, {"01_03.bvh", 4511}}) {
    const BvhMotion m = read_bvh(kCmuDir + file);
    EXPECT_EQ(m.num_joints_without_end_sites(), 31) << file;
    EXPECT_EQ(m.joints.size(), 31u + 7u) << file;  // end sites: toes, fingers, thumbs ×2, head
    EXPECT_EQ(m.num_frames(), frames) << file;
    EXPECT_EQ(m.extra_frame_lines, 0) << file;
    EXPECT_EQ(m.num_channels(), 6 + 30 * 3) << file;
    EXPECT_NEAR(1.0 / m.frame_time_s, 120.0, 0.01) << file;
    EXPECT_EQ(m.joints[0].name, "Hips");
    EXPECT_EQ(m.joints[0].channels[3], BvhChannel::z_rotation);  // CMU: Zrotation Yrotation Xrotation
    EXPECT_EQ(m.joints[0].channels[4], BvhChannel::y_rotation);
    // Every frame poses to finite transforms; the skeleton's FK agrees with the BVH's.
    const Skeleton s = skeleton_from_bvh(m);
    for (int f = 0; f < m.num_frames(); f += 97) {
      const BvhTransforms G = bvh_global_transforms(m, f);
      const Transforms H = forward_kinematics(s, bvh_frame_dofs(m, f));
      for (size_t j = 0; j < G.size(); ++j) {
        ASSERT_TRUE(G[j].matrix().allFinite());
        ASSERT_TRUE(G[j].isApprox(H[s.joint_index(m.joints[j].name)], 1e-9)) << m.joints[j].name;
      }
    }
  }
  // Another exporter: 21 joints in Zrotation Xrotation Yrotation order at 100 Hz.
  if (std::filesystem::exists(kCmuDir + "Boxing_Toes.bvh")) {
    const BvhMotion b = read_bvh(kCmuDir + "Boxing_Toes.bvh");
    EXPECT_EQ(b.num_joints_without_end_sites(), 21);
    EXPECT_EQ(b.num_frames(), 3069);
    EXPECT_EQ(b.extra_frame_lines, 1);
    EXPECT_DOUBLE_EQ(b.frame_time_s, 0.01);
    EXPECT_EQ(b.joints[0].channels[4], BvhChannel::x_rotation);
  }
}

}  // namespace
