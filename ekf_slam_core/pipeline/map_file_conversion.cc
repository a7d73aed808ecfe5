#include "ekf_slam_core/pipeline/map_file_conversion.h"

namespace ekf_slam {
namespace {

bool isPoint(const EkfSlam& filter, int id) {
  const int slot = filter.slotOf(id);
  return slot >= 0 && filter.landmarkKind(slot) == LandmarkKind::kPoint;
}

}  // namespace

LandmarkMapFile toLandmarkMapFile(const EkfSlam& filter,
                                  const std::unordered_map<int, LineSupport>& support,
                                  const std::string& frame) {
  LandmarkMapFile out;
  out.frame = frame;
  for (int s = 0; s < filter.landmarkCount(); ++s) {
    const LandmarkInfo& info = filter.landmarks()[s];
    const auto seen = support.find(info.id);
    switch (info.kind) {
      case LandmarkKind::kPoint: {
        LandmarkRecord r;
        r.id = info.id;
        r.position = filter.landmarkPosition(s);
        r.covariance = filter.landmarkCovariance(s);
        r.observations = info.observations;
        out.landmarks.push_back(r);
        break;
      }
      case LandmarkKind::kLine: {
        LineLandmarkRecord r;
        r.id = info.id;
        const PolarLine line = filter.lineLandmark(s);
        r.p = line.p;
        r.theta = line.theta;
        r.covariance = filter.landmarkCovariance(s);
        r.observations = info.observations;
        if (seen != support.end()) {
          r.has_extent = true;
          r.s_min = seen->second.s_min;
          r.s_max = seen->second.s_max;
        }
        out.lines.push_back(r);
        break;
      }
      case LandmarkKind::kLineAngle: {
        LineAngleRecord r;
        r.id = info.id;
        r.theta = filter.lineAngle(s);
        r.variance = filter.lineAngleVariance(s);
        r.observations = info.observations;
        if (seen != support.end()) {
          for (int k = 0; k < 2; ++k) {
            const int endpoint = seen->second.endpoint_ids[k];
            r.endpoint_ids[k] = isPoint(filter, endpoint) ? endpoint : -1;
          }
        }
        out.line_angles.push_back(r);
        break;
      }
    }
  }
  return out;
}

int seedFilter(const LandmarkMapFile& map, EkfSlam* filter,
               std::unordered_map<int, LineSupport>* support) {
  int refused = 0;
  for (const LandmarkRecord& r : map.landmarks) {
    if (filter->addLandmark(r.id, r.position, r.covariance, r.observations) != FilterStatus::kOk) {
      ++refused;
    }
  }
  for (const LineLandmarkRecord& r : map.lines) {
    if (filter->addLineLandmark(r.id, PolarLine{r.p, r.theta}, r.covariance, r.observations) !=
        FilterStatus::kOk) {
      ++refused;
      continue;
    }
    if (support && r.has_extent) {
      LineSupport& s = (*support)[r.id];
      s.s_min = r.s_min;
      s.s_max = r.s_max;
    }
  }
  for (const LineAngleRecord& r : map.line_angles) {
    if (filter->addLineAngleLandmark(r.id, r.theta, r.variance, r.observations) !=
        FilterStatus::kOk) {
      ++refused;
      continue;
    }
    if (!support) continue;
    LineSupport& s = (*support)[r.id];
    for (int k = 0; k < 2; ++k) {
      s.endpoint_ids[k] = isPoint(*filter, r.endpoint_ids[k]) ? r.endpoint_ids[k] : -1;
    }
  }
  return refused;
}

}  // namespace ekf_slam
