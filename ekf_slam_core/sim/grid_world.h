// A world loaded from a map image, as the thesis loaded bitmaps into Stage:
// the map_server format (YAML with image, resolution, origin, negate,
// occupied_thresh, free_thresh; the image a binary or ASCII PGM). Cells whose
// occupancy exceeds occupied_thresh are walls; rays are traced cell by cell
// (Amanatides–Woo) so a ray never skips a one-cell wall.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/sim/ray_caster.h"

namespace ekf_slam {
namespace sim {

class GridWorld : public RayCaster {
 public:
  // Loads `yaml_path` and the image it names (relative to the YAML's folder).
  // Returns an empty string on success, else "<file>: <problem>".
  static std::string load(const std::string& yaml_path, GridWorld* out);

  // A world from a row-major occupancy mask, cell (0, 0) at `origin`.
  GridWorld(int width, int height, double resolution, const Vector2& origin,
            std::vector<bool> occupied);
  GridWorld() = default;

  double castRay(const Vector2& origin, double angle, double max_range) const override;

  bool occupied(int ix, int iy) const {
    return ix >= 0 && iy >= 0 && ix < width_ && iy < height_ &&
           occupied_[static_cast<size_t>(iy) * width_ + ix];
  }
  bool occupiedAt(const Vector2& p) const;
  // The `start_pose: [x, y, yaw]` key of the YAML (not part of map_server's
  // format; the shipped worlds give a free pose for the robot), if present.
  bool hasStartPose() const { return has_start_pose_; }
  Pose2 startPose() const { return start_pose_; }

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  Vector2 origin() const { return origin_; }

 private:
  int width_ = 0, height_ = 0;
  double resolution_ = 0.05;
  Vector2 origin_ = Vector2::Zero();
  std::vector<bool> occupied_;
  bool has_start_pose_ = false;
  Pose2 start_pose_;
};

}  // namespace sim
}  // namespace ekf_slam
