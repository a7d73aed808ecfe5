#include "ekf_slam_ros/calibration/laser_mount.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

namespace ekf_slam {
namespace calibration {
namespace {

const std::string kSource = EKF_SLAM_SOURCE_DIR;

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

const char* kValid =
    "parent_frame: base_link\nchild_frame: laser\nx: 0.16\ny: -0.02\nz: 0.3\nyaw: 3.14\n";

TEST(LaserMountTest, ShippedFileLoads) {
  LaserMount mount;
  ASSERT_EQ(loadLaserMount(kSource + "/config/calibration.yaml", &mount), "");
  EXPECT_EQ(mount.parent_frame, "base_link");
  EXPECT_EQ(mount.child_frame, "laser");
  // The nominal Pioneer laser mount: 16 cm ahead of the axle, centred.
  EXPECT_NEAR(mount.x, 0.16, 1e-9);
  EXPECT_NEAR(mount.y, 0.0, 1e-9);
  EXPECT_NEAR(mount.yaw, 0.0, 1e-9);
}

TEST(LaserMountTest, ShippedRearFileLoads) {
  LaserMount mount;
  ASSERT_EQ(loadLaserMount(kSource + "/config/calibration_rear.yaml", &mount), "");
  EXPECT_EQ(mount.parent_frame, "base_link");
  EXPECT_EQ(mount.child_frame, "laser_rear");
  // Behind the axle on the centre line, facing backwards, and inside the
  // P3-DX's body (its rear end is 0.273 m behind the axle).
  EXPECT_NEAR(mount.x, -0.251, 1e-9);
  EXPECT_GT(mount.x, -0.273);
  EXPECT_NEAR(mount.y, 0.0, 1e-9);
  EXPECT_NEAR(std::abs(mount.pose().theta), kPi, 1e-9);
}

TEST(LaserMountTest, ReadsEveryKey) {
  LaserMount mount;
  ASSERT_EQ(loadLaserMount(writeTemp("mount_valid.yaml", kValid), &mount), "");
  EXPECT_DOUBLE_EQ(mount.x, 0.16);
  EXPECT_DOUBLE_EQ(mount.y, -0.02);
  EXPECT_DOUBLE_EQ(mount.z, 0.3);
  EXPECT_DOUBLE_EQ(mount.yaw, 3.14);
  EXPECT_NEAR(mount.pose().theta, 3.14, 1e-12);
}

// Roll and pitch: 0 when absent (files from before the tilt was kept),
// read when given, bounded, and written back by saveLaserMount.
TEST(LaserMountTest, TheTiltIsOptionalBoundedAndSaved) {
  LaserMount mount;
  ASSERT_EQ(loadLaserMount(writeTemp("mount_level.yaml", kValid), &mount), "");
  EXPECT_EQ(mount.roll, 0.0);
  EXPECT_EQ(mount.pitch, 0.0);
  const std::string tilted = std::string(kValid) + "roll: 0.01\npitch: -0.0349\n";
  ASSERT_EQ(loadLaserMount(writeTemp("mount_tilted.yaml", tilted), &mount), "");
  EXPECT_DOUBLE_EQ(mount.roll, 0.01);
  EXPECT_DOUBLE_EQ(mount.pitch, -0.0349);
  const std::string saved = ::testing::TempDir() + "/mount_saved.yaml";
  ASSERT_EQ(saveLaserMount(saved, mount, "a tilted mount"), "");
  LaserMount back;
  ASSERT_EQ(loadLaserMount(saved, &back), "");
  EXPECT_DOUBLE_EQ(back.roll, 0.01);
  EXPECT_DOUBLE_EQ(back.pitch, -0.0349);
  const std::string steep = std::string(kValid) + "pitch: 2.0\n";
  EXPECT_NE(loadLaserMount(writeTemp("mount_steep.yaml", steep), &mount).find("pitch: must be in"),
            std::string::npos);
}

TEST(LaserMountTest, MissingFileNamesThePath) {
  LaserMount mount;
  const std::string error = loadLaserMount("/nonexistent/calibration.yaml", &mount);
  EXPECT_NE(error.find("/nonexistent/calibration.yaml"), std::string::npos) << error;
}

TEST(LaserMountTest, UnknownKeyIsRejectedByName) {
  LaserMount mount;
  mount.x = 42.0;
  const std::string error =
      loadLaserMount(writeTemp("mount_typo.yaml", std::string(kValid) + "yaw_deg: 5\n"), &mount);
  EXPECT_NE(error.find("yaw_deg"), std::string::npos) << error;
  EXPECT_DOUBLE_EQ(mount.x, 42.0) << "a rejected file must leave the output untouched";
}

TEST(LaserMountTest, MissingKeyAndBadValuesAreNamed) {
  LaserMount mount;
  std::string error = loadLaserMount(
      writeTemp("mount_missing.yaml", "parent_frame: base_link\nchild_frame: laser\nx: 0.1\n"),
      &mount);
  EXPECT_NE(error.find("y: missing"), std::string::npos) << error;
  EXPECT_NE(error.find("yaw: missing"), std::string::npos) << error;

  error = loadLaserMount(writeTemp("mount_mm.yaml",
                                   "parent_frame: base_link\nchild_frame: laser\nx: 160\n"
                                   "y: 0\nz: 0\nyaw: 0\n"),
                         &mount);
  EXPECT_NE(error.find("x: must be in"), std::string::npos) << error;

  error = loadLaserMount(writeTemp("mount_text.yaml",
                                   "parent_frame: base_link\nchild_frame: laser\nx: front\n"
                                   "y: 0\nz: 0\nyaw: 0\n"),
                         &mount);
  EXPECT_NE(error.find("x: must be a number"), std::string::npos) << error;

  error = loadLaserMount(writeTemp("mount_same.yaml",
                                   "parent_frame: laser\nchild_frame: laser\nx: 0\n"
                                   "y: 0\nz: 0\nyaw: 0\n"),
                         &mount);
  EXPECT_NE(error.find("child_frame"), std::string::npos) << error;
}

TEST(LaserMountTest, NotAMappingIsRejected) {
  LaserMount mount;
  EXPECT_NE(loadLaserMount(writeTemp("mount_list.yaml", "- 1\n- 2\n"), &mount), "");
  EXPECT_NE(loadLaserMount(writeTemp("mount_bad.yaml", "x: [1, \n"), &mount), "");
}

}  // namespace
}  // namespace calibration
}  // namespace ekf_slam
