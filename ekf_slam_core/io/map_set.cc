#include "ekf_slam_core/io/map_set.h"

#include <vector>

#include "ekf_slam_core/io/file_set.h"

namespace ekf_slam {

MapSetPaths mapSetPaths(const std::string& landmark_path) {
  const std::string suffix = ".yaml";
  const bool yaml =
      landmark_path.size() > suffix.size() &&
      landmark_path.compare(landmark_path.size() - suffix.size(), suffix.size(), suffix) == 0;
  MapSetPaths paths;
  paths.landmarks = landmark_path;
  paths.grid =
      (yaml ? landmark_path.substr(0, landmark_path.size() - suffix.size()) : landmark_path) +
      "_grid.yaml";
  paths.image = imagePathFor(paths.grid);
  return paths;
}

std::string writeMapSet(const std::string& landmark_path, const LandmarkMapFile& landmarks,
                        const std::optional<GridMapFile>& grid) {
  const MapSetPaths paths = mapSetPaths(landmark_path);
  std::vector<FileSetEntry> files;
  if (grid) {
    const std::string error = formatGridMap(paths.grid, *grid, &files);
    if (!error.empty()) return error;
  } else {
    files.push_back({paths.image, std::nullopt});
    files.push_back({paths.grid, std::nullopt});
  }
  // The landmark file last: the set's main file.
  files.push_back({paths.landmarks, formatLandmarkMap(landmarks)});
  return writeFileSet(journalFor(paths.landmarks), files);
}

std::string finishInterruptedMapSave(const std::string& landmark_path) {
  const MapSetPaths paths = mapSetPaths(landmark_path);
  return finishInterruptedSave(journalFor(paths.landmarks),
                               {paths.image, paths.grid, paths.landmarks});
}

}  // namespace ekf_slam
