#include "ekf_slam_core/mecp/mecp_update.h"

#include <cmath>

#include "ekf_slam_core/mecp/empty_convex_polygon.h"
#include "ekf_slam_core/mecp/mecp_observation.h"

namespace ekf_slam {

MecpUpdateResult updateWithMecp(EkfSlam* filter, const std::vector<PointObservation>& observations,
                                const std::vector<int>& landmark_ids,
                                const MecpUpdateOptions& options) {
  MecpUpdateResult result;
  if (landmark_ids.size() != observations.size()) return result;

  // The matched readings as points in the laser frame; the robot's origin
  // in that frame is the query.
  std::vector<Vector2> points;
  std::vector<int> reading_of_point;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (landmark_ids[i] < 0 || filter->slotOf(landmark_ids[i]) < 0) continue;
    const RangeBearing& z = observations[i].z;
    points.emplace_back(z.range * std::cos(z.bearing), z.range * std::sin(z.bearing));
    reading_of_point.push_back(static_cast<int>(i));
  }
  const Pose2& laser = filter->options().laser_pose;
  const Vector2 robot_in_laser = inverse(laser).translation();
  const std::vector<int> polygon = maximumEmptyConvexPolygon(points, robot_in_laser);
  if (polygon.size() < 3) return result;

  const int k = static_cast<int>(polygon.size());
  std::vector<RangeBearing> readings;
  std::vector<Matrix2> reading_covariances;
  std::vector<Vector2> members;
  std::vector<int> slots;
  for (int v : polygon) {
    const PointObservation& obs = observations[reading_of_point[v]];
    const int id = landmark_ids[reading_of_point[v]];
    readings.push_back(obs.z);
    reading_covariances.push_back(obs.covariance);
    result.member_ids.push_back(id);
    slots.push_back(filter->slotOf(id));
    members.push_back(filter->landmarkPosition(slots.back()));
  }
  RangeBearing observed, predicted;
  Matrix2 noise;
  Matrix23 J_z_pose;
  std::vector<Matrix2> J_z_members;
  if (!observeMecp(readings, reading_covariances, &observed, &noise) ||
      !predictMecpObservation(filter->pose(), laser, members, &predicted, &J_z_pose,
                              &J_z_members)) {
    result.outcome = MecpOutcome::kNoPolygon;
    return result;
  }

  // S from the filter's blocks, for the near-centre test before the update.
  Matrix2 S = J_z_pose * filter->poseCovariance() * J_z_pose.transpose() + noise;
  for (int i = 0; i < k; ++i) {
    const Matrix2 cross =
        J_z_pose * filter->poseLandmarkCovariance(slots[i]) * J_z_members[i].transpose();
    S += cross + cross.transpose();
    for (int j = 0; j < k; ++j) {
      const Matrix2 P_ij = i == j ? filter->landmarkCovariance(slots[i])
                                  : filter->landmarkCrossCovariance(slots[i], slots[j]);
      S += J_z_members[i] * P_ij * J_z_members[j].transpose();
    }
  }
  if (!(std::sqrt(S(1, 1)) <= options.max_bearing_sigma)) {
    result.outcome = MecpOutcome::kNearCentre;
    return result;
  }

  GenericObservation update;
  update.innovation =
      Vector2(observed.range - predicted.range, wrapAngle(observed.bearing - predicted.bearing));
  update.J_z_pose = J_z_pose;
  update.landmark_ids = result.member_ids;
  for (const Matrix2& J : J_z_members) update.J_z_landmarks.emplace_back(J);
  update.noise = noise;
  result.status = filter->updateGeneric(update, &result.nis);
  result.outcome =
      result.status == FilterStatus::kOk ? MecpOutcome::kApplied : MecpOutcome::kFilterRefused;
  return result;
}

}  // namespace ekf_slam
