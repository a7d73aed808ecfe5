#include "ekf_slam_core/filter/slam_iteration.h"

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {

IterationReport runIteration(EkfSlam& filter, const AssociationOptions& association,
                             const Pose2& odom_previous, const Pose2& odom_current, double dt,
                             const std::vector<PointObservation>& observations) {
  IterationReport report;
  report.predict_status = filter.predict(odom_previous, odom_current, dt);
  if (report.predict_status != FilterStatus::kOk) return report;
  observe(filter, association, observations, &report);
  return report;
}

void observe(EkfSlam& filter, const AssociationOptions& association,
             const std::vector<PointObservation>& observations, IterationReport* out,
             const Associator& associator) {
  IterationReport& report = *out;
  report.association = associator ? associator(filter, observations, association)
                                  : associate(filter, observations, association);
  report.matches = report.association.matches();
  report.update_status = filter.update(observations, report.matches, &report.nis);
  if (report.update_status != FilterStatus::kOk) {
    report.matches.clear();
    report.nis.clear();
  }
  // Augment after the update so new landmarks hang off the corrected pose.
  for (int i : report.association.newLandmarks()) {
    int id = -1;
    if (filter.augment(observations[i], &id) == FilterStatus::kOk) {
      report.new_landmark_ids.push_back(id);
      report.created.push_back({i, id});
    } else {
      ++report.augment_failures;
    }
  }
  report.pruned = filter.pruneTentative();
  if (association.merge_probability > 0.0) {
    std::vector<int> touched = report.new_landmark_ids;
    for (const PointMatch& m : report.matches) touched.push_back(m.landmark_id);
    report.merged =
        filter.mergeDuplicates(touched, chiSquareQuantile(association.merge_probability, 2.0),
                               association.merge_distance, association.merge_bias_sigma);
  }
}

}  // namespace ekf_slam
