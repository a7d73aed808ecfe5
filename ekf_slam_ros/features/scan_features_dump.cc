// scan_features_dump BAG INDEX [TOPIC]
// Extracts features from scan number INDEX (0-based, file order) of a bag
// with the default FeatureOptions and prints them as plain text for
// tools/analysis/plot_scan_features.py. All coordinates in the laser frame (m, rad):
//   scan <index> <stamp> <beams> <valid>
//   point <beam> <x> <y> <cluster>
//   line <p> <theta> <x0> <y0> <x1> <y1> <var_p> <cov_p_theta> <var_theta>
//   feature <corner|end> <context> <landmark 0|1> <x> <y> <var_x> <cov_xy> <var_y>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_ros/features/bag_scans.h"

namespace {

const char* contextName(ekf_slam::EndpointContext context) {
  switch (context) {
    case ekf_slam::EndpointContext::kCorner:
      return "corner";
    case ekf_slam::EndpointContext::kFrontEdge:
      return "front_edge";
    case ekf_slam::EndpointContext::kOccluded:
      return "occluded";
    case ekf_slam::EndpointContext::kNoReturn:
      return "no_return";
    case ekf_slam::EndpointContext::kScanBoundary:
      return "scan_boundary";
    case ekf_slam::EndpointContext::kUnresolved:
      return "unresolved";
  }
  return "unknown";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s BAG INDEX [TOPIC=/scan]\n", argv[0]);
    return 2;
  }
  const std::string bag = argv[1];
  char* end = nullptr;
  const long wanted = std::strtol(argv[2], &end, 10);
  if (*end != '\0' || wanted < 0) {
    std::fprintf(stderr, "INDEX must be a non-negative integer, got '%s'\n", argv[2]);
    return 2;
  }
  const std::string topic = argc > 3 ? argv[3] : "/scan";
  bool found = false;
  try {
    ekf_slam::ros_conversions::forEachBagScan(
        bag, topic, [&](int index, const ekf_slam::Scan& scan) {
          if (index < wanted) return true;
          found = true;
          const ekf_slam::FeatureSet set =
              ekf_slam::extractFeatures(scan, ekf_slam::FeatureOptions());
          if (!set.error.empty()) {
            std::fprintf(stderr, "scan %d rejected: %s\n", index, set.error.c_str());
            return false;
          }
          std::printf("scan %d %.6f %d %zu\n", index, scan.stamp, scan.size(), set.points.size());
          for (size_t c = 0; c < set.clusters.size(); ++c) {
            for (int i = set.clusters[c].first; i <= set.clusters[c].last; ++i) {
              const ekf_slam::ScanPoint& p = set.points[i];
              std::printf("point %d %.4f %.4f %zu\n", p.beam, p.xy.x(), p.xy.y(), c);
            }
          }
          for (const ekf_slam::LineFeature& l : set.lines) {
            std::printf("line %.5f %.5f %.4f %.4f %.4f %.4f %.3e %.3e %.3e\n", l.p, l.theta,
                        l.start.x(), l.start.y(), l.end.x(), l.end.y(), l.covariance(0, 0),
                        l.covariance(0, 1), l.covariance(1, 1));
          }
          for (const ekf_slam::PointFeature& f : set.points_of_interest) {
            std::printf("feature %s %s %d %.4f %.4f %.3e %.3e %.3e\n",
                        f.kind == ekf_slam::PointKind::kCorner ? "corner" : "end",
                        contextName(f.context), f.landmark_candidate ? 1 : 0, f.position.x(),
                        f.position.y(), f.covariance(0, 0), f.covariance(0, 1), f.covariance(1, 1));
          }
          return false;
        });
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cannot read %s: %s\n", bag.c_str(), e.what());
    return 1;
  }
  if (!found) {
    std::fprintf(stderr, "%s has no scan %ld on %s\n", bag.c_str(), wanted, topic.c_str());
    return 1;
  }
  return 0;
}
