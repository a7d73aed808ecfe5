#include "ekf_slam_core/io/grid_map_file.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

#include "ekf_slam_core/io/atomic_file.h"
#include "ekf_slam_core/io/yaml_fields.h"

namespace ekf_slam {
namespace {

using io_yaml::describe;
using io_yaml::lineOf;

bool finiteNumber(const YAML::Node& node, double* value) {
  return io_yaml::scalarNumber(node, value) && std::isfinite(*value);
}

std::string directoryOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

// map_server's reading of a pixel as an occupancy probability, inverted:
// the pixel that reads back as `value`.
uint8_t pixelFor(int8_t value) {
  if (value < 0) return 205;   // unknown
  if (value == 0) return 254;  // free, as map_saver writes it
  if (value >= 100) return 0;  // occupied
  return static_cast<uint8_t>(std::lround(255.0 * (1.0 - value / 100.0)));
}

// The next header token of a PGM (whitespace and # comments skipped).
bool pgmToken(const std::string& bytes, size_t* at, std::string* token) {
  while (*at < bytes.size()) {
    const char c = bytes[*at];
    if (c == '#') {
      while (*at < bytes.size() && bytes[*at] != '\n') ++*at;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++*at;
    } else {
      break;
    }
  }
  const size_t start = *at;
  while (*at < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[*at]))) ++*at;
  *token = bytes.substr(start, *at - start);
  return !token->empty();
}

bool parseCount(const std::string& token, long* value) {
  if (token.empty() || token.size() > 9) return false;
  for (char c : token) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  }
  *value = std::atol(token.c_str());
  return true;
}

}  // namespace

std::string imagePathFor(const std::string& yaml_path) {
  const std::string suffix = ".yaml";
  if (yaml_path.size() > suffix.size() &&
      yaml_path.compare(yaml_path.size() - suffix.size(), suffix.size(), suffix) == 0) {
    return yaml_path.substr(0, yaml_path.size() - suffix.size()) + ".pgm";
  }
  return yaml_path + ".pgm";
}

std::string formatGridMap(const std::string& yaml_path, const GridMapFile& grid,
                          std::vector<FileSetEntry>* files) {
  const long cells = static_cast<long>(grid.width) * grid.height;
  if (grid.width <= 0 || grid.height <= 0 || cells > kMaxGridCells ||
      static_cast<long>(grid.cells.size()) != cells) {
    return yaml_path + ": the grid is " + std::to_string(grid.width) + " x " +
           std::to_string(grid.height) + " cells with " + std::to_string(grid.cells.size()) +
           " values; nothing written";
  }
  if (!(grid.resolution > 0.0) || !std::isfinite(grid.resolution) ||
      !std::isfinite(grid.origin_x) || !std::isfinite(grid.origin_y) ||
      !std::isfinite(grid.origin_yaw)) {
    return yaml_path + ": the grid's resolution or origin is not finite; nothing written";
  }
  const std::string image_path = imagePathFor(yaml_path);
  std::string image = "P5\n# ekf_slam occupancy grid\n" + std::to_string(grid.width) + " " +
                      std::to_string(grid.height) + "\n255\n";
  const size_t header = image.size();
  image.resize(header + static_cast<size_t>(cells));
  // The image's first row is the top of the map (largest y).
  for (int row = 0; row < grid.height; ++row) {
    const size_t from = static_cast<size_t>(grid.height - 1 - row) * grid.width;
    for (int col = 0; col < grid.width; ++col) {
      image[header + static_cast<size_t>(row) * grid.width + col] =
          static_cast<char>(pixelFor(grid.cells[from + col]));
    }
  }
  const size_t slash = image_path.find_last_of('/');
  const std::string image_name =
      slash == std::string::npos ? image_path : image_path.substr(slash + 1);
  char numbers[256];
  std::snprintf(numbers, sizeof(numbers),
                "resolution: %.17g\norigin: [%.17g, %.17g, %.17g]\nnegate: 0\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\n",
                grid.resolution, grid.origin_x, grid.origin_y, grid.origin_yaw);
  files->push_back({image_path, std::move(image)});
  files->push_back({yaml_path, "image: " + io_yaml::scalarText(image_name) + "\n" + numbers});
  return "";
}

std::string writeGridMap(const std::string& yaml_path, const GridMapFile& grid) {
  std::vector<FileSetEntry> files;
  const std::string error = formatGridMap(yaml_path, grid, &files);
  return error.empty() ? writeFileSet(journalFor(yaml_path), files) : error;
}

namespace {

// What readGridMap takes from the YAML file, map_server's defaults where a
// key may be left out.
struct MapServerKeys {
  std::string image;
  double resolution = 0.0;  // 0: not given
  bool have_origin = false;
  double origin[3] = {0.0, 0.0, 0.0};
  double negate = 0.0, occupied = 0.65, free_below = 0.196;
};

// The keys of the YAML file's tree; an empty string or the problem, with
// in `line` the 1-based line where the value at fault starts (0: the file
// as a whole).
std::string readKeys(const YAML::Node& root, MapServerKeys* keys, int* line) {
  auto fail = [line](const YAML::Node& node, const std::string& problem) {
    *line = lineOf(node);
    return problem;
  };
  if (!root.IsNull() && !root.IsMap()) {
    return fail(
        root, "expected map_server's keys (image, resolution, origin, ...), got " + describe(root));
  }
  std::set<std::string> seen;
  for (const auto& pair : root) {
    const YAML::Node &key_node = pair.first, &value = pair.second;
    if (!key_node.IsScalar()) continue;  // not one of map_server's keys
    const std::string& key = key_node.Scalar();
    if (!seen.insert(key).second) return fail(key_node, "key '" + key + "' given twice");
    if (key == "image") {
      if (!value.IsNull() && !value.IsScalar()) {
        return fail(value, "image must be a file name, got " + describe(value));
      }
      keys->image = value.Scalar();
    } else if (key == "resolution") {
      if (!finiteNumber(value, &keys->resolution) || !(keys->resolution > 0.0)) {
        return fail(value,
                    "resolution must be a positive number (m per cell), got " + describe(value));
      }
    } else if (key == "origin") {
      if (!value.IsSequence() || value.size() != 3 || !finiteNumber(value[0], &keys->origin[0]) ||
          !finiteNumber(value[1], &keys->origin[1]) || !finiteNumber(value[2], &keys->origin[2])) {
        return fail(value,
                    "origin must be [x, y, yaw], three finite numbers, got " + describe(value));
      }
      keys->have_origin = true;
    } else if (key == "negate") {
      if (!finiteNumber(value, &keys->negate) || (keys->negate != 0.0 && keys->negate != 1.0)) {
        return fail(value, "negate must be 0 or 1, got " + describe(value));
      }
    } else if (key == "occupied_thresh") {
      if (!finiteNumber(value, &keys->occupied)) {
        return fail(value, "occupied_thresh must be a number, got " + describe(value));
      }
    } else if (key == "free_thresh") {
      if (!finiteNumber(value, &keys->free_below)) {
        return fail(value, "free_thresh must be a number, got " + describe(value));
      }
    } else if (key == "mode") {
      if (!value.IsScalar() || value.Scalar() != "trinary") {
        return fail(value, "mode " + describe(value) + ": only trinary maps are read (-1, 0, 100)");
      }
    }  // other keys (for example map_server's own additions) are not needed
  }
  if (keys->image.empty()) return "no 'image'";
  if (!(keys->resolution > 0.0)) return "no 'resolution'";
  if (!keys->have_origin) return "no 'origin'";
  if (!(keys->free_below >= 0.0 && keys->free_below < keys->occupied && keys->occupied <= 1.0)) {
    return "thresholds must satisfy 0 <= free_thresh < occupied_thresh <= 1";
  }
  return "";
}

}  // namespace

std::string readGridMap(const std::string& yaml_path, GridMapFile* grid) {
  std::string text;
  if (!readWholeFile(yaml_path, &text)) return yaml_path + ": cannot open";
  YAML::Node root;
  int line = 0;
  std::string problem = io_yaml::loadDocument(text, &root, &line);
  MapServerKeys keys;
  if (problem.empty()) {
    try {
      problem = readKeys(root, &keys, &line);
    } catch (const YAML::Exception& e) {  // not expected: readKeys asks only what nodes hold
      line = e.mark.is_null() ? 0 : e.mark.line + 1;
      problem = e.msg;
    }
  }
  if (!problem.empty()) {
    return yaml_path + (line > 0 ? ":" + std::to_string(line) : "") + ": " + problem;
  }

  const std::string& image = keys.image;
  const std::string image_path = image.front() == '/' ? image : directoryOf(yaml_path) + image;
  std::string bytes;
  if (!readWholeFile(image_path, &bytes)) {
    return yaml_path + ": cannot open its image " + image_path;
  }
  size_t at = 0;
  std::string magic, w, h, maxval;
  long width = 0, height = 0, max_value = 0;
  if (!pgmToken(bytes, &at, &magic) || magic != "P5") {
    return image_path + ": not a binary PGM image (P5)";
  }
  if (!pgmToken(bytes, &at, &w) || !pgmToken(bytes, &at, &h) || !pgmToken(bytes, &at, &maxval) ||
      !parseCount(w, &width) || !parseCount(h, &height) || !parseCount(maxval, &max_value)) {
    return image_path + ": PGM header is not 'P5 width height maxval'";
  }
  if (width <= 0 || height <= 0 || width * height > kMaxGridCells) {
    return image_path + ": " + w + " x " + h + " cells (at most " + std::to_string(kMaxGridCells) +
           " are read)";
  }
  if (max_value < 1 || max_value > 255) {
    return image_path + ": maxval " + maxval + " (8-bit images only)";
  }
  ++at;  // the single whitespace after maxval
  const long cells = width * height;
  if (at > bytes.size() || static_cast<long>(bytes.size() - at) < cells) {
    return image_path + ": " + std::to_string(bytes.size() < at ? 0 : bytes.size() - at) +
           " bytes of pixels, " + std::to_string(cells) + " expected (the file is cut short)";
  }
  GridMapFile result;
  result.resolution = keys.resolution;
  result.origin_x = keys.origin[0];
  result.origin_y = keys.origin[1];
  result.origin_yaw = keys.origin[2];
  result.width = static_cast<int>(width);
  result.height = static_cast<int>(height);
  result.cells.resize(static_cast<size_t>(cells));
  for (long row = 0; row < height; ++row) {
    const size_t to = static_cast<size_t>(height - 1 - row) * width;
    for (long col = 0; col < width; ++col) {
      const double pixel = static_cast<unsigned char>(bytes[at + row * width + col]);
      const double occupancy =
          keys.negate != 0.0 ? pixel / max_value : (max_value - pixel) / max_value;
      result.cells[to + col] = occupancy > keys.occupied     ? 100
                               : occupancy < keys.free_below ? 0
                                                             : -1;
    }
  }
  *grid = std::move(result);
  return "";
}

}  // namespace ekf_slam
