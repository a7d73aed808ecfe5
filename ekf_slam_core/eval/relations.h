// The relation-based accuracy metric of Kümmerle et al. 2009 ("On measuring
// the accuracy of SLAM algorithms"), as described in
// ../shared/datasets/README.md, and the relations file format.
//
// A relation (t1, t2, δ) is the ground-truth motion from the pose at scan
// time t1 to the pose at t2, in the frame of the first. For an estimated
// trajectory the error is e = δ⁻¹ ⊕ (x(t1)⁻¹ ⊕ x(t2)); the translational
// error is |e_t| (m), the rotational error |e_θ| (rad).
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/geometry/stamped_pose.h"
#include "ekf_slam_core/io/trajectory_file.h"

namespace ekf_slam {

struct Relation {
  double t1 = 0.0, t2 = 0.0;  // s
  Pose2 motion;               // x(t1)⁻¹ ⊕ x(t2), ground truth
};

// Reads "t1 t2 x y z roll pitch yaw" lines (# comments and blank lines
// skipped). Returns an empty string on success, else "<path>:<line>:
// <problem>". Trajectories: io/trajectory_file.h.
std::string readRelations(const std::string& path, std::vector<Relation>* out);

struct ErrorStats {
  double mean = 0.0, stddev = 0.0;
};

struct RelationErrors {
  int relations = 0;                       // in the file
  int used = 0;                            // both poses found
  ErrorStats translation;                  // m
  ErrorStats rotation;                     // rad
  ErrorStats translation_squared;          // m²
  ErrorStats rotation_squared;             // rad²
  std::vector<double> translation_errors;  // per used relation
  std::vector<double> rotation_errors;
  std::vector<double> spans;  // s, |t2 − t1| per used relation
};

// Poses are looked up by stamp within `stamp_tolerance` seconds (the nearest
// one). Relations whose poses are missing are not used (see `used`).
RelationErrors evaluateRelations(const std::vector<Relation>& relations,
                                 const std::vector<StampedPose>& trajectory,
                                 double stamp_tolerance = 1e-4);

// The errors split by how far apart the two poses of a relation are in
// time: short relations measure the local accuracy (the front end), long
// ones whether revisits agree (loop closure). Bin k holds the relations
// with span in [edges[k], edges[k + 1]); the last bin is open above.
struct SpanBin {
  double from = 0.0, to = 0.0;  // s; `to` is infinity for the last bin
  int relations = 0;
  double translation_mean = 0.0;   // m
  double rotation_mean = 0.0;      // rad
  double translation_share = 0.0;  // of the sum of all translational errors
};
std::vector<SpanBin> errorsBySpan(const RelationErrors& errors, const std::vector<double>& edges);

}  // namespace ekf_slam
